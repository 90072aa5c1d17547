// glint's kernel, part 0 of 8: correctly rounded division and square root, the only doors
// through which arithmetic that a driver may round its own way reaches the kernel.
//
// Vulkan rounds `+ - *` correctly but lets `/` be off by 2.5 ULP and `sqrt` by a few. Every
// division and square root of the kernel goes through `div_rn` and `sqrt_rn` (and the
// vector forms below them). Under `EXACT_MATH` they start from the driver's own result on
// two significands in [1, 4), where every driver is accurate to a few ULP, and finish with
// integer arithmetic, which Vulkan defines exactly:
//
// 1. the operands' signs, exponents and 24-bit significands are read from their bits
//    (subnormal operands included, whatever the driver does with subnormal floats);
// 2. the driver's quotient (root) of the significands, scaled by 2^23, is a candidate
//    integer N within a few units of the truth;
// 3. the remainder of N, `X·2^23 − N·Y` (`T − N²` for the root), is small, so its low 32
//    bits are the whole of it: wrapping u32 products give it exactly; four fixed steps
//    each way then move N to the floor of the exact quotient (root);
// 4. the remainder decides the rounding to nearest, ties to even, at 24 bits or, for a
//    subnormal quotient, at the coarser grid it lands on; the bits are assembled as u32.
//
// The result is IEEE 754's round-to-nearest-even quotient and root in every bit whenever the
// driver's first approximation is within ±3 ULP (the steps reach ±4 units; Vulkan allows
// 2.5 ULP for division and 3 for the root). Zeros, infinities, NaN (any quiet NaN),
// overflow, subnormal operands and results and |b| beyond 2^126 are handled by the bits, not
// by the driver; no intermediate float is subnormal, so a driver that flushes subnormals
// gives the same bits. The CPU twin is `src/cpu/exact.rs`, function for function.
//
// A non-integer power (a Phong exponent) never reaches the driver's `exp2` and `log2`, whose
// error Vulkan leaves to the driver: `pow_det` builds it from `+ - *`, `div_rn`, `round`,
// Dekker's exact product (`product_error`) and bits, so it is the same function everywhere.
//
// `INEXACT_DRIVER` perturbs every first approximation by up to ±2 ULP, differently from
// operation to operation and pixel to pixel, to prove on an exact driver (lavapipe) that
// the corrections do not depend on it; with `EXACT_MATH` off the raw results reach the
// image and it differs.

/// Division and square root correctly rounded whatever the driver (`--math exact`); off,
/// the driver's own `/` and `sqrt` (`--math fast`).
override EXACT_MATH: bool = true;
/// Simulate a driver whose `/` and `sqrt` are off by up to ±2 ULP (`--inexact-driver`).
override INEXACT_DRIVER: bool = false;

/// How many first approximations this invocation has made: varies the simulated error
/// from operation to operation.
var<private> approx_ops: u32 = 0u;

/// A 32-bit mix (the finaliser of MurmurHash3).
fn inexact_hash(x: u32) -> u32 {
    var h = x;
    h ^= h >> 16u;
    h *= 0x85ebca6bu;
    h ^= h >> 13u;
    h *= 0xc2b2ae35u;
    h ^= h >> 16u;
    return h;
}

/// `q` moved by k ULP, k in -2..=2 chosen by a hash of the operands and of the operation's
/// number; zeros, infinities and NaN pass unchanged, and no step crosses zero or infinity.
fn perturb(q: f32, a: u32, b: u32) -> f32 {
    approx_ops += 1u;
    let h = inexact_hash(a ^ inexact_hash(b ^ inexact_hash(approx_ops)));
    let k = i32(h % 5u) - 2;
    let bits = bitcast<u32>(q);
    let mag = bits & 0x7fffffffu;
    if mag == 0u || mag >= 0x7f800000u {
        return q;
    }
    let moved = u32(clamp(i32(mag) + k, 1, 0x7f7fffff));
    return bitcast<f32>((bits & 0x80000000u) | moved);
}

/// The driver's `a / b` (perturbed under `INEXACT_DRIVER`).
fn approx_div(a: f32, b: f32) -> f32 {
    let q = a / b;
    if INEXACT_DRIVER {
        return perturb(q, bitcast<u32>(a), bitcast<u32>(b));
    }
    return q;
}

/// The driver's `sqrt(x)` (perturbed under `INEXACT_DRIVER`).
fn approx_sqrt(x: f32) -> f32 {
    let s = sqrt(x);
    if INEXACT_DRIVER {
        return perturb(s, bitcast<u32>(x), 0x5bd1e995u);
    }
    return s;
}

