//! Per-subresource resource state tracking for the frame graph.
//!
//! Given the sequence of accesses the graph's passes make to an image or a
//! buffer, this module derives the synchronization2 barriers (and image layout
//! transitions) that must precede each access. It is pure bookkeeping: no
//! device, no `unsafe`; `ash::vk` is used for its flag and enum types only.
//!
//! # The model
//!
//! Every image subresource (mip, layer) — and every buffer, as a whole — keeps:
//!
//! * its current layout (images only);
//! * the **last write**: the stages it ran in and the write accesses it made.
//!   A layout transition is a write too; it has no access of its own to make
//!   available (the spec makes a transition's writes available automatically),
//!   so it is recorded as the destination stages of the barrier that performed
//!   it, with access NONE — later barriers reach it by execution-dependency
//!   chaining through those stages;
//! * the **readers** since that write (union of their stages): a later write or
//!   layout transition must wait for them (write-after-read);
//! * the **visibility set** since that write: the (stages × accesses) pairs the
//!   write has already been made visible to by an earlier barrier. A reader
//!   inside that set needs no barrier; any other reader does, even when the
//!   layout is unchanged and other reads already happened.
//!
//! # Rules (per subresource; `N` is the next access)
//!
//! * layout differs from `N`'s (or first use): a transition. It reads and writes
//!   the whole subresource, so it must wait for the last write (made available)
//!   *and* for every reader since: `src = (write ∪ readers stages, write access)`,
//!   `dst = N`. A fresh image has neither, hence `src = NONE/NONE`.
//! * `N` writes, same layout, readers since the last write: write-after-read
//!   needs only an execution dependency on those readers (`src = readers/NONE`).
//!   The readers' own barriers already made the last write available, and this
//!   barrier's destination access makes it visible to `N`'s read part, if any.
//! * `N` writes, same layout, no readers: write-after-write, `src = last write`.
//! * `N` reads, same layout: read-after-write needs `src = last write,
//!   dst = N` unless `N` is already in the visibility set.
//! * Nothing written and nothing to wait for: no barrier.
//!
//! Barriers carry `N`'s full stage and access masks as destination (including the
//! read half of read-modify-write accesses such as colour attachments with
//! `LOAD_OP_LOAD` or storage images used with `imageLoad` + `imageStore`).
//!
//! # Conservative choices
//!
//! Coverage is tested bit by bit on the stage masks as given: meta stages
//! (`ALL_GRAPHICS`, `ALL_COMMANDS`) and the expansion of stages to logically
//! earlier/later ones are *not* taken into account. That can only cause extra
//! barriers, never missing ones. Prefer precise stage bits in [`Access`].

use ash::vk;

type Stages = vk::PipelineStageFlags2;
type AccessMask = vk::AccessFlags2;

// ---------------------------------------------------------------------------
// Subresource ranges
// ---------------------------------------------------------------------------

pub use crate::backend::SubresourceRange;

// ---------------------------------------------------------------------------
// Accesses
// ---------------------------------------------------------------------------

