//! The CPU twin of `shaders/exact.wgsl`: correctly rounded division and square root built
//! from a driver's approximation and integer arithmetic, function for function.
//!
//! The mirror itself divides with Rust's `/` and takes [`f32::sqrt`], which IEEE 754 rounds
//! to nearest, ties to even. The shader cannot: Vulkan lets `/` be off by 2.5 ULP and `sqrt`
//! by a few. So the shader's [`div_rn`] and [`sqrt_rn`] take the driver's result on two
//! significands in [1, 4) only as a first guess and finish with exact integer steps. This
//! file runs the same algorithm with the first guess as a parameter, so the tests can feed
//! it approximations off by every error from −3 to +3 ULP (and flushed or kept subnormals)
//! and check that it returns Rust's own `/` and `sqrt` in every bit (`tests/exact_math.rs`).
//!
//! The contract, on both sides: whenever the first approximation of the significands'
//! quotient (root) is within ±3 ULP, the result is IEEE 754's round-to-nearest-even value,
//! including zeros, infinities, overflow, subnormal operands and subnormal quotients; a NaN
//! result is a quiet NaN (Vulkan keeps no payload, so neither side promises one). No float
//! intermediate is subnormal, so flushing subnormal intermediates changes nothing.
//!
//! [`pow_det`], the power of a non-integer Phong exponent, is built from `+ - *`, division,
//! rounding to an integer, Dekker's exact product ([`product_error`]) and bits, never from a
//! driver's `exp2` and `log2`: the mirror calls this very function.

use crate::shared::real::Real;

/// WGSL `inexact_hash`: a 32-bit mix (the finaliser of MurmurHash3).
pub fn inexact_hash(x: u32) -> u32 {
    let mut h = x;
    h ^= h >> 16;
    h = h.wrapping_mul(0x85eb_ca6b);
    h ^= h >> 13;
    h = h.wrapping_mul(0xc2b2_ae35);
    h ^= h >> 16;
    h
}

/// WGSL `perturb`: `q` moved by k ULP, k in −2..=2 from a hash of the operands and of the
/// operation's number `op` (the shader's `approx_ops` after its increment); zeros,
/// infinities and NaN pass unchanged, and no step crosses zero or infinity.
pub fn perturb(q: f32, a: u32, b: u32, op: u32) -> f32 {
    let h = inexact_hash(a ^ inexact_hash(b ^ inexact_hash(op)));
    let k = (h % 5) as i32 - 2;
    let bits = q.to_bits();
    let mag = bits & 0x7fff_ffff;
    if mag == 0 || mag >= 0x7f80_0000 {
        return q;
    }
    let moved = (mag as i32 + k).clamp(1, 0x7f7f_ffff) as u32;
    f32::from_bits((bits & 0x8000_0000) | moved)
}

/// WGSL `unpack_rn`: a positive finite non-zero float's bits as (significand, exponent),
/// the value being `sig · 2^(exp − 150)` with `sig` in [2^23, 2^24).
pub fn unpack_rn(mag: u32) -> (i32, i32) {
    let field = mag >> 23;
    if field == 0 {
        let shift = mag.leading_zeros() - 8;
        return ((mag << shift) as i32, 1 - shift as i32);
    }
    (((mag & 0x7f_ffff) | 0x80_0000) as i32, field as i32)
}

/// WGSL `nan_rn`: a quiet NaN.
pub fn nan_rn() -> f32 {
    f32::from_bits(0x7fc0_0000)
}

/// WGSL `inf_rn`: +infinity.
pub fn inf_rn() -> f32 {
    f32::INFINITY
}