/// A positive finite non-zero float's bits (sign cleared) as (significand, exponent): the
/// value is `sig · 2^(exp − 150)` with `sig` in [2^23, 2^24); subnormals are normalised.
fn unpack_rn(mag: u32) -> vec2<i32> {
    let field = mag >> 23u;
    if field == 0u {
        let shift = countLeadingZeros(mag) - 8u;
        return vec2<i32>(i32(mag << shift), 1 - i32(shift));
    }
    return vec2<i32>(i32((mag & 0x7fffffu) | 0x800000u), i32(field));
}

/// The bits of a quiet NaN and of +infinity, read at run time: WGSL makes a constant
/// expression whose value is a NaN or an infinity a shader-creation error (Tint applies it).
var<private> qnan_bits: u32 = 0x7fc00000u;
var<private> inf_bits: u32 = 0x7f800000u;

/// A quiet NaN.
fn nan_rn() -> f32 {
    return bitcast<f32>(qnan_bits);
}

/// +infinity.
fn inf_rn() -> f32 {
    return bitcast<f32>(inf_bits);
}

/// `a / b` rounded to nearest, ties to even, as IEEE 754 divides.
fn div_rn(a: f32, b: f32) -> f32 {
    if !EXACT_MATH {
        return approx_div(a, b);
    }
    let ua = bitcast<u32>(a);
    let ub = bitcast<u32>(b);
    let sign = (ua ^ ub) & 0x80000000u;
    let ma = ua & 0x7fffffffu;
    let mb = ub & 0x7fffffffu;
    if ma > 0x7f800000u || mb > 0x7f800000u || (ma == mb && (ma == 0u || ma == 0x7f800000u)) {
        return nan_rn();
    }
    if ma == 0x7f800000u || mb == 0u {
        return bitcast<f32>(sign | 0x7f800000u);
    }
    if ma == 0u || mb == 0x7f800000u {
        return bitcast<f32>(sign);
    }
    let pa = unpack_rn(ma);
    let pb = unpack_rn(mb);
    let y = u32(pb.x);
    // X in [Y, 2Y): the quotient's significand lies in [1, 2).
    let below = u32(pa.x) < y;
    let x = u32(pa.x) << select(0u, 1u, below);
    var biased = pa.y - pb.y + 127 - select(0, 1, below);
    // The driver's quotient of two floats in [1, 4), within a few ULP: a candidate N.
    let q = approx_div(f32(x), f32(y));
    var n = clamp(u32(q * 8388608.0), 0x800000u, 0xffffffu);
    // The remainder X·2^23 − N·Y, exact in its low 32 bits because it is small.
    var r = i32((x << 23u) - n * y);
    for (var i = 0; i < 4; i++) {
        let low = r < 0;
        n = select(n, n - 1u, low);
        r = select(r, r + i32(y), low);
    }
    for (var i = 0; i < 4; i++) {
        let high = r >= i32(y);
        n = select(n, n + 1u, high);
        r = select(r, r - i32(y), high);
    }
    // Now N = floor(2^23 X / Y) in [2^23, 2^24) and 0 <= r < Y.
    let twice = u32(r) * 2u;
    if biased >= 1 {
        let up = twice > y || (twice == y && (n & 1u) == 1u);
        n += select(0u, 1u, up);
        if n == 0x1000000u {
            n = 0x800000u;
            biased += 1;
        }
        if biased >= 255 {
            return bitcast<f32>(sign | 0x7f800000u);
        }
        return bitcast<f32>(sign | (u32(biased) << 23u) | (n & 0x7fffffu));
    }
    // A subnormal quotient: N/2^23 · 2^(biased − 127) on the grid of 2^-149.
    let shift = u32(min(1 - biased, 25));
    let kept = n >> shift;
    let dropped = n & ((1u << shift) - 1u);
    let half = 1u << (shift - 1u);
    let up = dropped > half || (dropped == half && (r != 0 || (kept & 1u) == 1u));
    return bitcast<f32>(sign | (kept + select(0u, 1u, up)));
}