/// How a pass uses a resource: a stage mask, an access mask, an image layout
/// (ignored for buffers) and whether it writes.
///
/// A pass that uses one subresource in two ways at once must declare a single
/// access covering both (e.g. [`Access::Custom`] with the union of the masks
/// and a layout valid for both).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Access {
    /// Sampled image / uniform texel buffer read. `SHADER_READ_ONLY_OPTIMAL`.
    SampledRead { stages: Stages },
    /// Storage image / storage buffer read only. `GENERAL`.
    StorageRead { stages: Stages },
    /// Storage image / storage buffer write, including read-modify-write
    /// (`imageLoad` + `imageStore`, atomics): the destination access holds
    /// `SHADER_STORAGE_READ` as well, so the previous contents are visible to the
    /// shader. `GENERAL`.
    StorageWrite { stages: Stages },
    /// Uniform buffer read.
    UniformRead { stages: Stages },
    /// Colour attachment, written and (load op LOAD, blending) read.
    /// Also covers MSAA resolve targets under dynamic rendering.
    /// `COLOR_ATTACHMENT_OPTIMAL`.
    ColorAttachmentWrite,
    /// Depth/stencil attachment with depth/stencil writes (and tests).
    /// `DEPTH_STENCIL_ATTACHMENT_OPTIMAL`.
    DepthStencilAttachmentWrite,
    /// Depth/stencil attachment, tests only. `DEPTH_STENCIL_READ_ONLY_OPTIMAL`.
    DepthStencilAttachmentRead,
    /// Sampling a depth/stencil image while keeping it in
    /// `DEPTH_STENCIL_READ_ONLY_OPTIMAL`, so that it can be alternated with
    /// [`Access::DepthStencilAttachmentRead`] without layout transitions.
    DepthSampledRead { stages: Stages },
    /// Copy/blit/resolve source. `TRANSFER_SRC_OPTIMAL`.
    TransferRead,
    /// Copy/blit/clear destination. `TRANSFER_DST_OPTIMAL`.
    TransferWrite,
    /// Host readback after the GPU wrote (buffers). Stage `HOST`, `HOST_READ`.
    /// The executor still waits for a fence before reading on the CPU.
    HostRead,
    /// Hand-off to the presentation engine: `PRESENT_SRC_KHR`, stage and access
    /// NONE. Terminal: after it, the image belongs to the presentation engine
    /// until re-acquired (build a new state with [`ImageState::external`]).
    Present,
    /// Vertex buffer.
    VertexRead,
    /// Index buffer.
    IndexRead,
    /// Indirect draw/dispatch arguments.
    IndirectRead,
    /// Anything else. `access` may mix read and write bits; `write` says whether
    /// the subresource's contents change.
    Custom {
        stages: Stages,
        access: AccessMask,
        layout: vk::ImageLayout,
        write: bool,
    },
}

/// Every write bit of `AccessFlags2`; the rest are reads.
const WRITE_ACCESS: AccessMask = AccessMask::from_raw(
    AccessMask::SHADER_WRITE.as_raw()
        | AccessMask::SHADER_STORAGE_WRITE.as_raw()
        | AccessMask::COLOR_ATTACHMENT_WRITE.as_raw()
        | AccessMask::DEPTH_STENCIL_ATTACHMENT_WRITE.as_raw()
        | AccessMask::TRANSFER_WRITE.as_raw()
        | AccessMask::HOST_WRITE.as_raw()
        | AccessMask::MEMORY_WRITE.as_raw()
        | AccessMask::TRANSFORM_FEEDBACK_WRITE_EXT.as_raw()
        | AccessMask::TRANSFORM_FEEDBACK_COUNTER_WRITE_EXT.as_raw()
        | AccessMask::COMMAND_PREPROCESS_WRITE_NV.as_raw()
        | AccessMask::ACCELERATION_STRUCTURE_WRITE_KHR.as_raw()
        | AccessMask::VIDEO_DECODE_WRITE_KHR.as_raw()
        | AccessMask::VIDEO_ENCODE_WRITE_KHR.as_raw()
        | AccessMask::MICROMAP_WRITE_EXT.as_raw()
        | AccessMask::OPTICAL_FLOW_WRITE_NV.as_raw(),
);

const FRAGMENT_TESTS: Stages =
    Stages::from_raw(Stages::EARLY_FRAGMENT_TESTS.as_raw() | Stages::LATE_FRAGMENT_TESTS.as_raw());

