//! The CPU mirror of `shaders/common.wgsl`, the second of the kernel's eight parts (after `exact.wgsl`): the
//! ray and hit records, the shader's module-scope globals (`params`, the buffers, the
//! override constants) as the fields of [`Globals`], and the small helpers.
//!
//! The mirror is six files with the shader's stems (`common.rs`, `prims.rs`,
//! `texture.rs`, `trace.rs`, `whitted.rs`, `aov.rs`), each with the same functions as its WGSL part, with the same names, in the
//! same order, doing the same operations in the same order. Written generic over [`Real`]:
//! instantiated at f32 it is the shader's twin (bit for bit on lavapipe), at f64 it is the
//! ground truth that error is measured against. Un-idiomatic Rust (`if !(x > 0)`, index
//! loops, early returns) is kept where it keeps a line comparable with its WGSL line.

// `!(x > 0)` is not `x <= 0` for NaN; the shader writes it so, on purpose, and so does its mirror.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

use crate::buffers::{SceneBuffers, Specialisation};
use crate::shared::real::{Real, V3};

/// WGSL `BVH_STACK`: the traversal stack, as deep as the builder lets a tree be.
pub const BVH_STACK: usize = crate::bvh::MAX_DEPTH;

/// The camera, in the tracer's precision. WGSL: the camera fields of `params`.
#[derive(Clone, Copy, Debug)]
pub struct Camera<R> {
    /// Ray origin.
    pub eye: V3<R>,
    /// Unit view direction.
    pub forward: V3<R>,
    /// Unit right vector.
    pub right: V3<R>,
    /// Camera up.
    pub up: V3<R>,
    /// tan(fov / 2).
    pub tan_half: R,
    /// width / height.
    pub aspect: R,
    /// Image width.
    pub width: u32,
    /// Image height.
    pub height: u32,
    /// Samples per pixel side.
    pub samples: u32,
}

impl Camera<f32> {
    /// The f32 camera exactly as the shader receives it.
    pub fn from_params(p: &crate::buffers::Params) -> Self {
        Camera {
            eye: p.eye.into(),
            forward: p.forward.into(),
            right: p.right.into(),
            up: p.up.into(),
            tan_half: p.tan_half,
            aspect: p.aspect,
            width: p.width,
            height: p.height,
            samples: p.samples,
        }
    }
}

/// What the shader sees at module scope, for the CPU; and what counts the traversal's
/// steps ([`super::count`]: nothing, for the tracers).
pub struct Globals<'a, R, C = super::count::NoCount> {
    /// The camera.
    pub cam: Camera<R>,
    /// Scene buffers (colours and geometry are widened from f32 to `R` where read).
    pub buf: &'a SceneBuffers,
    /// The pipeline's override constants.
    pub spec: Specialisation,
    /// The traversal's counter.
    pub count: C,
}

/// WGSL `Ray`.
#[derive(Clone, Copy, Debug)]
pub struct Ray<R> {
    /// Origin.
    pub origin: V3<R>,
    /// Direction (any length).
    pub dir: V3<R>,
}

/// WGSL `Hit`.
#[derive(Clone, Copy, Debug)]
pub struct Hit<R> {
    /// Distance along the ray.
    pub t: R,
    /// Primitive index with `TRIANGLE_BIT` for triangles, or `PRIM_NONE`.
    pub prim: u32,
    /// Barycentric weight of b.
    pub u: R,
    /// Barycentric weight of c.
    pub v: R,
    /// The instance whose primitive was hit (0 where the scene has none).
    pub inst: u32,
}

// ---- small helpers ---------------------------------------------------------------------

/// WGSL `max0`: `x` when `x > 0`, else 0 (NaN gives 0).
#[inline]
pub fn max0<R: Real>(x: R) -> R {
    if x > R::ZERO { x } else { R::ZERO }
}

/// WGSL `max2`: the larger of `a` and `b` (`b` when either is NaN).
#[inline]
pub fn max2<R: Real>(a: R, b: R) -> R {
    if a > b { a } else { b }
}

/// WGSL `flush`: `x`, or 0 where |x| is below the smallest normal f32
/// ([`crate::shared::layout::FLUSH_BELOW`], the same threshold in f64: the model's, not the
/// type's).
#[inline]
pub fn flush<R: Real>(x: R) -> R {
    if x.abs() < R::FLUSH_BELOW { R::ZERO } else { x }
}

/// WGSL `flush3`: [`flush`] of each component.
#[inline]
pub fn flush3<R: Real>(v: V3<R>) -> V3<R> {
    V3::new(flush(v.x), flush(v.y), flush(v.z))
}

/// WGSL `clamp01`: `x` clamped to [0, 1] (NaN gives 0).
#[inline]
pub fn clamp01<R: Real>(x: R) -> R {
    if !(x > R::ZERO) {
        R::ZERO
    } else if x > R::ONE {
        R::ONE
    } else {
        x
    }
}

/// WGSL `to_u8` and `pack_rgba8`, in their place in the mirror: defined on the ground
/// floor (`shared::real`), since the image writer, below this floor, quantises with them.
pub use crate::shared::real::{pack_rgba8, to_u8};

/// WGSL `in_interval`: whether t lies in (t_min, t_max); false for NaN.
#[inline]
pub fn in_interval<R: Real>(t: R, t_min: R, t_max: R) -> bool {
    t > t_min && t < t_max
}

/// WGSL `select(-1.0, 1.0, b >= 0.0)`.
#[inline]
pub fn sign_nonneg<R: Real>(b: R) -> R {
    if b >= R::ZERO { R::ONE } else { -R::ONE }
}
