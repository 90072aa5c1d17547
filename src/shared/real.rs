//! The numeric kernel, at the bottom of the house (imports only `shared::layout`'s
//! constants): the arithmetic the CPU tracer is written in: a scalar [`Real`] (f32 to mirror the
//! shader, f64 for the ground truth) and a three-vector [`V3`] whose every operation is
//! written out in WGSL's order.
//!
//! Why not glam: glam's `Vec3` is fine arithmetic, but the order of its operations is its
//! own business and may change; here `dot` is `x·x' + y·y' + z·z'` left to right and
//! `normalize` is `v / sqrt(dot(v, v))`, which is what lavapipe does for WGSL's
//! `dot` and `normalize` (checked by `tests/primitives.rs`).

use std::ops::{Add, Div, Mul, Neg, Sub};

/// A float type the CPU tracer can run in: f32 (the shader's mirror) or f64 (the reference).
pub trait Real:
    Copy
    + PartialOrd
    + Send
    + Sync
    + std::fmt::Debug
    + Add<Output = Self>
    + Sub<Output = Self>
    + Mul<Output = Self>
    + Div<Output = Self>
    + Neg<Output = Self>
{
    /// Whether this is the shader's own f32 (the mirror), not the f64 reference.
    const MIRROR: bool;
    /// 0.
    const ZERO: Self;
    /// 1.
    const ONE: Self;
    /// The `t` of "no hit yet" (`buffers::INFINITY` for f32, `f64::MAX` for f64).
    const INFINITY: Self;
    /// Veltkamp's splitter, 2^(p/2) + 1 for p bits of mantissa.
    const SPLITTER: Self;
    /// The relative shadow-ray offset unit (machine epsilon).
    const EPSILON: Self;
    /// 2γ(3) rounded up (4 ε), the relative slack of the conservative box test (pbrt).
    const BOX_SLACK: Self;
    /// The naive test's sliver bound, 16 ε (`buffers::NAIVE_MIN_SIN2`).
    const NAIVE_MIN_SIN2: Self;
    /// The smallest normal f32, below which a shading term is 0 (`buffers::FLUSH_BELOW`),
    /// in this type.
    const FLUSH_BELOW: Self;
    /// WGSL `bitcast<f32>(bitcast<u32>(x) + 1u)`: the next float up, for positive finite x.
    fn bits_plus_one(self) -> Self;
    /// Exact conversion from f32.
    fn from_f32(x: f32) -> Self;
    /// Conversion from u32 (exact below 2^24 for f32).
    fn from_u32(x: u32) -> Self;
    /// Conversion to f32 (rounding).
    fn to_f32(self) -> f32;
    /// Correctly rounded square root.
    fn sqrt(self) -> Self;
    /// Absolute value.
    fn abs(self) -> Self;
    /// `self^e` (libm's `pow`): the reference's power; the mirror's is
    /// `cpu::exact::pow_det`.
    fn powf(self, e: Self) -> Self;
    /// The largest integer not above `self` (exact).
    fn floor(self) -> Self;
    /// WGSL `i32(x)`: towards zero, saturating (exact for the integers below 2^24 that
    /// the texture lookup converts).
    fn to_i32(self) -> i32;
}

impl Real for f32 {
    const MIRROR: bool = true;
    const ZERO: Self = 0.0;
    const ONE: Self = 1.0;
    const INFINITY: Self = crate::shared::layout::INFINITY;
    const SPLITTER: Self = crate::shared::layout::SPLITTER;
    const EPSILON: Self = crate::shared::layout::SHADOW_EPSILON;
    const BOX_SLACK: Self = crate::shared::layout::BOX_SLACK;
    const NAIVE_MIN_SIN2: Self = crate::shared::layout::NAIVE_MIN_SIN2;
    const FLUSH_BELOW: Self = crate::shared::layout::FLUSH_BELOW;
    fn bits_plus_one(self) -> Self {
        f32::from_bits(self.to_bits().wrapping_add(1))
    }
    fn from_f32(x: f32) -> Self {
        x
    }
    fn from_u32(x: u32) -> Self {
        x as f32
    }
    fn to_f32(self) -> f32 {
        self
    }
    fn sqrt(self) -> Self {
        f32::sqrt(self)
    }
    fn abs(self) -> Self {
        f32::abs(self)
    }
    fn powf(self, e: Self) -> Self {
        f32::powf(self, e)
    }
    fn floor(self) -> Self {
        f32::floor(self)
    }
    fn to_i32(self) -> i32 {
        self as i32
    }
}

impl Real for f64 {
    const MIRROR: bool = false;
    const ZERO: Self = 0.0;
    const ONE: Self = 1.0;
    const INFINITY: Self = f64::MAX;
    const SPLITTER: Self = 134_217_729.0; // 2^27 + 1
    const EPSILON: Self = f64::EPSILON;
    const BOX_SLACK: Self = 4.0 * f64::EPSILON;
    const NAIVE_MIN_SIN2: Self = 16.0 * f64::EPSILON;
    const FLUSH_BELOW: Self = crate::shared::layout::FLUSH_BELOW as f64;
    fn bits_plus_one(self) -> Self {
        f64::from_bits(self.to_bits().wrapping_add(1))
    }
    fn from_f32(x: f32) -> Self {
        x as f64
    }
    fn from_u32(x: u32) -> Self {
        x as f64
    }
    fn to_f32(self) -> f32 {
        self as f32
    }
    fn sqrt(self) -> Self {
        f64::sqrt(self)
    }
    fn abs(self) -> Self {
        f64::abs(self)
    }
    fn powf(self, e: Self) -> Self {
        f64::powf(self, e)
    }
    fn floor(self) -> Self {
        f64::floor(self)
    }
    fn to_i32(self) -> i32 {
        self as i32
    }
}