impl Access {
    pub fn stages(&self) -> Stages {
        match *self {
            Access::SampledRead { stages }
            | Access::StorageRead { stages }
            | Access::StorageWrite { stages }
            | Access::UniformRead { stages }
            | Access::DepthSampledRead { stages }
            | Access::Custom { stages, .. } => stages,
            Access::ColorAttachmentWrite => Stages::COLOR_ATTACHMENT_OUTPUT,
            Access::DepthStencilAttachmentWrite | Access::DepthStencilAttachmentRead => FRAGMENT_TESTS,
            Access::TransferRead | Access::TransferWrite => Stages::ALL_TRANSFER,
            Access::HostRead => Stages::HOST,
            Access::Present => Stages::NONE,
            Access::VertexRead => Stages::VERTEX_ATTRIBUTE_INPUT,
            Access::IndexRead => Stages::INDEX_INPUT,
            Access::IndirectRead => Stages::DRAW_INDIRECT,
        }
    }

    pub fn access(&self) -> AccessMask {
        match *self {
            Access::SampledRead { .. } | Access::DepthSampledRead { .. } => AccessMask::SHADER_SAMPLED_READ,
            Access::StorageRead { .. } => AccessMask::SHADER_STORAGE_READ,
            Access::StorageWrite { .. } => AccessMask::SHADER_STORAGE_READ | AccessMask::SHADER_STORAGE_WRITE,
            Access::UniformRead { .. } => AccessMask::UNIFORM_READ,
            Access::ColorAttachmentWrite => AccessMask::COLOR_ATTACHMENT_READ | AccessMask::COLOR_ATTACHMENT_WRITE,
            Access::DepthStencilAttachmentWrite => {
                AccessMask::DEPTH_STENCIL_ATTACHMENT_READ | AccessMask::DEPTH_STENCIL_ATTACHMENT_WRITE
            }
            Access::DepthStencilAttachmentRead => AccessMask::DEPTH_STENCIL_ATTACHMENT_READ,
            Access::TransferRead => AccessMask::TRANSFER_READ,
            Access::TransferWrite => AccessMask::TRANSFER_WRITE,
            Access::HostRead => AccessMask::HOST_READ,
            Access::Present => AccessMask::NONE,
            Access::VertexRead => AccessMask::VERTEX_ATTRIBUTE_READ,
            Access::IndexRead => AccessMask::INDEX_READ,
            Access::IndirectRead => AccessMask::INDIRECT_COMMAND_READ,
            Access::Custom { access, .. } => access,
        }
    }

    /// The image layout this access needs. Buffer-only accesses answer
    /// `UNDEFINED`; using one on an image panics.
    pub fn layout(&self) -> vk::ImageLayout {
        match *self {
            Access::SampledRead { .. } => vk::ImageLayout::SHADER_READ_ONLY_OPTIMAL,
            Access::StorageRead { .. } | Access::StorageWrite { .. } | Access::HostRead => vk::ImageLayout::GENERAL,
            Access::ColorAttachmentWrite => vk::ImageLayout::COLOR_ATTACHMENT_OPTIMAL,
            Access::DepthStencilAttachmentWrite => vk::ImageLayout::DEPTH_STENCIL_ATTACHMENT_OPTIMAL,
            Access::DepthStencilAttachmentRead | Access::DepthSampledRead { .. } => {
                vk::ImageLayout::DEPTH_STENCIL_READ_ONLY_OPTIMAL
            }
            Access::TransferRead => vk::ImageLayout::TRANSFER_SRC_OPTIMAL,
            Access::TransferWrite => vk::ImageLayout::TRANSFER_DST_OPTIMAL,
            Access::Present => vk::ImageLayout::PRESENT_SRC_KHR,
            Access::UniformRead { .. } | Access::VertexRead | Access::IndexRead | Access::IndirectRead => {
                vk::ImageLayout::UNDEFINED
            }
            Access::Custom { layout, .. } => layout,
        }
    }

    pub fn is_write(&self) -> bool {
        match *self {
            Access::StorageWrite { .. }
            | Access::ColorAttachmentWrite
            | Access::DepthStencilAttachmentWrite
            | Access::TransferWrite => true,
            Access::Custom { write, .. } => write,
            _ => false,
        }
    }
}

