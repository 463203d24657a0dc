//! The frame graph: passes that declare the images they read and write, recorded in one go.
//!
//! A pass is added with its name, its reads and writes of the graph's images, and a closure
//! that records it ([`Graph::add_pass`]). [`Graph::execute`] then:
//! - checks the order: a transient image is read only after an earlier pass wrote it;
//! - culls the passes whose writes nothing uses (no imported image, no transient read by a
//!   live pass; a pass that declares no write is kept: its effects lie outside the graph);
//! - allocates the transient images from a [`TransientPool`], one physical image serving
//!   several transients whose lifetimes do not overlap, and the same images from frame to
//!   frame;
//! - records the live passes in order through one [`Recorder`], which derives every barrier,
//!   each pass timed under its name when a timer is given, and refuses a pass that touches a
//!   graph image it did not declare (or writes one it declared read).
//!
//! Images are imported (a host's or umbra's, kept) or transient (made by the graph, contents
//! undefined at the start of each execution). Buffers stay outside the graph: the recorder
//! orders them all the same.

use super::{Context, GpuTimer, Image, Recorder, Resource, Use};
use crate::error::{Error, Result};
use ash::vk;
use std::cell::Cell;
use std::collections::HashMap;
use std::sync::Mutex;

/// An image of a [`Graph`], imported or transient.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct GraphImage(usize);

/// What a transient image is: every pass that shares one must agree on it.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct ImageDesc {
    /// Width and height.
    pub size: (u32, u32),
    /// Its format (a storage image, `GENERAL` layout while recorded).
    pub format: vk::Format,
}

#[derive(Debug, Clone)]
enum Slot {
    Imported(vk::ImageView),
    Transient(ImageDesc),
}

/// The record closure of one pass: the recorder, and the views of the graph's images.
type RecordFn<'g> = Box<dyn FnOnce(&mut Recorder<'_>, &GraphViews) -> Result<()> + 'g>;

struct Node<'g> {
    name: String,
    reads: Vec<GraphImage>,
    writes: Vec<GraphImage>,
    record: RecordFn<'g>,
}

/// Passes and the images they read and write, recorded by [`Graph::execute`].
#[derive(Default)]
pub struct Graph<'g> {
    names: Vec<String>,
    slots: Vec<Slot>,
    nodes: Vec<Node<'g>>,
}

/// A pass being declared ([`Graph::add_pass`]); [`PassBuilder::record`] adds it.
pub struct PassBuilder<'a, 'g> {
    graph: &'a mut Graph<'g>,
    name: String,
    reads: Vec<GraphImage>,
    writes: Vec<GraphImage>,
}

impl<'g> PassBuilder<'_, 'g> {
    /// The pass reads `image`.
    pub fn read(mut self, image: GraphImage) -> Self {
        self.reads.push(image);
        self
    }

    /// The pass reads every image of `images`.
    pub fn read_all(mut self, images: impl IntoIterator<Item = GraphImage>) -> Self {
        self.reads.extend(images);
        self
    }

    /// The pass writes `image` (and may read it).
    pub fn write(mut self, image: GraphImage) -> Self {
        self.writes.push(image);
        self
    }

    /// The pass writes every image of `images` (and may read them).
    pub fn write_all(mut self, images: impl IntoIterator<Item = GraphImage>) -> Self {
        self.writes.extend(images);
        self
    }

    /// Adds the pass, recorded by `record` with the views of the graph's images: its
    /// operations go through the recorder (umbra's kernels, or [`Recorder::access`] before a
    /// command of the caller's own).
    pub fn record(self, record: impl FnOnce(&mut Recorder<'_>, &GraphViews) -> Result<()> + 'g) {
        let PassBuilder { graph, name, reads, writes } = self;
        graph.nodes.push(Node { name, reads, writes, record: Box::new(record) });
    }

    /// Adds a pass of the caller's own commands, which the recorder does not see: recorded by
    /// `record` into the command buffer once the recorder has ordered it by its declared reads
    /// and writes (as kernel reads and writes; the caller keeps to them).
    pub fn record_raw(self, record: impl FnOnce(vk::CommandBuffer, &GraphViews) -> Result<()> + 'g) {
        let uses: Vec<(GraphImage, Use)> = (self.reads.iter().map(|&i| (i, Use::ComputeRead)))
            .chain(self.writes.iter().map(|&i| (i, Use::ComputeWrite)))
            .collect();
        self.record(move |rec, views| {
            let uses: Vec<(Resource, Use)> =
                uses.iter().map(|&(i, u)| (Resource::Image(views[i]), u)).collect();
            rec.access(&uses);
            record(rec.cmd(), views)
        })
    }
}

