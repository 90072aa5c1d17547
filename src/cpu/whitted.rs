//! The CPU mirror of `shaders/whitted.wgsl`: Whitted's secondary rays, a depth-first walk
//! with a stack of rays that carry premultiplied weights (see the shader's header for the
//! model: Fresnel, total internal reflection, the side rule, the origins, `min_weight`).

// `!(x > 0)` is not `x <= 0` for NaN; the shader writes it so, on purpose, and so does its mirror.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

use super::common::{Globals, Hit, Ray, clamp01, flush, flush3, max0, max2};
use super::count::{Count, RayKind};
use super::prims::{prim_material, prim_normal, shading_at};
use super::trace::{closest_hit, shade};
use crate::buffers::{Material, PRIM_NONE};
use crate::shared::real::{Real, V3};

/// WGSL `WHITTED_STACK`: the most rays waiting at once (max_depth + 1 for the largest
/// max_depth, 16).
pub const WHITTED_STACK: usize = crate::shared::layout::WHITTED_STACK as usize;

/// The largest `max_depth` a scene may ask for (the stack holds max_depth + 1 rays).
pub const MAX_DEPTH: u32 = crate::shared::layout::MAX_WHITTED_DEPTH;

/// WGSL `Pending`: a secondary ray waiting on the stack.
#[derive(Clone, Copy, Debug)]
pub struct Pending<R> {
    /// Origin.
    pub origin: V3<R>,
    /// The reflections and refractions that made it.
    pub depth: u32,
    /// Direction.
    pub dir: V3<R>,
    /// Premultiplied weight.
    pub weight: V3<R>,
}

/// WGSL `fresnel_dielectric`: the unpolarised dielectric Fresnel reflectance at incidence
/// cosine `cos_i` ≥ 0, relative index `eta` and squared transmitted sine `sin2_t`; 1 at and
/// beyond the critical angle; 0 where `eta` is 1 (no boundary, grazing included).
pub fn fresnel_dielectric<R: Real>(cos_i: R, eta: R, sin2_t: R) -> R {
    if eta == R::ONE {
        return R::ZERO;
    }
    if sin2_t >= R::ONE {
        return R::ONE;
    }
    let cos_t = max0(R::ONE - sin2_t).sqrt();
    let r_parl = (eta * cos_i - cos_t) / (eta * cos_i + cos_t);
    let r_perp = (cos_i - eta * cos_t) / (cos_i + eta * cos_t);
    flush((flush(r_parl * r_parl) + flush(r_perp * r_perp)) / (R::ONE + R::ONE))
}

/// WGSL `spawn_origin`: the origin of a secondary ray leaving the hit `p` of a ray from
/// `o`, on the side of `n`: 16 ε of the largest coordinate of `o`, `p` (and 1) along `n`.
pub fn spawn_origin<R: Real>(o: V3<R>, p: V3<R>, n: V3<R>) -> V3<R> {
    let scale_p = max2(max2(p.x.abs(), p.y.abs()), max2(p.z.abs(), R::ONE));
    let scale = max2(scale_p, max2(max2(o.x.abs(), o.y.abs()), o.z.abs()));
    p + n * (scale * R::EPSILON * R::from_u32(16))
}

/// WGSL `worth_tracing`: the weight's largest channel is positive and reaches
/// `min_weight`.
pub fn worth_tracing<R: Real, C: Count>(g: &Globals<R, C>, w: V3<R>) -> bool {
    let m = max2(max2(w.x, w.y), w.z);
    m > R::ZERO && m >= R::from_f32(g.buf.params.min_weight)
}

/// WGSL `keep_side`: `dir`, mirrored about the plane of unit normal `n` when it does not
/// leave on the side `side` says (+1 the normal's, −1 the other).
pub fn keep_side<R: Real>(dir: V3<R>, n: V3<R>, side: R) -> V3<R> {
    let along = dir.dot(n);
    if along * side > R::ZERO {
        return dir;
    }
    dir - n * ((R::ONE + R::ONE) * along)
}

