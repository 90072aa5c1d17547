//! What a GPU lane does, counted on the CPU: the mirror follows the shader's per-ray
//! traversal step by step, so counting its steps counts the shader's (`glint stats`).
//!
//! The tracer's functions are generic over a [`Count`]; [`NoCount`], the tracers' own,
//! does nothing in every hook and compiles to nothing, so counting costs a render nothing
//! (a type, not a branch per step). [`Counter`] records each ray: its kind, the interior
//! nodes and leaves it visited, the primitives it tested, its deepest stack and the bytes
//! of nodes and primitives the traversal read. The hooks are not in the WGSL; they sit
//! beside the lines they count.

use std::cell::RefCell;

use crate::buffers::{BvhNode, Sphere, TRIANGLE_BIT, Triangle};

/// The kinds of rays a pixel traces.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum RayKind {
    /// From the camera through the pixel.
    Camera,
    /// Towards a light (any hit ends it).
    Shadow,
    /// A mirror reflection (total internal reflection included).
    Reflected,
    /// A refraction into or out of a transparent material.
    Refracted,
}

impl RayKind {
    /// Every kind, in report order.
    pub const ALL: [RayKind; 4] = [
        RayKind::Camera,
        RayKind::Shadow,
        RayKind::Reflected,
        RayKind::Refracted,
    ];

    /// `camera`, `shadow`, `reflected`, `refracted`.
    pub fn name(self) -> &'static str {
        match self {
            RayKind::Camera => "camera",
            RayKind::Shadow => "shadow",
            RayKind::Reflected => "reflected",
            RayKind::Refracted => "refracted",
        }
    }
}

/// The hooks the tracer calls; each does nothing unless a counter overrides it.
pub trait Count {
    /// The next closest-hit search is a ray of kind `k` (the camera's).
    #[inline(always)]
    fn next_kind(&self, _k: RayKind) {}
    /// A secondary ray of kind `k` was pushed onto the Whitted stack.
    #[inline(always)]
    fn pushed(&self, _k: RayKind) {}
    /// The Whitted walk popped a ray: the next closest-hit search is the kind it was
    /// pushed as.
    #[inline(always)]
    fn popped(&self) {}
    /// A search begins: any-hit (a shadow ray) or closest-hit.
    #[inline(always)]
    fn begin(&self, _any_hit: bool) {}
    /// `n` nodes were read (a box or a node's header).
    #[inline(always)]
    fn nodes_read(&self, _n: u32) {}
    /// An interior node was visited.
    #[inline(always)]
    fn interior(&self) {}
    /// A leaf was visited.
    #[inline(always)]
    fn leaf(&self) {}
    /// Primitive `id` was tested.
    #[inline(always)]
    fn prim(&self, _id: u32) {}
    /// The traversal stack holds `depth` entries.
    #[inline(always)]
    fn stack(&self, _depth: usize) {}
    /// The search ended.
    #[inline(always)]
    fn end(&self) {}
}

/// The tracers' own [`Count`]: nothing.
#[derive(Clone, Copy, Debug, Default)]
pub struct NoCount;

impl Count for NoCount {}

/// One ray's traversal.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct RayCount {
    /// Interior nodes visited.
    pub interior: u32,
    /// Leaves visited.
    pub leaves: u32,
    /// Primitives tested.
    pub prims: u32,
    /// The deepest stack.
    pub stack: u32,
    /// Bytes of nodes and primitives read.
    pub bytes: u64,
}

#[derive(Debug, Default)]
struct State {
    /// The kind of the next closest-hit search.
    next: Option<RayKind>,
    /// The kinds of the rays on the Whitted stack, bottom first.
    pending: Vec<RayKind>,
    /// The search under way.
    current: Option<(RayKind, RayCount)>,
    /// The finished rays, in order.
    rays: Vec<(RayKind, RayCount)>,
}

/// A [`Count`] that records every ray (for one thread: one pixel or row at a time).
#[derive(Debug, Default)]
pub struct Counter(RefCell<State>);

impl Counter {
    /// An empty counter.
    pub fn new() -> Counter {
        Counter::default()
    }

    /// The rays recorded since the last call, in the order they were traced.
    pub fn take(&self) -> Vec<(RayKind, RayCount)> {
        std::mem::take(&mut self.0.borrow_mut().rays)
    }

    fn with(&self, f: impl FnOnce(&mut RayCount)) {
        if let Some((_, c)) = &mut self.0.borrow_mut().current {
            f(c)
        }
    }
}

const NODE_BYTES: u64 = std::mem::size_of::<BvhNode>() as u64;
const TRIANGLE_BYTES: u64 = std::mem::size_of::<Triangle>() as u64;
const SPHERE_BYTES: u64 = std::mem::size_of::<Sphere>() as u64;

impl Count for Counter {
    fn next_kind(&self, k: RayKind) {
        self.0.borrow_mut().next = Some(k);
    }
    fn pushed(&self, k: RayKind) {
        self.0.borrow_mut().pending.push(k);
    }
    fn popped(&self) {
        let mut s = self.0.borrow_mut();
        s.next = s.pending.pop();
    }
    fn begin(&self, any_hit: bool) {
        let mut s = self.0.borrow_mut();
        let kind = if any_hit {
            RayKind::Shadow
        } else {
            s.next.unwrap_or(RayKind::Camera)
        };
        s.current = Some((kind, RayCount::default()));
    }
    fn nodes_read(&self, n: u32) {
        self.with(|c| c.bytes += n as u64 * NODE_BYTES);
    }
    fn interior(&self) {
        self.with(|c| c.interior += 1);
    }
    fn leaf(&self) {
        self.with(|c| c.leaves += 1);
    }
    fn prim(&self, id: u32) {
        self.with(|c| {
            c.prims += 1;
            c.bytes += if id & TRIANGLE_BIT != 0 {
                TRIANGLE_BYTES
            } else {
                SPHERE_BYTES
            };
        });
    }
    fn stack(&self, depth: usize) {
        self.with(|c| c.stack = c.stack.max(depth as u32));
    }
    fn end(&self) {
        let mut s = self.0.borrow_mut();
        if let Some(r) = s.current.take() {
            s.rays.push(r);
        }
    }
}