/// The views of a graph's images while one of its passes records: those the pass declared (an
/// undeclared one is a null view, and the graph refuses the pass after it records).
#[derive(Debug)]
pub struct GraphViews {
    views: Vec<vk::ImageView>,
    declared: Vec<bool>,
    /// The first undeclared image the pass asked for.
    undeclared: Cell<Option<usize>>,
}

impl std::ops::Index<GraphImage> for GraphViews {
    type Output = vk::ImageView;

    fn index(&self, image: GraphImage) -> &vk::ImageView {
        const NULL: vk::ImageView = vk::ImageView::null();
        match self.declared.get(image.0) {
            Some(true) => &self.views[image.0],
            _ => {
                if self.undeclared.get().is_none() {
                    self.undeclared.set(Some(image.0));
                }
                &NULL
            }
        }
    }
}

/// What one execution recorded.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct GraphStats {
    /// The passes recorded, in order.
    pub recorded: Vec<String>,
    /// The passes culled (nothing used what they write).
    pub culled: Vec<String>,
    /// Transient images used.
    pub transients: usize,
    /// Physical images that held the transients.
    pub physical: usize,
}

impl<'g> Graph<'g> {
    /// An empty graph.
    pub fn new() -> Self {
        Self::default()
    }

    /// An image the caller owns (a host's, or one it reads back), in `GENERAL` layout: kept
    /// after the graph, so a pass that writes it is never culled.
    pub fn import(&mut self, name: &str, view: vk::ImageView) -> GraphImage {
        self.slot(name, Slot::Imported(view))
    }

    /// An image made for this execution (from the pool): undefined until a pass writes it,
    /// dropped after the last pass that reads it.
    pub fn transient(&mut self, name: &str, desc: ImageDesc) -> GraphImage {
        self.slot(name, Slot::Transient(desc))
    }

    fn slot(&mut self, name: &str, slot: Slot) -> GraphImage {
        self.names.push(name.to_owned());
        self.slots.push(slot);
        GraphImage(self.slots.len() - 1)
    }

    /// Declares a pass: its reads and writes, then [`PassBuilder::record`].
    pub fn add_pass(&mut self, name: &str) -> PassBuilder<'_, 'g> {
        PassBuilder { graph: self, name: name.to_owned(), reads: Vec::new(), writes: Vec::new() }
    }