// ---------------------------------------------------------------------------
// Barriers
// ---------------------------------------------------------------------------

/// One image memory barrier, over `range` of the image it was derived for.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct ImageBarrier {
    pub range: SubresourceRange,
    pub src_stages: Stages,
    pub src_access: AccessMask,
    pub dst_stages: Stages,
    pub dst_access: AccessMask,
    pub old_layout: vk::ImageLayout,
    pub new_layout: vk::ImageLayout,
}

impl ImageBarrier {
    /// The sync2 struct, with no queue family ownership transfer.
    pub fn to_vk(&self, image: vk::Image, aspect: vk::ImageAspectFlags) -> vk::ImageMemoryBarrier2<'static> {
        vk::ImageMemoryBarrier2::default()
            .src_stage_mask(self.src_stages)
            .src_access_mask(self.src_access)
            .dst_stage_mask(self.dst_stages)
            .dst_access_mask(self.dst_access)
            .old_layout(self.old_layout)
            .new_layout(self.new_layout)
            .src_queue_family_index(vk::QUEUE_FAMILY_IGNORED)
            .dst_queue_family_index(vk::QUEUE_FAMILY_IGNORED)
            .image(image)
            .subresource_range(self.range.to_vk(aspect))
    }
}

/// A whole-buffer memory dependency.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct BufferBarrier {
    pub src_stages: Stages,
    pub src_access: AccessMask,
    pub dst_stages: Stages,
    pub dst_access: AccessMask,
}

impl BufferBarrier {
    /// As a buffer memory barrier over the whole buffer.
    pub fn to_vk(&self, buffer: vk::Buffer) -> vk::BufferMemoryBarrier2<'static> {
        vk::BufferMemoryBarrier2::default()
            .src_stage_mask(self.src_stages)
            .src_access_mask(self.src_access)
            .dst_stage_mask(self.dst_stages)
            .dst_access_mask(self.dst_access)
            .src_queue_family_index(vk::QUEUE_FAMILY_IGNORED)
            .dst_queue_family_index(vk::QUEUE_FAMILY_IGNORED)
            .buffer(buffer)
            .offset(0)
            .size(vk::WHOLE_SIZE)
    }
    /// As a global memory barrier (equivalent for a whole buffer, and several
    /// of them can be OR-ed into one).
    pub fn to_memory_barrier(&self) -> vk::MemoryBarrier2<'static> {
        vk::MemoryBarrier2::default()
            .src_stage_mask(self.src_stages)
            .src_access_mask(self.src_access)
            .dst_stage_mask(self.dst_stages)
            .dst_access_mask(self.dst_access)
    }
}

/// A barrier without its range: what one subresource needs.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
struct Sync {
    src_stages: Stages,
    src_access: AccessMask,
    dst_stages: Stages,
    dst_access: AccessMask,
    old_layout: vk::ImageLayout,
    new_layout: vk::ImageLayout,
}

// ---------------------------------------------------------------------------
// Per-subresource state machine (shared by images and buffers)
// ---------------------------------------------------------------------------

#[derive(Clone, Debug, PartialEq, Eq)]
struct SubState {
    layout: vk::ImageLayout,
    /// Stages of the last write, or of the barrier that performed the last
    /// layout transition (what later barriers chain through).
    write_stages: Stages,
    /// Write bits of the last write; NONE for a layout transition.
    write_access: AccessMask,
    /// Stages that read since the last write.
    read_stages: Stages,
    /// (stages, accesses) pairs the last write has been made visible to. Each
    /// pair means "every stage in .0 × every access in .1"; pairs are kept
    /// separate because a union of stages and a union of accesses would claim
    /// combinations no barrier covered.
    visible: Vec<(Stages, AccessMask)>,
}