/// A three-vector in WGSL's order of operations.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct V3<R> {
    /// x.
    pub x: R,
    /// y.
    pub y: R,
    /// z.
    pub z: R,
}

impl<R: Real> V3<R> {
    /// `vec3(x, y, z)`.
    pub fn new(x: R, y: R, z: R) -> Self {
        V3 { x, y, z }
    }
    /// `vec3(s)`.
    pub fn splat(s: R) -> Self {
        V3 { x: s, y: s, z: s }
    }
    /// Widens an f32 array.
    pub fn from_f32(a: [f32; 3]) -> Self {
        V3::new(R::from_f32(a[0]), R::from_f32(a[1]), R::from_f32(a[2]))
    }
    /// Narrows to an f32 array.
    pub fn to_f32(self) -> [f32; 3] {
        [self.x.to_f32(), self.y.to_f32(), self.z.to_f32()]
    }
    /// WGSL `dot`: x·x' + y·y' + z·z', left to right.
    pub fn dot(self, o: Self) -> R {
        self.x * o.x + self.y * o.y + self.z * o.z
    }
    /// WGSL `cross3` (glint's written-out cross product).
    pub fn cross(self, o: Self) -> Self {
        V3::new(
            self.y * o.z - self.z * o.y,
            self.z * o.x - self.x * o.z,
            self.x * o.y - self.y * o.x,
        )
    }
    /// WGSL `normalize` as lavapipe computes it: v / √(v·v), each component divided
    /// (not multiplied by a reciprocal: that differs in about half the cases).
    pub fn normalize(self) -> Self {
        let len = self.dot(self).sqrt();
        V3::new(self.x / len, self.y / len, self.z / len)
    }
    /// WGSL `abs` per component.
    pub fn abs(self) -> Self {
        V3::new(self.x.abs(), self.y.abs(), self.z.abs())
    }
    /// `v[k]` for k in 0..3 (WGSL's dynamic vector index).
    pub fn get(self, k: u32) -> R {
        match k {
            0 => self.x,
            1 => self.y,
            _ => self.z,
        }
    }
}

impl From<[f32; 3]> for V3<f32> {
    fn from(a: [f32; 3]) -> Self {
        V3::new(a[0], a[1], a[2])
    }
}

impl From<V3<f32>> for [f32; 3] {
    fn from(v: V3<f32>) -> Self {
        [v.x, v.y, v.z]
    }
}

impl<R: Real> Add for V3<R> {
    type Output = Self;
    fn add(self, o: Self) -> Self {
        V3::new(self.x + o.x, self.y + o.y, self.z + o.z)
    }
}

impl<R: Real> Sub for V3<R> {
    type Output = Self;
    fn sub(self, o: Self) -> Self {
        V3::new(self.x - o.x, self.y - o.y, self.z - o.z)
    }
}

impl<R: Real> Mul for V3<R> {
    type Output = Self;
    fn mul(self, o: Self) -> Self {
        V3::new(self.x * o.x, self.y * o.y, self.z * o.z)
    }
}

impl<R: Real> Mul<R> for V3<R> {
    type Output = Self;
    fn mul(self, s: R) -> Self {
        V3::new(self.x * s, self.y * s, self.z * s)
    }
}

impl<R: Real> Div for V3<R> {
    type Output = Self;
    fn div(self, o: Self) -> Self {
        V3::new(self.x / o.x, self.y / o.y, self.z / o.z)
    }
}

impl<R: Real> Neg for V3<R> {
    type Output = Self;
    fn neg(self) -> Self {
        V3::new(-self.x, -self.y, -self.z)
    }
}

/// The scene format's camera basis (docs/scene-format.md), evaluated left to right: `[forward, right, up']`.
pub fn camera_basis<R: Real>(eye: V3<R>, look_at: V3<R>, up: V3<R>) -> [V3<R>; 3] {
    let forward = (look_at - eye).normalize();
    let right = forward.cross(up).normalize();
    let up2 = right.cross(forward);
    [forward, right, up2]
}

/// WGSL `to_u8` (common.wgsl): one channel to 8 bits, as the PNG holds it: clamped to
/// [0, 1] as `clamp01` does (NaN gives 0), scaled by 255, rounded half up. glint's one
/// quantisation, kept on the ground floor so that the image writer (`image.rs`), `compare`
/// and the mirror (`cpu::common` re-exports it in WGSL's order) share it.
#[inline]
// `!(x > 0.0)` is the point: a NaN takes the first branch, as in `clamp01`.
#[allow(clippy::neg_cmp_op_on_partial_ord)]
pub fn to_u8(x: f32) -> u8 {
    let c = if !(x > 0.0) {
        0.0
    } else if x > 1.0 {
        1.0
    } else {
        x
    };
    (c * 255.0 + 0.5) as u8
}

/// WGSL `pack_rgba8`: a colour as four bytes, red in the lowest, alpha opaque.
#[inline]
pub fn pack_rgba8(c: [f32; 4]) -> u32 {
    to_u8(c[0]) as u32 | (to_u8(c[1]) as u32) << 8 | (to_u8(c[2]) as u32) << 16 | 255 << 24
}
