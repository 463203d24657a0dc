//! Values built once per key, at their first use, then shared: a pass's pipelines keyed by the
//! value that specialises them (a kernel's `Spec`, the path tracer's
//! [`crate::passes::pathtrace::PathOptions`]). A new specialization constant is a new field of
//! the key, with no slot count or index formula to keep in step with it.

use std::hash::Hash;
use std::sync::OnceLock;

/// A map from keys to values built on first use; [`Cache::get_or_try_init`] takes `&self`, so
/// threads share one cache (pipelines are made on several at once).
pub struct Cache<K, V> {
    /// Each value in a box of its own: the map may move its entries as it grows, a box's
    /// contents never move, so a reference handed out stays valid while the cache lives.
    cells: elsa::sync::FrozenMap<K, Box<OnceLock<V>>>,
}

impl<K, V> Default for Cache<K, V> {
    fn default() -> Self {
        Self { cells: elsa::sync::FrozenMap::new() }
    }
}

impl<K: Eq + Hash, V> Cache<K, V> {
    /// An empty cache.
    pub fn new() -> Self {
        Self::default()
    }

    /// The value for `key`, built by `build` if none is yet. An error is returned and nothing
    /// kept, so a later call tries again. Two threads that ask for a new key at once may both
    /// build it: the first value stored is kept and returned to both, the other dropped.
    pub fn get_or_try_init<E>(&self, key: K, build: impl FnOnce() -> Result<V, E>) -> Result<&V, E> {
        let cell = match self.cells.get(&key) {
            Some(cell) => cell,
            None => self.cells.insert_with(key, || Box::new(OnceLock::new())),
        };
        if let Some(value) = cell.get() {
            return Ok(value);
        }
        let value = build()?;
        Ok(cell.get_or_init(|| value))
    }

    /// [`Cache::get_or_try_init`] for a build that cannot fail.
    pub fn get_or_init(&self, key: K, build: impl FnOnce() -> V) -> &V {
        self.get_or_try_init(key, || Ok::<V, std::convert::Infallible>(build()))
            .unwrap_or_else(|e| match e {})
    }
}

#[cfg(test)]
mod tests {
    use super::Cache;
    use std::sync::atomic::{AtomicUsize, Ordering};

    /// Equal keys share one value, built once; different keys (one field apart) get their own;
    /// a failed build keeps nothing, so the next call builds again.
    #[test]
    fn one_value_per_key_built_once() {
        let builds = AtomicUsize::new(0);
        let cache: Cache<(bool, u32), String> = Cache::new();
        let build = |key: (bool, u32)| {
            builds.fetch_add(1, Ordering::Relaxed);
            Ok::<_, ()>(format!("{key:?}"))
        };
        let a = cache.get_or_try_init((false, 1), || build((false, 1))).unwrap();
        let b = cache.get_or_try_init((true, 1), || build((true, 1))).unwrap();
        let c = cache.get_or_try_init((false, 2), || build((false, 2))).unwrap();
        assert_eq!((a.as_str(), b.as_str(), c.as_str()), ("(false, 1)", "(true, 1)", "(false, 2)"));
        let again = cache.get_or_try_init((false, 1), || build((false, 1))).unwrap();
        assert!(std::ptr::eq(a, again), "an equal key built a second value");
        assert_eq!(builds.load(Ordering::Relaxed), 3);

        assert_eq!(cache.get_or_try_init((true, 7), || Err(())), Err(()));
        let later = cache.get_or_try_init((true, 7), || build((true, 7))).unwrap();
        assert_eq!(later, "(true, 7)");
        assert_eq!(builds.load(Ordering::Relaxed), 4);
    }

    /// References stay valid while the map grows past many reallocations, and threads asking
    /// for the same keys at once all see the one value kept.
    #[test]
    fn references_survive_growth_and_threads_agree() {
        let cache: Cache<u32, Box<u32>> = Cache::new();
        let first = cache.get_or_init(0, || Box::new(0));
        for k in 1..4096 {
            cache.get_or_init(k, || Box::new(k));
        }
        assert_eq!(**first, 0);
        let seen: Vec<Vec<usize>> = std::thread::scope(|s| {
            let handles: Vec<_> = (0..4)
                .map(|_| {
                    s.spawn(|| {
                        (4096..4160u32)
                            .map(|k| &**cache.get_or_init(k, || Box::new(k)) as *const u32 as usize)
                            .collect()
                    })
                })
                .collect();
            handles.into_iter().map(|h| h.join().unwrap()).collect()
        });
        assert!(seen.windows(2).all(|w| w[0] == w[1]), "threads saw different values for one key");
    }
}