/// Whether the pairs make the last write visible to every `stages × access`.
fn covers(visible: &[(Stages, AccessMask)], stages: Stages, access: AccessMask) -> bool {
    let mut bits = stages.as_raw();
    while bits != 0 {
        let bit = Stages::from_raw(bits & bits.wrapping_neg());
        bits &= bits - 1;
        let reached = visible
            .iter()
            // ALL_COMMANDS reaches every stage (an imported image declared visible to all).
            .filter(|(s, _)| s.contains(bit) || s.contains(Stages::ALL_COMMANDS))
            .fold(AccessMask::NONE, |acc, (_, a)| acc | *a);
        if !reached.contains(access) {
            return false;
        }
    }
    true
}

fn add_visible(visible: &mut Vec<(Stages, AccessMask)>, stages: Stages, access: AccessMask) {
    if covers(visible, stages, access) {
        return;
    }
    // Merging only pairs sharing a side keeps the set exact.
    if let Some(e) = visible.iter_mut().find(|e| e.1 == access) {
        e.0 |= stages;
    } else if let Some(e) = visible.iter_mut().find(|e| e.0 == stages) {
        e.1 |= access;
    } else {
        visible.push((stages, access));
    }
}

impl SubState {
    fn fresh() -> Self {
        SubState {
            layout: vk::ImageLayout::UNDEFINED,
            write_stages: Stages::NONE,
            write_access: AccessMask::NONE,
            read_stages: Stages::NONE,
            visible: Vec::new(),
        }
    }

    /// As if `initial` had just been performed, after a barrier that made all
    /// earlier work visible to it.
    fn settled(initial: Access, has_layout: bool) -> Self {
        let mut s = SubState::fresh();
        if has_layout {
            s.layout = initial.layout();
        }
        s.write_stages = initial.stages();
        s.visible.push((initial.stages(), initial.access()));
        s.record(initial);
        s
    }

    fn external(layout: vk::ImageLayout, stages: Stages, access: AccessMask) -> Self {
        SubState {
            layout,
            write_stages: stages,
            write_access: access & WRITE_ACCESS,
            ..SubState::fresh()
        }
    }

    fn has_write(&self) -> bool {
        !self.write_stages.is_empty() || !self.write_access.is_empty()
    }

    /// The barrier this subresource needs before `next`, and the state after it.
    fn step(&mut self, next: Access, discard: bool, has_layout: bool) -> Option<Sync> {
        let (stages, access) = (next.stages(), next.access());
        let new_layout = if has_layout { next.layout() } else { self.layout };
        let sync = |src_stages, src_access, old_layout| Sync {
            src_stages,
            src_access,
            dst_stages: stages,
            dst_access: access,
            old_layout,
            new_layout,
        };

        let barrier = if new_layout != self.layout {
            // The transition rewrites the memory: it must come after the last
            // write (made available: it must not race with a late cache flush)
            // and after every reader (or it would clobber what they read).
            // Discarding only relaxes what the transition has to preserve.
            let old = if discard {
                vk::ImageLayout::UNDEFINED
            } else {
                self.layout
            };
            let b = sync(self.write_stages | self.read_stages, self.write_access, old);
            // The transition is now the last write: automatically available,
            // visible to `next` only, reachable through `next`'s stages.
            self.layout = new_layout;
            self.write_stages = stages;
            self.write_access = AccessMask::NONE;
            self.read_stages = Stages::NONE;
            self.visible.clear();
            self.visible.push((stages, access));
            Some(b)
        } else if next.is_write() {
            if !self.read_stages.is_empty() {
                // WAR: the readers' barriers already made the last write
                // available, so only ordering after them is missing.
                Some(sync(self.read_stages, AccessMask::NONE, self.layout))
            } else if self.has_write() {
                // WAW: order and make the previous write available, so that the
                // two cannot land in memory in the wrong order.
                Some(sync(self.write_stages, self.write_access, self.layout))
            } else {
                None
            }
        } else if self.has_write() && !covers(&self.visible, stages, access) {
            // RAW, or a new kind of reader of an already-visible write: the
            // earlier barrier's visibility operation did not include it.
            add_visible(&mut self.visible, stages, access);
            Some(sync(self.write_stages, self.write_access, self.layout))
        } else {
            None
        };
        self.record(next);
        barrier
    }