/// `sqrt(x)` rounded to nearest, as IEEE 754 takes it (never subnormal, never a tie).
fn sqrt_rn(x: f32) -> f32 {
    if !EXACT_MATH {
        return approx_sqrt(x);
    }
    let ux = bitcast<u32>(x);
    let mag = ux & 0x7fffffffu;
    if mag == 0u || ux == 0x7f800000u {
        return x;
    }
    if ux > 0x7f800000u {
        return nan_rn();
    }
    let p = unpack_rn(mag);
    // x = sig · 2^e with e = exp − 150; T = sig · 2^k with e − k even, T in [2^46, 2^48).
    let e = p.y - 150;
    let k = select(24u, 23u, (e & 1) != 0);
    let sig = u32(p.x);
    // The driver's root of T / 2^46, a float in [1, 4): a candidate S within a few units.
    let f = f32(sig) * select(2.384185791015625e-7, 1.1920928955078125e-7, k == 23u);
    let s0 = approx_sqrt(f);
    var s = clamp(u32(s0 * 8388608.0), 0x800000u, 0xffffffu);
    // The remainder T − S², exact in its low 32 bits because it is small.
    var r = i32((sig << k) - s * s);
    for (var i = 0; i < 4; i++) {
        let low = r < 0;
        s = select(s, s - 1u, low);
        r = select(r, r + i32(2u * s + 1u), low);
    }
    for (var i = 0; i < 4; i++) {
        let high = r > i32(2u * s);
        r = select(r, r - i32(2u * s + 1u), high);
        s = select(s, s + 1u, high);
    }
    // Now S = floor(√T), and T − S² = r in [0, 2S]: round up when T > (S + 1/2)².
    s += select(0u, 1u, r > i32(s));
    var biased = 150 + (e - i32(k)) / 2;
    if s == 0x1000000u {
        s = 0x800000u;
        biased += 1;
    }
    return bitcast<f32>((u32(biased) << 23u) | (s & 0x7fffffu));
}

/// `div_rn` of each component.
fn div3_rn(a: vec3<f32>, b: vec3<f32>) -> vec3<f32> {
    return vec3<f32>(div_rn(a.x, b.x), div_rn(a.y, b.y), div_rn(a.z, b.z));
}

/// `div_rn` of each component by one divisor.
fn div3s_rn(a: vec3<f32>, b: f32) -> vec3<f32> {
    return vec3<f32>(div_rn(a.x, b), div_rn(a.y, b), div_rn(a.z, b));
}

/// `v / sqrt(dot(v, v))`, each step correctly rounded: WGSL's `normalize`, written out.
fn normalize_rn(v: vec3<f32>) -> vec3<f32> {
    return div3s_rn(v, sqrt_rn(dot(v, v)));
}

// ---- a power without the driver's exp2 and log2 -------------------------------------------

const SPLITTER: f32 = 4097.0; // 2^12 + 1, Veltkamp's split for f32

/// The rounding error of the f32 product `a * b` (Dekker's TwoProduct without fma):
/// a * b == fl(a * b) + product_error(a, b, fl(a * b)) exactly, barring under/overflow.
fn product_error(a: f32, b: f32, p: f32) -> f32 {
    let ca = SPLITTER * a;
    let a_hi = ca - (ca - a);
    let a_lo = a - a_hi;
    let cb = SPLITTER * b;
    let b_hi = cb - (cb - b);
    let b_lo = b - b_hi;
    return ((a_hi * b_hi - p) + a_hi * b_lo + a_lo * b_hi) + a_lo * b_lo;
}

/// 1/ln 2 as the unevaluated sum `INV_LN2_HI + INV_LN2_LO` (to 2^-51).
const INV_LN2_HI: f32 = 1.442695;
const INV_LN2_LO: f32 = 1.925963e-08;
/// 2/3 as the unevaluated sum `TWO_THIRDS_HI + TWO_THIRDS_LO` (to 2^-50).
const TWO_THIRDS_HI: f32 = 0.6666667;
const TWO_THIRDS_LO: f32 = -1.9868216e-08;
/// The bits of 2^-60: below it a power's exponent changes no bit of the result (x^y
/// rounds to 1).
const POW_TINY_Y: u32 = 0x21800000u;
/// The bits of 2^64: above it every power is 0, 1 or infinity (and Veltkamp's split of y
/// cannot overflow).
const POW_HUGE_Y: u32 = 0x5f800000u;

/// `a + b == s + two_sum_error(a, b, s)` exactly for `s = a + b` (Knuth's TwoSum).
fn two_sum_error(a: f32, b: f32, s: f32) -> f32 {
    let bb = s - a;
    return (a - (s - bb)) + (b - bb);
}

