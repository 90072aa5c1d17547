//! The packet twins of `common.rs`: the packet's size, its rays as structure of arrays
//! (with one origin or one per lane), lane masks and lane-wise vector helpers.

// Lane loops index several arrays in step, `for l in 0..LANES`, the form LLVM vectorises.
#![allow(clippy::needless_range_loop)]

use crate::kernel::real::V3;

/// Rays per packet.
pub const LANES: usize = 16;

const _: () = assert!(
    LANES.is_multiple_of(8) && LANES <= 16,
    "mask_of gathers eight flags at a time into a u16"
);

/// Packet width in pixels (the packet is `PACKET_W` × `PACKET_H`).
pub const PACKET_W: u32 = 4;

/// Packet height in pixels.
pub const PACKET_H: u32 = 4;

/// A bit per lane.
pub type Mask = u16;

/// Where the lanes' rays start: `rel(p, l)` is `p - origin` of lane l, per component, and
/// `from(p, l)` is `origin - p`.
pub(super) trait Origins {
    fn rel(&self, p: &[f32; 3], l: usize) -> [f32; 3];
    fn from(&self, p: &[f32; 3], l: usize) -> [f32; 3];
    /// Lane l's origin.
    fn at(&self, l: usize) -> [f32; 3];
    /// The origins with their components reordered: component i of the result is
    /// component `k[i]` of the original.
    fn permuted(&self, k: [usize; 3]) -> Self;
}

/// One origin for every lane (camera rays): LLVM hoists `rel` out of the lane loops.
pub(super) struct Shared(pub(super) V3<f32>);

impl Origins for Shared {
    #[inline(always)]
    fn rel(&self, p: &[f32; 3], _l: usize) -> [f32; 3] {
        [p[0] - self.0.x, p[1] - self.0.y, p[2] - self.0.z]
    }
    #[inline(always)]
    fn from(&self, p: &[f32; 3], _l: usize) -> [f32; 3] {
        [self.0.x - p[0], self.0.y - p[1], self.0.z - p[2]]
    }
    #[inline(always)]
    fn at(&self, _l: usize) -> [f32; 3] {
        [self.0.x, self.0.y, self.0.z]
    }
    #[inline(always)]
    fn permuted(&self, k: [usize; 3]) -> Self {
        let o = [self.0.x, self.0.y, self.0.z];
        Shared(V3::new(o[k[0]], o[k[1]], o[k[2]]))
    }
}

/// An origin per lane (shadow rays), as structure of arrays.
pub(super) struct PerLane(pub(super) [[f32; LANES]; 3]);

impl Origins for PerLane {
    #[inline(always)]
    fn rel(&self, p: &[f32; 3], l: usize) -> [f32; 3] {
        [
            p[0] - self.0[0][l],
            p[1] - self.0[1][l],
            p[2] - self.0[2][l],
        ]
    }
    #[inline(always)]
    fn from(&self, p: &[f32; 3], l: usize) -> [f32; 3] {
        [
            self.0[0][l] - p[0],
            self.0[1][l] - p[1],
            self.0[2][l] - p[2],
        ]
    }
    #[inline(always)]
    fn at(&self, l: usize) -> [f32; 3] {
        [self.0[0][l], self.0[1][l], self.0[2][l]]
    }
    #[inline(always)]
    fn permuted(&self, k: [usize; 3]) -> Self {
        PerLane([self.0[k[0]], self.0[k[1]], self.0[k[2]]])
    }
}

/// Rays with their directions, reciprocal directions and `dir · dir` as structure of
/// arrays.
pub(super) struct Lanes<O> {
    pub(super) origin: O,
    pub(super) dir: [[f32; LANES]; 3],
    pub(super) ix: [f32; LANES],
    pub(super) iy: [f32; LANES],
    pub(super) iz: [f32; LANES],
    /// `dir.dot(dir)` of each lane (`V3::dot`'s order).
    pub(super) dd: [f32; LANES],
    /// Which axes the directions run down, where every lane's runs the same way on every
    /// axis and each reciprocal is finite and not 0 (`None` otherwise).
    pub(super) neg: Option<[bool; 3]>,
}

impl<O> Lanes<O> {
    /// The rays from `origin` with directions `dir` (structure of arrays).
    #[inline(always)]
    pub(super) fn new(origin: O, dir: &[[f32; LANES]; 3]) -> Self {
        let mut r = Lanes {
            origin,
            dir: *dir,
            ix: [0.0; LANES],
            iy: [0.0; LANES],
            iz: [0.0; LANES],
            dd: [0.0; LANES],
            neg: None,
        };
        for l in 0..LANES {
            r.ix[l] = 1.0 / dir[0][l];
            r.iy[l] = 1.0 / dir[1][l];
            r.iz[l] = 1.0 / dir[2][l];
            r.dd[l] = dot_lane(dir, dir, l);
        }
        let neg = [dir[0][0] < 0.0, dir[1][0] < 0.0, dir[2][0] < 0.0];
        let mut same = [true; LANES];
        for l in 0..LANES {
            let inv = [r.ix[l], r.iy[l], r.iz[l]];
            for k in 0..3 {
                let ok = inv[k].is_finite() && inv[k] != 0.0 && (inv[k] < 0.0) == neg[k];
                same[l] &= ok;
            }
        }
        if same.iter().all(|&s| s) {
            r.neg = Some(neg);
        }
        r
    }
}

/// The bits of the lanes' flags, lane l in bit l. Branch-free, eight lanes at a time: the
/// flags as bytes (0 or 1) times 0x0102040810204080 puts byte l's bit in bit 56 + l, and no
/// two partial products share a bit, so nothing carries.
#[inline(always)]
pub(super) fn mask_of(flags: &[bool; LANES]) -> Mask {
    let bytes: [u8; LANES] = flags.map(u8::from);
    let mut m: Mask = 0;
    for h in 0..LANES / 8 {
        let eight: [u8; 8] = bytes[8 * h..8 * h + 8].try_into().expect("eight lanes");
        let bits = u64::from_le_bytes(eight).wrapping_mul(0x0102_0408_1020_4080) >> 56;
        m |= (bits as Mask) << (8 * h);
    }
    m
}

/// `a · b` of lane l, left to right as `V3::dot`.
#[inline(always)]
pub(super) fn dot_lane(a: &[[f32; LANES]; 3], b: &[[f32; LANES]; 3], l: usize) -> f32 {
    a[0][l] * b[0][l] + a[1][l] * b[1][l] + a[2][l] * b[2][l]
}

/// `V3::normalize` of every lane.
#[inline(always)]
pub(super) fn normalize_lanes(v: &[[f32; LANES]; 3]) -> [[f32; LANES]; 3] {
    let mut out = [[0.0f32; LANES]; 3];
    for l in 0..LANES {
        let len = dot_lane(v, v, l).sqrt();
        out[0][l] = v[0][l] / len;
        out[1][l] = v[1][l] / len;
        out[2][l] = v[2][l] / len;
    }
    out
}