    /// Orders, culls and allocates (see the module's documentation), then records the live
    /// passes into `rec`, timing each under its name with `timer` when given.
    pub fn execute(
        self,
        rec: &mut Recorder<'_>,
        pool: &TransientPool,
        mut timer: Option<&mut GpuTimer>,
    ) -> Result<GraphStats> {
        let metas: Vec<PassMeta> = self
            .nodes
            .iter()
            .map(|n| PassMeta {
                reads: n.reads.iter().map(|i| i.0).collect(),
                writes: n.writes.iter().map(|i| i.0).collect(),
            })
            .collect();
        let kinds: Vec<Option<ImageDesc>> = self
            .slots
            .iter()
            .map(|s| match s {
                Slot::Imported(_) => None,
                Slot::Transient(desc) => Some(*desc),
            })
            .collect();
        let plan = plan(&kinds, &metas).map_err(|(pass, image, what)| {
            let image = image.map_or("", |i| self.names[i].as_str());
            Error::Invalid(format!("frame graph: pass '{}' {what}{image}", self.nodes[pass].name))
        })?;
        let ctx = rec.ctx();
        let mut physical = pool.take(ctx, &plan.physical)?;
        let views: Vec<vk::ImageView> = self
            .slots
            .iter()
            .enumerate()
            .map(|(i, s)| match (s, plan.physical_of[i]) {
                (Slot::Imported(view), _) => *view,
                (Slot::Transient(_), Some(p)) => physical[p].view,
                (Slot::Transient(_), None) => vk::ImageView::null(),
            })
            .collect();
        // The graph's images by resource, for each pass's contract (moved in and back out).
        let mut managed: HashMap<Resource, String> = (0..self.slots.len())
            .filter(|&i| views[i] != vk::ImageView::null())
            .map(|i| (Resource::Image(views[i]), self.names[i].clone()))
            .collect();
        for image in &physical {
            rec.discard(image);
        }
        let mut stats = GraphStats {
            transients: plan.physical_of.iter().flatten().count(),
            physical: physical.len(),
            ..GraphStats::default()
        };
        let result = (|| {
            for (node, live) in self.nodes.into_iter().zip(&plan.live) {
                if !live {
                    stats.culled.push(node.name);
                    continue;
                }
                let mut declared: HashMap<Resource, bool> = HashMap::new();
                let mut pass_views = GraphViews {
                    views: views.clone(),
                    declared: vec![false; views.len()],
                    undeclared: Cell::new(None),
                };
                let uses = node.reads.iter().map(|i| (i, false)).chain(node.writes.iter().map(|i| (i, true)));
                for (image, writes) in uses {
                    pass_views.declared[image.0] = true;
                    *declared.entry(Resource::Image(views[image.0])).or_default() |= writes;
                }
                if let Some(t) = timer.as_deref_mut() {
                    t.begin(rec.cmd(), &node.name)?;
                }
                rec.contract =
                    Some(Contract { managed: std::mem::take(&mut managed), declared, broken: None });
                let recorded = (node.record)(rec, &pass_views);
                let contract = rec.contract.take().expect("the pass's contract");
                managed = contract.managed;
                let mut broken = contract.broken;
                if let Some(i) = pass_views.undeclared.get() {
                    broken = Some(format!("uses the image '{}' it did not declare", self.names[i]));
                }
                if let Some(broken) = broken {
                    return Err(Error::Invalid(format!("frame graph: pass '{}' {broken}", node.name)));
                }
                recorded?;
                if let Some(t) = timer.as_deref_mut() {
                    t.end(rec.cmd())?;
                }
                stats.recorded.push(node.name);
            }
            Ok(())
        })();
        pool.give_back(&mut physical);
        result.map(|()| stats)
    }
}

/// What a pass declared, by image index.
#[derive(Debug, Clone, Default)]
struct PassMeta {
    reads: Vec<usize>,
    writes: Vec<usize>,
}

/// The outcome of [`plan`].
#[derive(Debug, Clone, PartialEq)]
struct Plan {
    /// Per pass: recorded (true) or culled.
    live: Vec<bool>,
    /// Per image: the physical image holding a transient a live pass uses.
    physical_of: Vec<Option<usize>>,
    /// The physical images.
    physical: Vec<ImageDesc>,
}