/// WGSL `div_rn` under `EXACT_MATH`: `a / b` rounded to nearest, ties to even, from
/// `approx_div`, the driver's quotient of two floats in [1, 4).
pub fn div_rn(a: f32, b: f32, approx_div: &mut impl FnMut(f32, f32) -> f32) -> f32 {
    let ua = a.to_bits();
    let ub = b.to_bits();
    let sign = (ua ^ ub) & 0x8000_0000;
    let ma = ua & 0x7fff_ffff;
    let mb = ub & 0x7fff_ffff;
    if ma > 0x7f80_0000 || mb > 0x7f80_0000 || (ma == mb && (ma == 0 || ma == 0x7f80_0000)) {
        return nan_rn();
    }
    if ma == 0x7f80_0000 || mb == 0 {
        return f32::from_bits(sign | 0x7f80_0000);
    }
    if ma == 0 || mb == 0x7f80_0000 {
        return f32::from_bits(sign);
    }
    let pa = unpack_rn(ma);
    let pb = unpack_rn(mb);
    let y = pb.0 as u32;
    // X in [Y, 2Y): the quotient's significand lies in [1, 2).
    let below = (pa.0 as u32) < y;
    let x = (pa.0 as u32) << if below { 1 } else { 0 };
    let mut biased = pa.1 - pb.1 + 127 - if below { 1 } else { 0 };
    // The driver's quotient of two floats in [1, 4), within a few ULP: a candidate N.
    let q = approx_div(x as f32, y as f32);
    let mut n = wgsl_u32(q * 8_388_608.0).clamp(0x80_0000, 0xff_ffff);
    // The remainder X·2^23 − N·Y, exact in its low 32 bits because it is small.
    let mut r = (x << 23).wrapping_sub(n.wrapping_mul(y)) as i32;
    for _ in 0..4 {
        let low = r < 0;
        n = if low { n.wrapping_sub(1) } else { n };
        r = if low { r.wrapping_add(y as i32) } else { r };
    }
    for _ in 0..4 {
        let high = r >= y as i32;
        n = if high { n.wrapping_add(1) } else { n };
        r = if high { r.wrapping_sub(y as i32) } else { r };
    }
    // Now N = floor(2^23 X / Y) in [2^23, 2^24) and 0 <= r < Y.
    let twice = (r as u32).wrapping_mul(2);
    if biased >= 1 {
        let up = twice > y || (twice == y && (n & 1) == 1);
        n += up as u32;
        if n == 0x100_0000 {
            n = 0x80_0000;
            biased += 1;
        }
        if biased >= 255 {
            return f32::from_bits(sign | 0x7f80_0000);
        }
        return f32::from_bits(sign | ((biased as u32) << 23) | (n & 0x7f_ffff));
    }
    // A subnormal quotient: N/2^23 · 2^(biased − 127) on the grid of 2^-149.
    let shift = (1 - biased).min(25) as u32;
    let kept = n >> shift;
    let dropped = n & ((1 << shift) - 1);
    let half = 1 << (shift - 1);
    let up = dropped > half || (dropped == half && (r != 0 || (kept & 1) == 1));
    f32::from_bits(sign | (kept + up as u32))
}

/// WGSL `sqrt_rn` under `EXACT_MATH`: `sqrt(x)` rounded to nearest from `approx_sqrt`, the
/// driver's root of a float in [1, 4).
pub fn sqrt_rn(x: f32, approx_sqrt: &mut impl FnMut(f32) -> f32) -> f32 {
    let ux = x.to_bits();
    let mag = ux & 0x7fff_ffff;
    if mag == 0 || ux == 0x7f80_0000 {
        return x;
    }
    if ux > 0x7f80_0000 {
        return nan_rn();
    }
    let p = unpack_rn(mag);
    // x = sig · 2^e with e = exp − 150; T = sig · 2^k with e − k even, T in [2^46, 2^48).
    let e = p.1 - 150;
    let k: u32 = if (e & 1) != 0 { 23 } else { 24 };
    let sig = p.0 as u32;
    // The driver's root of T / 2^46, a float in [1, 4): a candidate S within a few units.
    let f = sig as f32 * if k == 23 { TWO_M23 } else { 2.0 * TWO_M23 };
    let s0 = approx_sqrt(f);
    let mut s = wgsl_u32(s0 * 8_388_608.0).clamp(0x80_0000, 0xff_ffff);
    // The remainder T − S², exact in its low 32 bits because it is small.
    let mut r = (sig << k).wrapping_sub(s.wrapping_mul(s)) as i32;
    for _ in 0..4 {
        let low = r < 0;
        s = if low { s.wrapping_sub(1) } else { s };
        r = if low {
            r.wrapping_add(s.wrapping_mul(2).wrapping_add(1) as i32)
        } else {
            r
        };
    }
    for _ in 0..4 {
        let high = r > s.wrapping_mul(2) as i32;
        r = if high {
            r.wrapping_sub(s.wrapping_mul(2).wrapping_add(1) as i32)
        } else {
            r
        };
        s = if high { s.wrapping_add(1) } else { s };
    }
    // Now S = floor(√T), and T − S² = r in [0, 2S]: round up when T > (S + 1/2)².
    s += (r > s as i32) as u32;
    let mut biased = 150 + (e - k as i32) / 2;
    if s == 0x100_0000 {
        s = 0x80_0000;
        biased += 1;
    }
    f32::from_bits(((biased as u32) << 23) | (s & 0x7f_ffff))
}

