//! The packet twins of `common.rs`: the packet's size, its rays as structure of arrays
//! (with one origin or one per lane), lane masks and lane-wise vector helpers.

// Lane loops index several arrays in step, `for l in 0..LANES`, the form LLVM vectorises.
#![allow(clippy::needless_range_loop)]

use crate::cpu::instance::map_point;
use crate::shared::real::V3;

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
    /// Each lane's origin mapped by the affine map `m` (the mirror's `map_point`).
    fn mapped(&self, m: &[[f32; 4]; 3]) -> Self;
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
    #[inline(always)]
    fn mapped(&self, m: &[[f32; 4]; 3]) -> Self {
        Shared(map_point(m, self.0))
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
    #[inline(always)]
    fn mapped(&self, m: &[[f32; 4]; 3]) -> Self {
        let mut out = [[0.0f32; LANES]; 3];
        for l in 0..LANES {
            let p = map_point(m, V3::new(self.0[0][l], self.0[1][l], self.0[2][l]));
            [out[0][l], out[1][l], out[2][l]] = [p.x, p.y, p.z];
        }
        PerLane(out)
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
                // `&`, not `&&`: no branch a lane, so that the loop vectorises.
                let ok = inv[k].is_finite() & (inv[k] != 0.0) & ((inv[k] < 0.0) == neg[k]);
                same[l] &= ok;
            }
        }
        if same.iter().all(|&s| s) {
            r.neg = Some(neg);
        }
        r
    }
}

/// The bits of the lanes' flags, lane l in bit l. On x86-64 (SSE2 is in its baseline, so
/// in every build): the sixteen flags as bytes (0 or 1) in one register, shifted so each
/// byte's flag is its sign bit, and `pmovmskb` gathers the sixteen sign bits. Elsewhere,
/// branch-free, eight lanes at a time: the flags as bytes times 0x0102040810204080 puts
/// byte l's bit in bit 56 + l, and no two partial products share a bit, so nothing carries
/// (slower on x86: `docs/bench/cpu-packets.md`).
#[inline(always)]
pub(super) fn mask_of(flags: &[bool; LANES]) -> Mask {
    #[cfg(target_arch = "x86_64")]
    {
        use std::arch::x86_64::{__m128i, _mm_loadu_si128, _mm_movemask_epi8, _mm_slli_epi64};
        const _: () = assert!(LANES == 16, "one 16-byte register of flags");
        // SAFETY: the load reads the sixteen bytes of `flags` (a bool is one byte, 0 or 1);
        // SSE2 is in every x86-64 CPU. Each byte's bit 0 moves to its bit 7 (the bits
        // moving into the next byte are 0), and `pmovmskb` gathers bit 7 of each byte.
        unsafe {
            let x = _mm_loadu_si128(flags.as_ptr() as *const __m128i);
            _mm_movemask_epi8(_mm_slli_epi64::<7>(x)) as Mask
        }
    }
    #[cfg(not(target_arch = "x86_64"))]
    {
        let bytes: [u8; LANES] = flags.map(u8::from);
        let mut m: Mask = 0;
        for h in 0..LANES / 8 {
            let eight: [u8; 8] = bytes[8 * h..8 * h + 8].try_into().expect("eight lanes");
            let bits = u64::from_le_bytes(eight).wrapping_mul(0x0102_0408_1020_4080) >> 56;
            m |= (bits as Mask) << (8 * h);
        }
        m
    }
}

/// A build of the packet tracer (`Simd`), as a type: how it turns a lane-wise compare into
/// a lane mask. The box test's mask, 60 a packet on the peers' 1M-triangle scene, went
/// through `mask_of`: the compare's result, already a mask register in the AVX-512 build,
/// was widened to sixteen bytes and multiplied back into bits. Every build gives the same
/// mask (`<=` is false where either side is NaN, as `_CMP_LE_OQ` is).
///
/// A value of a build is its proof that the CPU runs its instructions: [`Avx2`] and
/// [`Avx512`] are made only by their `detect` (the CPU's own answer) or by an `unsafe`
/// constructor whose caller vouches for the CPU, so safe code cannot run their
/// instructions where the CPU lacks them.
pub(super) trait Build: Copy {
    /// Whether this build searches the two levels of a scene with instances (`Two`):
    /// a constant, so that the one-level build holds no code of the two levels.
    const INSTANCES: bool = false;
    /// The instance of each lane's hit: `()` without instances (nothing to carry), else a
    /// lane array.
    type Inst: InstLanes;
    /// The lanes where `a[l] <= b[l]`.
    fn le_mask(self, a: &[f32; LANES], b: &[f32; LANES]) -> Mask;
}