    /// The effect of performing `next` itself (after its barrier).
    fn record(&mut self, next: Access) {
        if next.is_write() {
            self.write_stages = next.stages();
            self.write_access = next.access() & WRITE_ACCESS;
            self.read_stages = Stages::NONE;
            self.visible.clear();
        } else if !next.access().is_empty() {
            // A "read" that touches no memory (access NONE) is no hazard for a
            // later write; counting it would also let a WAR barrier chain
            // through a stage that never waited for the last write.
            self.read_stages |= next.stages();
        }
    }
}

// ---------------------------------------------------------------------------
// Images
// ---------------------------------------------------------------------------

/// State of one image, per (mip, layer).
#[derive(Clone, Debug)]
pub struct ImageState {
    mip_count: u32,
    layer_count: u32,
    /// Indexed `mip * layer_count + layer`.
    subs: Vec<SubState>,
}

impl ImageState {
    /// A new image: every subresource `UNDEFINED`, nothing pending. The first
    /// barrier of each subresource has `src = NONE/NONE`, so this is only
    /// right for an image no earlier work can still be touching (freshly
    /// created and bound to fresh memory). For a swapchain image, or one
    /// aliasing memory another resource used, use [`Self::external`].
    ///
    /// Reading a subresource that was never written is allowed (it transitions
    /// from `UNDEFINED` and reads garbage); avoiding it is the graph's business.
    pub fn new(mip_count: u32, layer_count: u32) -> Self {
        Self::from_sub(mip_count, layer_count, SubState::fresh())
    }

    /// An image whose every subresource was last used by `initial` (e.g. left
    /// so by an earlier frame, on the same queue), after a barrier that made
    /// all earlier work visible to that use. Prefer keeping the `ImageState`
    /// alive across frames, which needs no such assumption.
    pub fn with_initial(mip_count: u32, layer_count: u32, initial: Access) -> Self {
        Self::from_sub(mip_count, layer_count, SubState::settled(initial, true))
    }

    /// An image whose contents (in `layout`) were produced by work outside the
    /// graph that the queue waits for at `stages` — typically a swapchain image:
    /// `external(1, 1, UNDEFINED, COLOR_ATTACHMENT_OUTPUT, NONE)` when the acquire
    /// semaphore is waited at `COLOR_ATTACHMENT_OUTPUT`. The first barrier then
    /// has `src_stages = stages`, which chains it after the semaphore wait so
    /// that its layout transition cannot happen before the image is released.
    pub fn external(
        mip_count: u32,
        layer_count: u32,
        layout: vk::ImageLayout,
        stages: Stages,
        access: AccessMask,
    ) -> Self {
        Self::from_sub(mip_count, layer_count, SubState::external(layout, stages, access))
    }

    fn from_sub(mip_count: u32, layer_count: u32, sub: SubState) -> Self {
        assert!(mip_count > 0 && layer_count > 0, "image with no subresource");
        let n = mip_count as usize * layer_count as usize;
        ImageState {
            mip_count,
            layer_count,
            subs: vec![sub; n],
        }
    }

    /// What anything that follows all the work recorded so far on this image
    /// must wait for: the stages of every subresource's last write and of its
    /// readers since, and the write accesses to make available. For memory
    /// aliasing, start the next image on the same memory as
    /// `external(mips, layers, UNDEFINED, stages, access)` with these.
    pub fn pending(&self) -> (Stages, AccessMask) {
        self.subs.iter().fold((Stages::NONE, AccessMask::NONE), |(s, a), sub| {
            (s | sub.write_stages | sub.read_stages, a | sub.write_access)
        })
    }

    pub fn mip_count(&self) -> u32 {
        self.mip_count
    }
    pub fn layer_count(&self) -> u32 {
        self.layer_count
    }