/// Plans an execution over images (`None`: imported; `Some`: a transient of that description)
/// and passes, in their order: an error `(pass, image, what)` for an image read before any write
/// or one of another graph.
fn plan(
    images: &[Option<ImageDesc>],
    passes: &[PassMeta],
) -> std::result::Result<Plan, (usize, Option<usize>, &'static str)> {
    let mut written = vec![false; images.len()];
    for (p, pass) in passes.iter().enumerate() {
        if pass.reads.iter().chain(&pass.writes).any(|&i| i >= images.len()) {
            return Err((p, None, "names an image of another graph"));
        }
        if let Some(&i) = pass.reads.iter().find(|&&i| images[i].is_some() && !written[i]) {
            return Err((p, Some(i), "reads, before any pass writes it, the transient image "));
        }
        for &i in &pass.writes {
            written[i] = true;
        }
    }
    // Backwards: a pass lives when it declares no write, writes an imported image or writes a
    // transient that a later live pass reads. (A write may read too, so an earlier writer of
    // the same image is kept alive as well.)
    let mut needed = vec![false; images.len()];
    let mut live = vec![false; passes.len()];
    for (p, pass) in passes.iter().enumerate().rev() {
        live[p] = pass.writes.is_empty() || pass.writes.iter().any(|&i| images[i].is_none() || needed[i]);
        if live[p] {
            for &i in &pass.reads {
                needed[i] = true;
            }
        }
    }
    // Lifetimes of the transients, over live passes.
    let mut span: Vec<Option<(usize, usize)>> = vec![None; images.len()];
    for (p, pass) in passes.iter().enumerate().filter(|(p, _)| live[*p]) {
        for &i in pass.reads.iter().chain(&pass.writes) {
            if images[i].is_some() {
                let s = span[i].get_or_insert((p, p));
                s.1 = p;
            }
        }
    }
    // Greedy, in order of first use: a physical image of the same description free since before
    // this transient's first pass, or a new one.
    let mut order: Vec<usize> = (0..images.len()).filter(|&i| span[i].is_some()).collect();
    order.sort_by_key(|&i| span[i].map(|s| s.0));
    let mut physical: Vec<ImageDesc> = Vec::new();
    let mut busy_until: Vec<usize> = Vec::new();
    let mut physical_of = vec![None; images.len()];
    for i in order {
        let (Some(desc), Some((first, last))) = (images[i], span[i]) else { continue };
        let free = (0..physical.len()).find(|&j| physical[j] == desc && busy_until[j] < first);
        let j = free.unwrap_or_else(|| {
            physical.push(desc);
            busy_until.push(0);
            physical.len() - 1
        });
        busy_until[j] = last;
        physical_of[i] = Some(j);
    }
    Ok(Plan { live, physical_of, physical })
}

/// The graph's rule for one pass, checked by the [`Recorder`] at each operation: the graph's
/// images it may touch, and how.
#[derive(Debug)]
pub(super) struct Contract {
    /// Every image of the graph, by resource, and its name.
    pub(super) managed: HashMap<Resource, String>,
    /// The pass's declared images: true where it may write.
    pub(super) declared: HashMap<Resource, bool>,
    /// The first breach found.
    pub(super) broken: Option<String>,
}

impl Contract {
    /// Notes the first breach by an operation with `uses`; returns it, if any so far.
    pub(super) fn check_all(&mut self, uses: &[(Resource, Use)]) -> Option<&String> {
        for &(resource, how) in uses {
            self.check(resource, how.writes());
        }
        self.broken.as_ref()
    }

    /// Notes a breach by an operation using `resource`, writing it or not.
    fn check(&mut self, resource: Resource, writes: bool) {
        if self.broken.is_some() {
            return;
        }
        let Some(name) = self.managed.get(&resource) else { return };
        match self.declared.get(&resource) {
            None => self.broken = Some(format!("uses the image '{name}' it did not declare")),
            Some(false) if writes => {
                self.broken = Some(format!("writes the image '{name}' it declared read"))
            }
            _ => {}
        }
    }
}

/// Transient images kept from one graph execution to the next (storage images, freed with the
/// pool). Each execution starts them afresh (contents undefined), after the work recorded
/// before it on the queue.
#[derive(Default)]
pub struct TransientPool {
    free: Mutex<Vec<Image>>,
}

impl TransientPool {
    /// An empty pool.
    pub fn new() -> Self {
        Self::default()
    }