/// `x^y` for x ≥ 0 and y ≥ 0 from `+ - *`, `div_rn`, `round` and bits alone, so every
/// driver gives the same bits as the CPU twin: within a few ULP of the exact power
/// (`tests/exact_twin.rs` measures it against f64), 1 for y = 0, 0 where the power is below
/// about 2^-125.5 and infinity from about 2^127.5 (the rounded exponent of 2 leaves
/// [-125, 127]). NaN for a negative or NaN argument.
///
/// log2 x = k + ln(m) / ln 2 with m in [√½, √2], ln m = 2 atanh(s) for s = (m − 1)/(m + 1),
/// |s| ≤ 0.172, carried as a sum of two floats; y·log2 x = n + f with n an integer and
/// |f| ≤ ½; 2^f by its Taylor series to degree 8 (error 2^-28); 2^n by the exponent's bits.
fn pow_det(x: f32, y: f32) -> f32 {
    // The special cases by their bits: a driver that flushes subnormals compares them as 0.
    let xb = bitcast<u32>(x);
    let yb = bitcast<u32>(y);
    let xm = xb & 0x7fffffffu;
    let ym = yb & 0x7fffffffu;
    if xm > 0x7f800000u || ym > 0x7f800000u || (xb != xm && xm != 0u) || (yb != ym && ym != 0u) {
        return nan_rn();
    }
    if ym == 0u || xm == 0x3f800000u {
        return 1.0;
    }
    if xm == 0u || xm == 0x7f800000u {
        return bitcast<f32>(xm);
    }
    if ym < POW_TINY_Y {
        return 1.0;
    }
    if ym > POW_HUGE_Y {
        return select(inf_rn(), 0.0, xm < 0x3f800000u);
    }
    // x = m · 2^k, m in [√½, √2]; a subnormal x normalised by its leading zeros.
    var bits = xm;
    var k = i32(bits >> 23u) - 127;
    if (bits >> 23u) == 0u {
        let shift = countLeadingZeros(bits) - 8u;
        bits = bits << shift;
        k = -126 - i32(shift);
    }
    var m = bitcast<f32>((bits & 0x7fffffu) | 0x3f800000u);
    if m > 1.4142135 {
        m = m * 0.5;
        k = k + 1;
    }
    // s = (m − 1) / (m + 1) as s_hi + s_lo: m − 1 is exact, m + 1 is d_hi + d_lo.
    let t = m - 1.0;
    let d_hi = m + 1.0;
    let d_lo = two_sum_error(m, 1.0, d_hi);
    let s_hi = div_rn(t, d_hi);
    let p = s_hi * d_hi;
    let r = ((t - p) - product_error(s_hi, d_hi, p)) - s_hi * d_lo;
    let s_lo = div_rn(r, d_hi);
    // ln m = 2s + 2s³/3 + 2s⁵/5 + …: 2s and 2s³/3 as sums of two floats (s_lo enters
    // through the derivative 2 + 2s²), the terms from 2s⁵/5 on (below 2^-11 of ln m) in one.
    let z = s_hi * s_hi;
    let z_lo = product_error(s_hi, s_hi, z);
    let c = s_hi * z;
    let c_lo = product_error(s_hi, z, c) + s_hi * z_lo;
    let t1 = c * TWO_THIRDS_HI;
    let t1_lo = product_error(c, TWO_THIRDS_HI, t1) + (c * TWO_THIRDS_LO + c_lo * TWO_THIRDS_HI);
    let rest = (c * z) * (0.4 + z * (0.2857143 + z * (0.22222222 + z * (0.18181819 + z * 0.15384616))));
    let two_s = 2.0 * s_hi;
    let ln_hi = two_s + t1;
    let ln_lo = ((two_s - ln_hi) + t1) + (((t1_lo + rest) + 2.0 * s_lo) + (2.0 * z) * s_lo);
    // log2 x = k + ln m / ln 2, then y · log2 x, each as a sum of two floats.
    let q_hi = ln_hi * INV_LN2_HI;
    let q_lo = product_error(ln_hi, INV_LN2_HI, q_hi) + (ln_hi * INV_LN2_LO + ln_lo * INV_LN2_HI);
    let kf = f32(k);
    let l_hi = kf + q_hi;
    let l_lo = two_sum_error(kf, q_hi, l_hi) + q_lo;
    let w_hi = y * l_hi;
    let w_lo = product_error(y, l_hi, w_hi) + y * l_lo;
    // 2^(n + f): n by the exponent's bits, 2^f in [0.70, 1.42] by its series.
    let n = round(w_hi);
    if n > 127.0 {
        return inf_rn();
    }
    if n < -125.0 {
        return 0.0;
    }
    let f = (w_hi - n) + w_lo;
    let e = 1.0 + f * (0.6931472 + f * (0.2402265 + f * (0.05550411 + f * (0.009618129 + f * (0.0013333558 + f * (0.0001540353 + f * (1.5252734e-05 + f * 1.3215487e-06)))))));
    return e * bitcast<f32>(u32(i32(n) + 127) << 23u);
}