    /// Current layout of one subresource.
    pub fn layout(&self, mip: u32, layer: u32) -> vk::ImageLayout {
        self.subs[self.index(mip, layer)].layout
    }

    /// Record that the next use of `range` is `next`; return the barriers that
    /// must precede it, all to be issued together in one dependency. Adjacent
    /// subresources needing identical barriers are merged into rectangles.
    pub fn transition(&mut self, range: SubresourceRange, next: Access) -> Vec<ImageBarrier> {
        self.transition_impl(range, next, false)
    }

    /// Like [`Self::transition`], but the previous contents of `range` are not
    /// needed: a layout change is made from `UNDEFINED` (cheaper, may lose the
    /// contents). It still waits for earlier readers and writers, since the
    /// transition and `next` must not race with them. Where no layout change is
    /// needed it is exactly `transition`.
    pub fn transition_discard(&mut self, range: SubresourceRange, next: Access) -> Vec<ImageBarrier> {
        self.transition_impl(range, next, true)
    }

    fn index(&self, mip: u32, layer: u32) -> usize {
        assert!(
            mip < self.mip_count && layer < self.layer_count,
            "subresource (mip {mip}, layer {layer}) outside a {}x{} image",
            self.mip_count,
            self.layer_count
        );
        mip as usize * self.layer_count as usize + layer as usize
    }

    /// `range` with REMAINING counts made explicit; panics when out of bounds.
    pub fn resolve(&self, range: SubresourceRange) -> SubresourceRange {
        let rest = |base: u32, count: u32, total: u32, remaining: u32, what: &str| {
            assert!(base < total, "{what} {base} outside an image with {total}");
            let count = if count == remaining { total - base } else { count };
            assert!(
                count > 0 && count <= total - base,
                "{what} range {base}+{count} outside an image with {total}"
            );
            count
        };
        SubresourceRange {
            mip_count: rest(
                range.base_mip,
                range.mip_count,
                self.mip_count,
                vk::REMAINING_MIP_LEVELS,
                "mip",
            ),
            layer_count: rest(
                range.base_layer,
                range.layer_count,
                self.layer_count,
                vk::REMAINING_ARRAY_LAYERS,
                "layer",
            ),
            ..range
        }
    }

    fn transition_impl(&mut self, range: SubresourceRange, next: Access, discard: bool) -> Vec<ImageBarrier> {
        assert!(
            next.layout() != vk::ImageLayout::UNDEFINED,
            "{next:?} has no image layout (buffer-only access used on an image)"
        );
        let r = self.resolve(range);
        let mut grid = Vec::with_capacity(r.mip_count as usize * r.layer_count as usize);
        for mip in r.base_mip..r.base_mip + r.mip_count {
            for layer in r.base_layer..r.base_layer + r.layer_count {
                let i = self.index(mip, layer);
                grid.push(self.subs[i].step(next, discard, true));
            }
        }
        merge(r, &grid)
    }
}

/// Cover the cells of `grid` (mip-major over `r`) that need a barrier with as
/// few rectangles of identical barriers as a greedy sweep finds, trying both
/// sweep directions (runs along layers grown over mips, and the transpose).
/// That is optimal for the shapes a renderer produces: uniform ranges, whole
/// mips, whole layers, and a block inside a uniform surround.
fn merge(r: SubresourceRange, grid: &[Option<Sync>]) -> Vec<ImageBarrier> {
    let (mips, layers) = (r.mip_count as usize, r.layer_count as usize);
    let by_mip = sweep(mips, layers, |m, l| grid[m * layers + l]);
    let by_layer = sweep(layers, mips, |l, m| grid[m * layers + l]);
    let mut out: Vec<ImageBarrier> = if by_layer.len() < by_mip.len() {
        by_layer
            .into_iter()
            .map(|(l0, ln, m0, mn, s)| barrier(r, m0, mn, l0, ln, s))
            .collect()
    } else {
        by_mip
            .into_iter()
            .map(|(m0, mn, l0, ln, s)| barrier(r, m0, mn, l0, ln, s))
            .collect()
    };
    out.sort_by_key(|b| (b.range.base_mip, b.range.base_layer));
    out
}

