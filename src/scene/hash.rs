//! A content hash that stays the same across Rust releases, platforms and runs (std's
//! `DefaultHasher` promises none of that), for files that record what they were made from.

/// FNV-1a's step (xor, then multiply by the 64-bit FNV prime) over 32-bit little-endian words,
/// ended by splitmix64's finalizer so every input bit reaches every output bit. Each step is a
/// bijection of the state, so one changed word always changes the hash. Not cryptographic.
#[derive(Clone, Copy, Debug)]
pub struct ContentHasher(u64);

impl Default for ContentHasher {
    fn default() -> Self {
        Self::new()
    }
}

impl ContentHasher {
    const OFFSET: u64 = 0xcbf2_9ce4_8422_2325;
    const PRIME: u64 = 0x0000_0100_0000_01b3;

    /// A hasher at FNV's offset basis.
    pub fn new() -> Self {
        Self(Self::OFFSET)
    }

    /// Adds one word.
    pub fn u32(&mut self, v: u32) {
        self.0 = (self.0 ^ v as u64).wrapping_mul(Self::PRIME);
    }

    /// Adds a 64-bit value (low word first).
    pub fn u64(&mut self, v: u64) {
        self.u32(v as u32);
        self.u32((v >> 32) as u32);
    }

    /// Adds a length or count.
    pub fn len(&mut self, n: usize) {
        self.u64(n as u64);
    }

    /// Adds a flag.
    pub fn bool(&mut self, v: bool) {
        self.u32(v as u32);
    }

    /// Adds floats by their bits (so −0 and 0 differ, and a NaN is whatever its bits are).
    pub fn f32s(&mut self, v: &[f32]) {
        for x in v {
            self.u32(x.to_bits());
        }
    }

    /// Adds words.
    pub fn u32s(&mut self, v: &[u32]) {
        for &x in v {
            self.u32(x);
        }
    }

    /// Adds bytes, length first, in little-endian words (the last one padded with zeros).
    pub fn bytes(&mut self, v: &[u8]) {
        self.len(v.len());
        let mut words = v.chunks_exact(4);
        for w in &mut words {
            self.u32(u32::from_le_bytes([w[0], w[1], w[2], w[3]]));
        }
        let tail = words.remainder();
        if !tail.is_empty() {
            let mut w = [0u8; 4];
            w[..tail.len()].copy_from_slice(tail);
            self.u32(u32::from_le_bytes(w));
        }
    }

    /// Adds a string's UTF-8 bytes, length first.
    pub fn str(&mut self, s: &str) {
        self.bytes(s.as_bytes());
    }

    /// The hash of everything added.
    pub fn finish(&self) -> u64 {
        // splitmix64's finalizer.
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        z ^ (z >> 31)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The hash is a pure function of its input, pinned to values computed once (by an independent Python transcription): a change of
    /// algorithm (which would orphan every file recording a hash) fails here first.
    #[test]
    fn the_hash_is_pinned() {
        assert_eq!(ContentHasher::new().finish(), 0xf52a_15e9_a9b5_e89b);
        let mut h = ContentHasher::new();
        h.str("umbra");
        h.f32s(&[1.0, -0.0]);
        h.u64(u64::MAX);
        assert_eq!(h.finish(), 0xc555_8e4e_98e9_6e5b);
    }

    #[test]
    fn lengths_separate_fields() {
        let hash = |parts: &[&[u8]]| {
            let mut h = ContentHasher::new();
            parts.iter().for_each(|p| h.bytes(p));
            h.finish()
        };
        assert_ne!(hash(&[b"ab", b"c"]), hash(&[b"a", b"bc"]));
        assert_ne!(hash(&[b"a"]), hash(&[b"a\0"]));
    }
}