/// WGSL `push_children`: pushes the transmitted ray, then the reflected one, of the hit
/// `hit` of `ray` (weight `weight`, made by `depth` bounces) onto `stack` above `sp`;
/// returns the new top.
pub fn push_children<R: Real, C: Count>(
    g: &Globals<R, C>,
    stack: &mut [Pending<R>; WHITTED_STACK],
    sp: usize,
    ray: Ray<R>,
    hit: &Hit<R>,
    weight: V3<R>,
    depth: u32,
) -> usize {
    let m: &Material = &g.buf.materials[prim_material(g, hit) as usize];
    let (kr, kt) = (V3::<R>::from_f32(m.kr), V3::<R>::from_f32(m.kt));
    let reflects = max2(max2(kr.x, kr.y), kr.z) > R::ZERO;
    let transmits = max2(max2(kt.x, kt.y), kt.z) > R::ZERO;
    if !reflects && !transmits {
        return sp;
    }
    let p = ray.origin + ray.dir * hit.t;
    let mut n = prim_normal(g, hit, p);
    let entering = !(n.dot(ray.dir) > R::ZERO);
    if !entering {
        n = -n;
    }
    let sh = shading_at(g, hit, p, n);
    let d = ray.dir.normalize();
    let cos_i = max0(-d.dot(sh.n));
    let ior = R::from_f32(m.ior);
    let eta = if entering { ior } else { R::ONE / ior };
    let sin2_t = max0(R::ONE - cos_i * cos_i) / (eta * eta);
    let tir = transmits && sin2_t >= R::ONE;
    let (mut wr, mut wt) = (kr, kt);
    if m.fresnel != 0 {
        let f = fresnel_dielectric(cos_i, eta, sin2_t);
        wr = kr * f;
        wt = kt * (R::ONE - f);
    }
    if tir {
        wr = wr + wt;
    }
    let mut top = sp;
    let w_t = flush3(weight * wt);
    if transmits && !tir && worth_tracing(g, w_t) {
        let cos_t = max0(R::ONE - sin2_t).sqrt();
        let t = keep_side(
            d / V3::splat(eta) + sh.n * (cos_i / eta - cos_t),
            n,
            -R::ONE,
        );
        stack[top] = Pending {
            origin: spawn_origin(ray.origin, p, -n),
            depth: depth + 1,
            dir: t,
            weight: w_t,
        };
        g.count.pushed(RayKind::Refracted);
        top += 1;
    }
    let w_r = flush3(weight * wr);
    if (reflects || tir) && worth_tracing(g, w_r) {
        let r = keep_side(d + sh.n * ((R::ONE + R::ONE) * cos_i), n, R::ONE);
        stack[top] = Pending {
            origin: spawn_origin(ray.origin, sh.p, n),
            depth: depth + 1,
            dir: r,
            weight: w_r,
        };
        g.count.pushed(RayKind::Reflected);
        top += 1;
    }
    top
}

/// WGSL `secondary`: the colour at the first hit `hit` of `ray` whose local shading is
/// `local`, with every reflection and refraction below it, summed in the shader's order
/// and clamped to [0, 1].
pub fn secondary<R: Real, C: Count>(
    g: &Globals<R, C>,
    ray: Ray<R>,
    hit: &Hit<R>,
    local: V3<R>,
) -> V3<R> {
    let zero = Pending {
        origin: V3::splat(R::ZERO),
        depth: 0,
        dir: V3::splat(R::ZERO),
        weight: V3::splat(R::ZERO),
    };
    let mut stack = [zero; WHITTED_STACK];
    let mut sp = 0;
    if g.buf.params.max_depth > 0 {
        sp = push_children(g, &mut stack, 0, ray, hit, V3::splat(R::ONE), 0);
    }
    let color = walk(g, &mut stack, sp, local);
    V3::new(clamp01(color.x), clamp01(color.y), clamp01(color.z))
}

/// The loop of WGSL `secondary`: pops the rays on `stack` below `sp` until none is left,
/// adding each one's weighted colour to `color` and pushing its own rays; the sum, not yet
/// clamped. (Apart so that the packet tracer can finish a lane's walk here.)
pub fn walk<R: Real, C: Count>(
    g: &Globals<R, C>,
    stack: &mut [Pending<R>; WHITTED_STACK],
    mut sp: usize,
    mut color: V3<R>,
) -> V3<R> {
    let background = V3::<R>::from_f32(g.buf.params.background);
    while sp != 0 {
        sp -= 1;
        let next = stack[sp];
        let r = Ray {
            origin: next.origin,
            dir: next.dir,
        };
        g.count.popped();
        let h = closest_hit(g, r, R::ZERO, R::INFINITY);
        if h.prim == PRIM_NONE {
            color = color + flush3(next.weight * background);
            continue;
        }
        color = color + flush3(next.weight * shade(g, r, &h));
        if next.depth < g.buf.params.max_depth {
            sp = push_children(g, stack, sp, r, &h, next.weight, next.depth);
        }
    }
    color
}

#[cfg(test)]
mod tests {
    use super::fresnel_dielectric;

    fn f(cos_i: f64, eta: f64) -> f64 {
        let sin2_t = (1.0 - cos_i * cos_i).max(0.0) / (eta * eta);
        fresnel_dielectric(cos_i, eta, sin2_t)
    }

    /// Mitsuba's `test_fresnel` values: 0.04 at normal incidence on glass; total internal
    /// reflection from inside at 45° gives exactly 1; η = 1 gives exactly 0 at every angle,
    /// with no NaN. The twin: just inside the critical angle the reflectance is below 1.
    #[test]
    fn fresnel_values() {
        assert!((f(1.0, 1.5) - 0.04).abs() < 1e-15, "{}", f(1.0, 1.5));
        let f32_normal = fresnel_dielectric(1.0f32, 1.5, 0.0);
        assert!((f32_normal - 0.04).abs() < 1e-7, "{f32_normal}");
        let c45 = std::f64::consts::FRAC_1_SQRT_2;
        assert_eq!(f(c45, 1.0 / 1.5), 1.0);
        for k in 0..=100 {
            let c = k as f64 / 100.0;
            assert_eq!(f(c, 1.0), 0.0, "cos {c}");
            assert_eq!(
                fresnel_dielectric(c as f32, 1.0, (1.0 - (c * c) as f32).max(0.0)),
                0.0
            );
        }
        // The critical angle from inside glass: sin θc = 1/1.5.
        let critical = (1.0f64 - 1.0 / 2.25).sqrt();
        assert!(f(critical + 1e-6, 1.0 / 1.5) < 1.0);
        assert_eq!(f(critical - 1e-6, 1.0 / 1.5), 1.0);
        // Grazing from outside: everything is reflected, and no NaN.
        assert!((f(0.0, 1.5) - 1.0).abs() < 1e-12);
    }
}