/// Each lane's hit's instance, as a packet's hits carry it.
pub(super) trait InstLanes: Copy + Default {
    /// Lane l's instance.
    fn lane(&self, l: usize) -> u32;
    /// Sets lane l's instance.
    fn set(&mut self, l: usize, inst: u32);
}

/// No instances: every hit is of instance 0.
impl InstLanes for () {
    #[inline(always)]
    fn lane(&self, _l: usize) -> u32 {
        0
    }
    #[inline(always)]
    fn set(&mut self, _l: usize, _inst: u32) {}
}

impl InstLanes for [u32; LANES] {
    #[inline(always)]
    fn lane(&self, l: usize) -> u32 {
        self[l]
    }
    #[inline(always)]
    fn set(&mut self, l: usize, inst: u32) {
        self[l] = inst;
    }
}

/// Build `B` for scenes with instances: the two-level searches and the shading of
/// instanced hits.
#[derive(Clone, Copy)]
pub(super) struct Two<B>(pub(super) B);

impl<B: Build> Build for Two<B> {
    const INSTANCES: bool = true;
    type Inst = [u32; LANES];
    #[inline(always)]
    fn le_mask(self, a: &[f32; LANES], b: &[f32; LANES]) -> Mask {
        self.0.le_mask(a, b)
    }
}

/// The baseline build: `mask_of`.
#[derive(Clone, Copy)]
pub(super) struct Portable;

impl Build for Portable {
    type Inst = ();
    #[inline(always)]
    fn le_mask(self, a: &[f32; LANES], b: &[f32; LANES]) -> Mask {
        let mut f = [false; LANES];
        for l in 0..LANES {
            f[l] = a[l] <= b[l];
        }
        mask_of(&f)
    }
}

/// The AVX2 build: two eight-lane compares and their sign bits (`movmskps`). A value is
/// the proof that the CPU has AVX2.
#[cfg(target_arch = "x86_64")]
#[derive(Clone, Copy)]
pub(super) struct Avx2(());

#[cfg(target_arch = "x86_64")]
impl Avx2 {
    /// The proof, where the CPU has AVX2.
    pub(super) fn detect() -> Option<Avx2> {
        std::arch::is_x86_feature_detected!("avx2").then_some(Avx2(()))
    }

    /// The proof, unchecked.
    ///
    /// # Safety
    /// The CPU must have AVX2 (as inside a function compiled with that feature, which
    /// itself may only run where the CPU has it).
    pub(super) unsafe fn new_unchecked() -> Avx2 {
        Avx2(())
    }
}

#[cfg(target_arch = "x86_64")]
impl Build for Avx2 {
    type Inst = ();
    #[inline(always)]
    fn le_mask(self, a: &[f32; LANES], b: &[f32; LANES]) -> Mask {
        // SAFETY: `self` proves that the CPU has AVX2.
        unsafe { le_mask_avx2(a, b) }
    }
}

/// [`Avx2::le_mask`], compiled for AVX2 (inlined into the AVX2 build).
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
#[inline]
fn le_mask_avx2(a: &[f32; LANES], b: &[f32; LANES]) -> Mask {
    use std::arch::x86_64::{_CMP_LE_OQ, _mm256_cmp_ps, _mm256_loadu_ps, _mm256_movemask_ps};
    let mut m: Mask = 0;
    for h in 0..LANES / 8 {
        // SAFETY: each load reads eight of the sixteen floats of `a` or `b`.
        let (x, y) = unsafe {
            (
                _mm256_loadu_ps(a.as_ptr().add(8 * h)),
                _mm256_loadu_ps(b.as_ptr().add(8 * h)),
            )
        };
        m |= (_mm256_movemask_ps(_mm256_cmp_ps::<_CMP_LE_OQ>(x, y)) as Mask) << (8 * h);
    }
    m
}

/// The AVX-512 build: one sixteen-lane compare into a mask register. A value is the
/// proof that the CPU has AVX-512 F.
#[cfg(target_arch = "x86_64")]
#[derive(Clone, Copy)]
pub(super) struct Avx512(());

#[cfg(target_arch = "x86_64")]
impl Avx512 {
    /// The proof, where the CPU has AVX-512 F, VL, BW and DQ (what the AVX-512 build of
    /// the packet tracer is compiled for).
    pub(super) fn detect() -> Option<Avx512> {
        (std::arch::is_x86_feature_detected!("avx512f")
            && std::arch::is_x86_feature_detected!("avx512vl")
            && std::arch::is_x86_feature_detected!("avx512bw")
            && std::arch::is_x86_feature_detected!("avx512dq"))
        .then_some(Avx512(()))
    }