/// 2^-23, exactly.
const TWO_M23: f32 = 1.0 / 8_388_608.0;

/// WGSL's `u32(x)` for an f32: towards zero, saturating at 0 and `u32::MAX` (NaN gives 0,
/// as Rust's `as` does).
fn wgsl_u32(x: f32) -> u32 {
    x as u32
}

/// The first approximation `exact` moved by `ulps` units in the last place, away from
/// zero for positive `ulps` (no step crosses zero or infinity): what a driver off by that
/// much returns, for the tests.
pub fn off_by(exact: f32, ulps: i32) -> f32 {
    let bits = exact.to_bits();
    let mag = bits & 0x7fff_ffff;
    if mag == 0 || mag >= 0x7f80_0000 {
        return exact;
    }
    let moved = (mag as i64 + ulps as i64).clamp(1, 0x7f7f_ffff) as u32;
    f32::from_bits((bits & 0x8000_0000) | moved)
}

// ---- a power without the driver's exp2 and log2 -------------------------------------------

/// WGSL `product_error`: Dekker's exact rounding error of the product `a * b == p`.
#[inline]
pub fn product_error<R: Real>(a: R, b: R, p: R) -> R {
    let ca = R::SPLITTER * a;
    let a_hi = ca - (ca - a);
    let a_lo = a - a_hi;
    let cb = R::SPLITTER * b;
    let b_hi = cb - (cb - b);
    let b_lo = b - b_hi;
    ((a_hi * b_hi - p) + a_hi * b_lo + a_lo * b_hi) + a_lo * b_lo
}

/// 1/ln 2 as the unevaluated sum `INV_LN2_HI + INV_LN2_LO` (to 2^-51).
const INV_LN2_HI: f32 = std::f32::consts::LOG2_E; // 1.442695
const INV_LN2_LO: f32 = 1.925963e-08;
/// 2/3 as the unevaluated sum `TWO_THIRDS_HI + TWO_THIRDS_LO` (to 2^-50).
const TWO_THIRDS_HI: f32 = 0.666_666_7;
const TWO_THIRDS_LO: f32 = -1.986_821_6e-8;
/// The bits of 2^-60: below it a power's exponent changes no bit of the result (x^y
/// rounds to 1).
const POW_TINY_Y: u32 = 0x2180_0000;
/// The bits of 2^64: above it every power is 0, 1 or infinity (and Veltkamp's split of y
/// cannot overflow).
const POW_HUGE_Y: u32 = 0x5f80_0000;

/// WGSL `two_sum_error`: `a + b == s + two_sum_error(a, b, s)` exactly for `s = a + b`.
#[inline]
pub fn two_sum_error(a: f32, b: f32, s: f32) -> f32 {
    let bb = s - a;
    (a - (s - bb)) + (b - bb)
}