fn barrier(r: SubresourceRange, m0: usize, mn: usize, l0: usize, ln: usize, s: Sync) -> ImageBarrier {
    ImageBarrier {
        range: SubresourceRange::new(r.base_mip + m0 as u32, mn as u32, r.base_layer + l0 as u32, ln as u32),
        src_stages: s.src_stages,
        src_access: s.src_access,
        dst_stages: s.dst_stages,
        dst_access: s.dst_access,
        old_layout: s.old_layout,
        new_layout: s.new_layout,
    }
}

/// Greedy rectangles over a rows × cols grid: take the first uncovered cell,
/// extend along its row, then down the rows while the whole run matches.
/// Returns (row, rows, col, cols, barrier).
fn sweep(
    rows: usize,
    cols: usize,
    at: impl Fn(usize, usize) -> Option<Sync>,
) -> Vec<(usize, usize, usize, usize, Sync)> {
    let mut used = vec![false; rows * cols];
    let mut out = Vec::new();
    for r in 0..rows {
        for c in 0..cols {
            let Some(s) = at(r, c) else { continue };
            if used[r * cols + c] {
                continue;
            }
            let same = |rr: usize, cc: usize, used: &[bool]| !used[rr * cols + cc] && at(rr, cc) == Some(s);
            let mut c_end = c + 1;
            while c_end < cols && same(r, c_end, &used) {
                c_end += 1;
            }
            let mut r_end = r + 1;
            while r_end < rows && (c..c_end).all(|cc| same(r_end, cc, &used)) {
                r_end += 1;
            }
            for rr in r..r_end {
                used[rr * cols + c..rr * cols + c_end].fill(true);
            }
            out.push((r, r_end - r, c, c_end - c, s));
        }
    }
    out
}

// ---------------------------------------------------------------------------
// Buffers
// ---------------------------------------------------------------------------

/// State of one buffer, tracked as a whole.
#[derive(Clone, Debug)]
pub struct BufferState {
    sub: SubState,
}

impl Default for BufferState {
    fn default() -> Self {
        Self::new()
    }
}

impl BufferState {
    /// A buffer no GPU work has touched yet. Host writes made before the
    /// submission are visible to it without a barrier (queue submission makes
    /// them so), hence the first access needs none.
    pub fn new() -> Self {
        BufferState { sub: SubState::fresh() }
    }

    /// A buffer last used by `initial`, after a barrier that made all earlier
    /// work visible to it. See [`ImageState::with_initial`].
    pub fn with_initial(initial: Access) -> Self {
        BufferState {
            sub: SubState::settled(initial, false),
        }
    }

    /// A buffer whose contents were produced outside the graph by work the
    /// queue waits for at `stages` (see [`ImageState::external`]), or which
    /// aliases memory last used as described by another state's `pending()`.
    pub fn external(stages: Stages, access: AccessMask) -> Self {
        BufferState {
            sub: SubState::external(vk::ImageLayout::UNDEFINED, stages, access),
        }
    }

    /// See [`ImageState::pending`].
    pub fn pending(&self) -> (Stages, AccessMask) {
        (self.sub.write_stages | self.sub.read_stages, self.sub.write_access)
    }

    /// Record that the next use is `next`; return the barrier that must
    /// precede it, if any.
    pub fn transition(&mut self, next: Access) -> Option<BufferBarrier> {
        self.sub.step(next, false, false).map(|s| BufferBarrier {
            src_stages: s.src_stages,
            src_access: s.src_access,
            dst_stages: s.dst_stages,
            dst_access: s.dst_access,
        })
    }
}

#[cfg(test)]
mod tests;