    /// The proof, unchecked.
    ///
    /// # Safety
    /// The CPU must have AVX-512 F (as inside a function compiled with that feature).
    pub(super) unsafe fn new_unchecked() -> Avx512 {
        Avx512(())
    }
}

#[cfg(target_arch = "x86_64")]
impl Build for Avx512 {
    type Inst = ();
    #[inline(always)]
    fn le_mask(self, a: &[f32; LANES], b: &[f32; LANES]) -> Mask {
        // SAFETY: `self` proves that the CPU has AVX-512 F.
        unsafe { le_mask_avx512(a, b) }
    }
}

/// [`Avx512::le_mask`], compiled for AVX-512 F (inlined into the AVX-512 build).
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx512f")]
#[inline]
fn le_mask_avx512(a: &[f32; LANES], b: &[f32; LANES]) -> Mask {
    use std::arch::x86_64::{_CMP_LE_OQ, _mm512_cmp_ps_mask, _mm512_loadu_ps};
    const _: () = assert!(LANES == 16, "one 16-lane vector");
    // SAFETY: each load reads the sixteen floats of `a` or `b`.
    let (x, y) = unsafe { (_mm512_loadu_ps(a.as_ptr()), _mm512_loadu_ps(b.as_ptr())) };
    _mm512_cmp_ps_mask::<_CMP_LE_OQ>(x, y)
}

/// Lane l's choice of `a` where bit l of `m` is set, else `b`, as bit operations. LLVM
/// turns `x[l] = if on { a } else { x[l] }` on an array behind a reference into a store
/// made only where `on` holds: a branch a lane, never a vector, and vector reads after it
/// of the lanes stored one at a time. This form is always an unconditional store, and
/// vectorises.
#[inline(always)]
pub(super) fn choose_bits(m: Mask, l: usize, a: u32, b: u32) -> u32 {
    let sel = 0u32.wrapping_sub(((m >> l) & 1) as u32);
    (a & sel) | (b & !sel)
}

/// The mirror's `flush` (WGSL `flush`) of a value that is not negative (a shading term, a
/// power, an average of colours), the very bits `flush` gives there (NaN kept, −0 made
/// +0): one float compare and select, which vectorises as such (a compare of `abs`, or
/// of the bits, measured slower in the packet's lane loops). Wrong for a negative value
/// (it gives 0): the callers' values never are.
#[inline(always)]
pub(super) fn flush_nonneg(x: f32) -> f32 {
    if x < crate::shared::layout::FLUSH_BELOW {
        0.0
    } else {
        x
    }
}