/// WGSL `pow_det`: `x^y` for x ≥ 0 and y ≥ 0 from `+ - *`, division, rounding to an
/// integer and bits alone, the shader's bits on every driver: within a few ULP of the exact
/// power (measured against f64 by `tests/exact_twin.rs`), 1 for y = 0, 0 where the power is
/// below about 2^-125.5 and infinity from about 2^127.5 (the rounded exponent of 2 leaves
/// [-125, 127]); NaN for a negative or NaN argument. The shader's
/// `div_rn` is IEEE division, which Rust's `/` is.
pub fn pow_det(x: f32, y: f32) -> f32 {
    // The special cases by their bits: a driver that flushes subnormals compares them as 0.
    let (xb, yb) = (x.to_bits(), y.to_bits());
    let (xm, ym) = (xb & 0x7fff_ffff, yb & 0x7fff_ffff);
    if xm > 0x7f80_0000 || ym > 0x7f80_0000 || (xb != xm && xm != 0) || (yb != ym && ym != 0) {
        return nan_rn();
    }
    if ym == 0 || xm == 0x3f80_0000 {
        return 1.0;
    }
    if xm == 0 || xm == 0x7f80_0000 {
        return f32::from_bits(xm);
    }
    if ym < POW_TINY_Y {
        return 1.0;
    }
    if ym > POW_HUGE_Y {
        return if xm < 0x3f80_0000 { 0.0 } else { inf_rn() };
    }
    // x = m · 2^k, m in [√½, √2]; a subnormal x normalised by its leading zeros.
    let mut bits = xm;
    let mut k = (bits >> 23) as i32 - 127;
    if (bits >> 23) == 0 {
        let shift = bits.leading_zeros() - 8;
        bits <<= shift;
        k = -126 - shift as i32;
    }
    let mut m = f32::from_bits((bits & 0x7f_ffff) | 0x3f80_0000);
    if m > std::f32::consts::SQRT_2 {
        m *= 0.5;
        k += 1;
    }
    // s = (m − 1) / (m + 1) as s_hi + s_lo: m − 1 is exact, m + 1 is d_hi + d_lo.
    let t = m - 1.0;
    let d_hi = m + 1.0;
    let d_lo = two_sum_error(m, 1.0, d_hi);
    let s_hi = t / d_hi;
    let p = s_hi * d_hi;
    let r = ((t - p) - product_error(s_hi, d_hi, p)) - s_hi * d_lo;
    let s_lo = r / d_hi;
    // ln m = 2s + 2s³/3 + 2s⁵/5 + …: 2s and 2s³/3 as sums of two floats (s_lo enters
    // through the derivative 2 + 2s²), the terms from 2s⁵/5 on (below 2^-11 of ln m) in one.
    let z = s_hi * s_hi;
    let z_lo = product_error(s_hi, s_hi, z);
    let c = s_hi * z;
    let c_lo = product_error(s_hi, z, c) + s_hi * z_lo;
    let t1 = c * TWO_THIRDS_HI;
    let t1_lo = product_error(c, TWO_THIRDS_HI, t1) + (c * TWO_THIRDS_LO + c_lo * TWO_THIRDS_HI);
    let rest = (c * z)
        * (0.4 + z * (0.285_714_3 + z * (0.222_222_22 + z * (0.181_818_19 + z * 0.153_846_16))));
    let two_s = 2.0 * s_hi;
    let ln_hi = two_s + t1;
    let ln_lo = ((two_s - ln_hi) + t1) + (((t1_lo + rest) + 2.0 * s_lo) + (2.0 * z) * s_lo);
    // log2 x = k + ln m / ln 2, then y · log2 x, each as a sum of two floats.
    let q_hi = ln_hi * INV_LN2_HI;
    let q_lo = product_error(ln_hi, INV_LN2_HI, q_hi) + (ln_hi * INV_LN2_LO + ln_lo * INV_LN2_HI);
    let kf = k as f32;
    let l_hi = kf + q_hi;
    let l_lo = two_sum_error(kf, q_hi, l_hi) + q_lo;
    let w_hi = y * l_hi;
    let w_lo = product_error(y, l_hi, w_hi) + y * l_lo;
    // 2^(n + f): n by the exponent's bits, 2^f in [0.70, 1.42] by its series.
    let n = w_hi.round_ties_even();
    if n > 127.0 {
        return inf_rn();
    }
    if n < -125.0 {
        return 0.0;
    }
    let f = (w_hi - n) + w_lo;
    let e = 1.0
        + f * (std::f32::consts::LN_2
            + f * (0.240_226_5
                + f * (0.055_504_11
                    + f * (0.009_618_129
                        + f * (0.001_333_355_8
                            + f * (0.000_154_035_3
                                + f * (1.525_273_4e-5 + f * 1.321_548_7e-6)))))));
    e * f32::from_bits(((n as i32 + 127) as u32) << 23)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_few_quotients_and_roots() {
        let mut exact_div = |a: f32, b: f32| a / b;
        let mut exact_sqrt = |x: f32| x.sqrt();
        for (a, b) in [
            (1.0f32, 3.0f32),
            (2.0, 7.0),
            (-5.5, 0.1),
            (1e-40, 3.0),
            (3e38, 1e-3),
        ] {
            assert_eq!(
                div_rn(a, b, &mut exact_div).to_bits(),
                (a / b).to_bits(),
                "{a} / {b}"
            );
        }
        for x in [2.0f32, 3.0, 1e-40, 1e30, 0.5] {
            assert_eq!(
                sqrt_rn(x, &mut exact_sqrt).to_bits(),
                x.sqrt().to_bits(),
                "sqrt {x}"
            );
        }
    }
}