    /// Images of `descs`, in order: the pool's where it has one, else new.
    fn take(&self, ctx: &Context, descs: &[ImageDesc]) -> Result<Vec<Image>> {
        let mut free = self.free.lock().unwrap_or_else(|e| e.into_inner());
        let mut out = Vec::with_capacity(descs.len());
        for desc in descs {
            let found = free
                .iter()
                .position(|i| i.format == desc.format && (i.extent.width, i.extent.height) == desc.size);
            out.push(match found {
                Some(k) => free.swap_remove(k),
                None => Image::storage_2d(ctx, "transient", desc.size.0, desc.size.1, desc.format)?,
            });
        }
        Ok(out)
    }

    fn give_back(&self, images: &mut Vec<Image>) {
        self.free.lock().unwrap_or_else(|e| e.into_inner()).append(images);
    }

    /// The images the pool holds while no graph executes.
    pub fn len(&self) -> usize {
        self.free.lock().unwrap_or_else(|e| e.into_inner()).len()
    }

    /// Whether it holds none.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const A: ImageDesc = ImageDesc { size: (4, 4), format: vk::Format::R32_SFLOAT };
    const B: ImageDesc = ImageDesc { size: (4, 4), format: vk::Format::R32G32B32A32_SFLOAT };

    fn pass(reads: &[usize], writes: &[usize]) -> PassMeta {
        PassMeta { reads: reads.to_vec(), writes: writes.to_vec() }
    }

    #[test]
    fn passes_whose_writes_nothing_uses_are_culled() {
        // 0: imported output; 1, 2: transients.
        let images = [None, Some(A), Some(A)];
        let passes = [
            pass(&[], &[1]),  // feeds pass 2: live
            pass(&[], &[2]),  // nothing reads 2: culled
            pass(&[1], &[0]), // writes the output: live
            pass(&[0], &[]),  // declares no write: kept
        ];
        let plan = plan(&images, &passes).unwrap();
        assert_eq!(plan.live, [true, false, true, true]);
        assert_eq!(plan.physical_of, [None, Some(0), None], "a culled pass's transient is not made");
        assert_eq!(plan.physical, [A]);
    }

    #[test]
    fn transients_share_an_image_only_when_their_lifetimes_do_not_overlap() {
        // 1 → 2 → 3 → out, each a transient of A; 4 a transient of B.
        let images = [None, Some(A), Some(A), Some(A), Some(B)];
        let passes = [pass(&[], &[1]), pass(&[1], &[2, 4]), pass(&[2, 4], &[3]), pass(&[3], &[0])];
        let plan = plan(&images, &passes).unwrap();
        // 1 lives over passes 0-1, 2 over 1-2, 3 over 2-3: 1 and 3 share, 2 needs its own.
        assert_eq!(plan.physical_of, [None, Some(0), Some(1), Some(0), Some(2)]);
        assert_eq!(plan.physical, [A, A, B]);
    }

    #[test]
    fn a_transient_read_before_it_is_written_is_refused() {
        let images = [None, Some(A)];
        let err = plan(&images, &[pass(&[1], &[0]), pass(&[], &[1])]).unwrap_err();
        assert_eq!((err.0, err.1), (0, Some(1)));
        // An imported image may be read first: the caller wrote it.
        assert!(plan(&images, &[pass(&[0], &[1]), pass(&[1], &[0])]).is_ok());
    }

    #[test]
    fn the_contract_names_undeclared_and_misdeclared_images() {
        use ash::vk::Handle;
        let [a, b, c] = [1, 2, 3].map(|n| Resource::Image(vk::ImageView::from_raw(n)));
        let mut contract = Contract {
            managed: [(a, "ao".to_string()), (b, "hdr".to_string())].into(),
            declared: [(a, false)].into(),
            broken: None,
        };
        contract.check(c, true); // not the graph's: the contract does not look
        contract.check(a, false);
        assert_eq!(contract.broken, None);
        contract.check(a, true);
        assert_eq!(contract.broken.as_deref(), Some("writes the image 'ao' it declared read"));
        contract.broken = None;
        contract.check(b, false);
        assert_eq!(contract.broken.as_deref(), Some("uses the image 'hdr' it did not declare"));
    }
}