/// [`choose_bits`] of two `f32`s: `a` where bit l of `m` is set, else `b`, the very bits.
#[inline(always)]
pub(super) fn choose(m: Mask, l: usize, a: f32, b: f32) -> f32 {
    f32::from_bits(choose_bits(m, l, a.to_bits(), b.to_bits()))
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

#[cfg(test)]
mod tests {
    use super::*;

    /// Lane l's flag in bit l, one lane at a time: what `mask_of` and every build's
    /// `le_mask` must give.
    fn by_lane(flags: &[bool; LANES]) -> Mask {
        (0..LANES).fold(0, |m, l| m | (Mask::from(flags[l]) << l))
    }

    /// `mask_of` and each build's `le_mask` (those this CPU runs) against the lane-by-lane
    /// bits, on every single-lane flag, alternating patterns and pseudo-random ones; the
    /// compare with NaN, infinities, signed zeros and equal values.
    #[test]
    fn masks_match_the_lanes() {
        let mut patterns: Vec<[bool; LANES]> = (0..LANES)
            .map(|k| std::array::from_fn(|l| l == k))
            .collect();
        patterns.push([true; LANES]);
        patterns.push([false; LANES]);
        let mut s = 0x9e37_79b9_7f4a_7c15u64;
        for _ in 0..1000 {
            s ^= s << 13;
            s ^= s >> 7;
            s ^= s << 17;
            patterns.push(std::array::from_fn(|l| (s >> l) & 1 == 1));
        }
        for f in &patterns {
            assert_eq!(mask_of(f), by_lane(f), "{f:?}");
        }
        let vals = [
            f32::NAN,
            f32::INFINITY,
            f32::NEG_INFINITY,
            0.0,
            -0.0,
            1.0,
            -1.0,
            f32::MIN_POSITIVE,
            f32::MAX,
        ];
        let mut checks = 0;
        for (i, &x) in vals.iter().enumerate() {
            let a: [f32; LANES] = std::array::from_fn(|l| vals[(i + l) % vals.len()]);
            let b: [f32; LANES] =
                std::array::from_fn(|l| if l % 2 == 0 { x } else { vals[l % vals.len()] });
            let want = by_lane(&std::array::from_fn(|l| a[l] <= b[l]));
            assert_eq!(Portable.le_mask(&a, &b), want);
            #[cfg(target_arch = "x86_64")]
            {
                if let Some(avx2) = Avx2::detect() {
                    assert_eq!(avx2.le_mask(&a, &b), want);
                    checks += 1;
                }
                if let Some(avx512) = Avx512::detect() {
                    assert_eq!(avx512.le_mask(&a, &b), want);
                    checks += 1;
                }
            }
        }
        eprintln!("le_mask checked on {checks} vector builds' cases");
    }

    /// The first lane of a mask where `pick(m, l, a, b)` is not the branch's choice, bit
    /// for bit, over every lane of pseudo-random masks and NaN payloads, signed zeros and
    /// infinities on both sides.
    fn first_wrong_choice(pick: impl Fn(Mask, usize, f32, f32) -> f32) -> Option<(Mask, usize)> {
        let vals = [
            f32::from_bits(0x7fc0_1234),
            f32::from_bits(0xffa0_0001),
            f32::INFINITY,
            f32::NEG_INFINITY,
            0.0,
            -0.0,
            1.5,
            -f32::MIN_POSITIVE,
        ];
        let mut s = 0x2545_f491_4f6c_dd1du64;
        for _ in 0..200 {
            s ^= s << 13;
            s ^= s >> 7;
            s ^= s << 17;
            let m = s as Mask;
            for l in 0..LANES {
                for &a in &vals {
                    for &b in &vals {
                        let want = if (m >> l) & 1 != 0 { a } else { b };
                        if pick(m, l, a, b).to_bits() != want.to_bits() {
                            return Some((m, l));
                        }
                    }
                }
            }
        }
        None
    }

    /// `choose` (and through it `choose_bits`) is the branch's choice, bit for bit.
    #[test]
    fn choose_is_the_branch() {
        assert_eq!(first_wrong_choice(choose), None);
    }

    /// The twin: a choice that reads the neighbouring lane's bit is caught.
    #[test]
    fn a_wrong_choice_is_caught() {
        let shifted = |m: Mask, l: usize, a: f32, b: f32| choose(m, (l + 1) % LANES, a, b);
        assert!(first_wrong_choice(shifted).is_some());
    }

    /// The check can fail: one lane's bit flipped is caught.
    #[test]
    fn a_wrong_mask_is_caught() {
        let f: [bool; LANES] = std::array::from_fn(|l| l % 3 == 0);
        assert_ne!(mask_of(&f) ^ (1 << 5), by_lane(&f));
    }

    /// The first value where `f` differs in bits from the mirror's `flush`, over the
    /// boundary's neighbourhood, zeros, infinity, NaNs and every exponent: the values a
    /// shading term can take (not negative, or NaN).
    fn first_wrong_flush(f: impl Fn(f32) -> f32) -> Option<f32> {
        let min = crate::shared::layout::FLUSH_BELOW;
        let mut xs = vec![
            0.0,
            -0.0,
            min,
            f32::from_bits(min.to_bits() - 1),
            f32::from_bits(min.to_bits() + 1),
            f32::from_bits(1),
            f32::INFINITY,
            f32::NAN,
            f32::from_bits(0xffc0_0001),
        ];
        for e in 0..=255u32 {
            for m in [0, 1, 0x40_0000, 0x7f_ffff] {
                xs.push(f32::from_bits(e << 23 | m));
            }
        }
        xs.into_iter()
            .find(|&x| f(x).to_bits() != crate::cpu::common::flush(x).to_bits())
    }

    /// `flush_nonneg` is the mirror's `flush` on the values it is given, bit for bit.
    #[test]
    fn flush_nonneg_is_the_mirrors_flush() {
        assert_eq!(first_wrong_flush(flush_nonneg), None);
    }

    /// The twin: a flush that compares with `<=` (flushing the smallest normal too) is
    /// caught.
    #[test]
    fn a_wrong_flush_is_caught() {
        let le = |x: f32| {
            if x <= crate::shared::layout::FLUSH_BELOW {
                0.0
            } else {
                x
            }
        };
        assert!(first_wrong_flush(le).is_some());
    }
}
