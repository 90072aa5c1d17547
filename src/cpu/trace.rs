//! The CPU mirror of `shaders/trace.wgsl`: rays through the scene. The camera, the
//! searches for the nearest hit ([`closest_hit`]) and for a blocker ([`occluded`]), over
//! every primitive or through the BVH, shading, and one pixel's samples (see
//! [`super::common`] for the mirror's rules).

// `!(x > 0)` is not `x <= 0` for NaN; the shader writes it so, on purpose, and so does its mirror.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

pub use super::common::{BVH_STACK, Camera, Globals, Hit, Ray};
use super::common::{clamp01, flush, flush3, max0, max2};
use super::count::{Count, RayKind};
use super::instance::{closest_hit_top, occluded_top};
use super::prims::{
    hit_prim, hit_sphere, hit_triangle, prim_material, prim_normal, ray_shear, shading_at,
};
use crate::buffers::{
    BvhNode, HitOut, Light, MODEL_AMBIENT, MODEL_PHONG, Material, PRIM_NONE, RayIn, TRIANGLE_BIT,
};
use crate::shared::layout::{LIGHT_DIRECTIONAL, LIGHT_SPOT};
use crate::shared::real::{Real, V3};

// ---- the camera ------------------------------------------------------------------------

/// WGSL `camera_ray`: the primary ray through the point (dx, dy) of pixel (i, j), each in
/// [0, 1) from its top-left corner (the centre is (0.5, 0.5)).
pub fn camera_ray<R: Real, C: Count>(g: &Globals<R, C>, i: u32, j: u32, dx: R, dy: R) -> Ray<R> {
    let c = &g.cam;
    let two = R::ONE + R::ONE;
    let x = ((R::from_u32(i) + dx) / R::from_u32(c.width) * two - R::ONE) * c.tan_half * c.aspect;
    let y = (R::ONE - (R::from_u32(j) + dy) / R::from_u32(c.height) * two) * c.tan_half;
    let dir = (c.forward + c.right * x + c.up * y).normalize();
    Ray { origin: c.eye, dir }
}

// ---- spheres -----------------------------------------------------------------------------

// ---- triangles -------------------------------------------------------------------------

// ---- the scene ---------------------------------------------------------------------------

/// WGSL `closest_sphere`: `best`, or the nearest sphere hit in (t_min, best.t); the first
/// sphere wins ties.
pub fn closest_sphere<R: Real, C: Count>(
    g: &Globals<R, C>,
    ray: Ray<R>,
    t_min: R,
    best: Hit<R>,
) -> Hit<R> {
    let mut b = best;
    for k in 0..g.buf.params.n_spheres {
        g.count.prim(k);
        let t = hit_sphere(ray, &g.buf.spheres[k as usize], t_min, b.t);
        if t < b.t {
            b = Hit {
                t,
                prim: k,
                u: R::ZERO,
                v: R::ZERO,
                inst: 0,
            };
        }
    }
    b
}

/// WGSL `sphere_blocks`: whether a sphere other than `skip` lies on the ray in (t_min,
/// t_max); stops at the first hit.
pub fn sphere_blocks<R: Real, C: Count>(
    g: &Globals<R, C>,
    ray: Ray<R>,
    t_min: R,
    t_max: R,
    skip: u32,
) -> bool {
    for k in 0..g.buf.params.n_spheres {
        g.count.prim(k);
        if k != skip && hit_sphere(ray, &g.buf.spheres[k as usize], t_min, t_max) < t_max {
            return true;
        }
    }
    false
}

/// WGSL `closest_hit_all`: the nearest hit in (t_min, t_max), spheres first; the first
/// primitive wins ties.
pub fn closest_hit_all<R: Real, C: Count>(
    g: &Globals<R, C>,
    ray: Ray<R>,
    t_min: R,
    t_max: R,
) -> Hit<R> {
    let mut best = Hit {
        t: t_max,
        prim: PRIM_NONE,
        u: R::ZERO,
        v: R::ZERO,
        inst: 0,
    };
    if g.spec.has_spheres {
        best = closest_sphere(g, ray, t_min, best);
    }
    if g.spec.has_triangles {
        let sh = ray_shear(g, ray.dir);
        for k in 0..g.buf.params.n_triangles {
            g.count.prim(k | TRIANGLE_BIT);
            let h = hit_triangle(g, ray, sh, &g.buf.triangles[k as usize], t_min, best.t);
            if h.0 < best.t {
                best = Hit {
                    t: h.0,
                    prim: k | TRIANGLE_BIT,
                    u: h.1,
                    v: h.2,
                    inst: 0,
                };
            }
        }
    }
    best
}

/// WGSL `occluded_all`: whether anything but `skip` lies on the ray, testing every primitive.
pub fn occluded_all<R: Real, C: Count>(
    g: &Globals<R, C>,
    ray: Ray<R>,
    t_min: R,
    t_max: R,
    skip: u32,
) -> bool {
    if g.spec.has_spheres && sphere_blocks(g, ray, t_min, t_max, skip) {
        return true;
    }
    if g.spec.has_triangles {
        let sh = ray_shear(g, ray.dir);
        for k in 0..g.buf.params.n_triangles {
            g.count.prim(k | TRIANGLE_BIT);
            if (k | TRIANGLE_BIT) != skip
                && hit_triangle(g, ray, sh, &g.buf.triangles[k as usize], t_min, t_max).0 < t_max
            {
                return true;
            }
        }
    }
    false
}

// ---- the BVH -----------------------------------------------------------------------------

/// WGSL `box_interval`: the part (t0, t1) of (t_min, t_max) inside the node's box, by the
/// conservative slab test; hit when t0 <= t1. The far end is the nearest exit distance
/// (NaN slabs passed over) widened by `BOX_SLACK` of itself: x + |x|·`BOX_SLACK` never
/// decreases as x grows (`slack_is_monotone`), so this is each exit widened, then the
/// nearest taken, in one widening instead of three. An exit at -∞ (a zero direction
/// component, the box wholly on one side of the ray's plane) is kept as -∞, so the box is
/// missed: widened, it was NaN and kept the box, and one shadow ray of the 1M-triangle
/// heightfield, parallel to z = 5 on it, visited 213,264 nodes instead of about 20
/// (`docs/bench/traversal.md`).
pub fn box_interval<R: Real>(
    node: &BvhNode,
    origin: V3<R>,
    inv_dir: V3<R>,
    t_min: R,
    t_max: R,
) -> (R, R) {
    let t_lo = (V3::from_f32(node.lo) - origin) * inv_dir;
    let t_hi = (V3::from_f32(node.hi) - origin) * inv_dir;
    let swap = (t_hi.x < t_lo.x, t_hi.y < t_lo.y, t_hi.z < t_lo.z);
    let near = V3::new(
        select(t_lo.x, t_hi.x, swap.0),
        select(t_lo.y, t_hi.y, swap.1),
        select(t_lo.z, t_hi.z, swap.2),
    );
    let far = V3::new(
        select(t_hi.x, t_lo.x, swap.0),
        select(t_hi.y, t_lo.y, swap.1),
        select(t_hi.z, t_lo.z, swap.2),
    );
    let mut t0 = t_min;
    t0 = select(t0, near.x, near.x > t0);
    t0 = select(t0, near.y, near.y > t0);
    t0 = select(t0, near.z, near.z > t0);
    let mut f = R::INFINITY;
    f = select(f, far.x, far.x < f);
    f = select(f, far.y, far.y < f);
    f = select(f, far.z, far.z < f);
    // An exit at -∞ (a slab the ray runs parallel to, outside it) is raised to -INFINITY,
    // the largest finite f32 below 0, which widens to a negative number: a miss. Widened
    // itself it would be NaN, which the select below would pass over, keeping the box.
    f = max2(f, -R::INFINITY);
    f = f + f.abs() * R::BOX_SLACK;
    let t1 = select(t_max, f, f < t_max);
    (t0, t1)
}

/// WGSL `select(f, t, c)`: `t` when `c`, else `f`.
pub fn select<R: Real>(f: R, t: R, c: bool) -> R {
    if c { t } else { f }
}

/// WGSL `tie_bound`: one ULP past `best.t` once there is a hit, so ties are seen.
pub fn tie_bound<R: Real>(best: &Hit<R>) -> R {
    if best.prim != PRIM_NONE && best.t > R::ZERO && best.t <= R::INFINITY {
        return best.t.bits_plus_one();
    }
    best.t
}

/// WGSL `nearer`: a smaller t, or the same t and a lower id.
pub fn nearer<R: Real>(t: R, id: u32, best: &Hit<R>) -> bool {
    t < best.t || (t == best.t && id < best.prim && best.prim != PRIM_NONE)
}

/// WGSL `closest_hit_bvh`: depth first, both children's boxes tested, the nearer entered
/// first; fixed stack, one step per node.
pub fn closest_hit_bvh<R: Real, C: Count>(
    g: &Globals<R, C>,
    ray: Ray<R>,
    t_min: R,
    t_max: R,
) -> Hit<R> {
    let mut best = Hit {
        t: t_max,
        prim: PRIM_NONE,
        u: R::ZERO,
        v: R::ZERO,
        inst: 0,
    };
    let sh = ray_shear(g, ray.dir);
    let inv_dir = V3::splat(R::ONE) / ray.dir;
    let nodes = &g.buf.nodes;
    if g.buf.params.n_nodes == 0 {
        return best;
    }
    let root = box_interval(&nodes[0], ray.origin, inv_dir, t_min, t_max);
    g.count.nodes_read(1);
    if !(root.0 <= root.1) {
        return best;
    }
    let mut stack = [0u32; BVH_STACK];
    let mut sp = 0usize;
    let mut at = 0u32;
    for _step in 0..g.buf.params.n_nodes {
        let node = &nodes[at as usize];
        g.count.nodes_read(1);
        let count = node.count_axis >> 2;
        if count == 0 {
            g.count.interior();
            g.count.nodes_read(2);
            let bound = tie_bound(&best);
            let left = box_interval(&nodes[at as usize + 1], ray.origin, inv_dir, t_min, bound);
            let right = box_interval(
                &nodes[node.first as usize],
                ray.origin,
                inv_dir,
                t_min,
                bound,
            );
            let hit_left = left.0 <= left.1;
            let hit_right = right.0 <= right.1;
            if hit_left && hit_right {
                if right.0 < left.0 {
                    stack[sp] = at + 1;
                    at = node.first;
                } else {
                    stack[sp] = node.first;
                    at += 1;
                }
                sp += 1;
                g.count.stack(sp);
                continue;
            }
            if hit_left {
                at += 1;
                continue;
            }
            if hit_right {
                at = node.first;
                continue;
            }
        } else {
            g.count.leaf();
            for k in node.first..node.first + count {
                let id = g.buf.prim_ids[k as usize];
                g.count.prim(id);
                let h = hit_prim(g, ray, sh, id, t_min, tie_bound(&best));
                if nearer(h.0, id, &best) {
                    best = Hit {
                        t: h.0,
                        prim: id,
                        u: h.1,
                        v: h.2,
                        inst: 0,
                    };
                }
            }
        }
        if sp == 0 {
            break;
        }
        sp -= 1;
        at = stack[sp];
    }
    best
}

/// WGSL `occluded_bvh`: `occluded` through the BVH; stops at the first hit. Repeats
/// `closest_hit_bvh`'s loop as the shader does (see there why).
pub fn occluded_bvh<R: Real, C: Count>(
    g: &Globals<R, C>,
    ray: Ray<R>,
    t_min: R,
    t_max: R,
    skip: u32,
) -> bool {
    let sh = ray_shear(g, ray.dir);
    let inv_dir = V3::splat(R::ONE) / ray.dir;
    let nodes = &g.buf.nodes;
    if g.buf.params.n_nodes == 0 {
        return false;
    }
    let root = box_interval(&nodes[0], ray.origin, inv_dir, t_min, t_max);
    g.count.nodes_read(1);
    if !(root.0 <= root.1) {
        return false;
    }
    let mut stack = [0u32; BVH_STACK];
    let mut sp = 0usize;
    let mut at = 0u32;
    for _step in 0..g.buf.params.n_nodes {
        let node = &nodes[at as usize];
        g.count.nodes_read(1);
        let count = node.count_axis >> 2;
        if count == 0 {
            g.count.interior();
            g.count.nodes_read(2);
            let left = box_interval(&nodes[at as usize + 1], ray.origin, inv_dir, t_min, t_max);
            let right = box_interval(
                &nodes[node.first as usize],
                ray.origin,
                inv_dir,
                t_min,
                t_max,
            );
            let hit_left = left.0 <= left.1;
            let hit_right = right.0 <= right.1;
            if hit_left && hit_right {
                if right.0 < left.0 {
                    stack[sp] = at + 1;
                    at = node.first;
                } else {
                    stack[sp] = node.first;
                    at += 1;
                }
                sp += 1;
                g.count.stack(sp);
                continue;
            }
            if hit_left {
                at += 1;
                continue;
            }
            if hit_right {
                at = node.first;
                continue;
            }
        } else {
            g.count.leaf();
            for k in node.first..node.first + count {
                let id = g.buf.prim_ids[k as usize];
                g.count.prim(id);
                if id != skip && hit_prim(g, ray, sh, id, t_min, t_max).0 < t_max {
                    return true;
                }
            }
        }
        if sp == 0 {
            break;
        }
        sp -= 1;
        at = stack[sp];
    }
    false
}

/// WGSL `finite_bound`: +inf lowered to INFINITY, the intersection tests' miss value.
pub fn finite_bound<R: Real>(t_max: R) -> R {
    select(t_max, R::INFINITY, t_max > R::INFINITY)
}

/// WGSL `closest_hit`: the nearest hit in (t_min, t_max); of equal t, the lowest id.
pub fn closest_hit<R: Real, C: Count>(
    g: &Globals<R, C>,
    ray: Ray<R>,
    t_min: R,
    t_max: R,
) -> Hit<R> {
    let t_hi = finite_bound(t_max);
    g.count.begin(false);
    let hit = if g.spec.instances {
        closest_hit_top(g, ray, t_min, t_hi)
    } else if g.spec.use_bvh {
        closest_hit_bvh(g, ray, t_min, t_hi)
    } else {
        closest_hit_all(g, ray, t_min, t_hi)
    };
    g.count.end();
    hit
}

/// WGSL `occluded`: whether anything but primitive `skip` (of instance `skip_inst`) lies
/// on the ray in (t_min, t_max). A convex primitive cannot shadow a point of its own where
/// N·L > 0, so skipping the one that was hit loses no shadow.
pub fn occluded<R: Real, C: Count>(
    g: &Globals<R, C>,
    ray: Ray<R>,
    t_min: R,
    t_max: R,
    skip: u32,
    skip_inst: u32,
) -> bool {
    let t_hi = finite_bound(t_max);
    g.count.begin(true);
    let blocked = if g.spec.instances {
        occluded_top(g, ray, t_min, t_hi, skip, skip_inst)
    } else if g.spec.use_bvh {
        occluded_bvh(g, ray, t_min, t_hi, skip)
    } else {
        occluded_all(g, ray, t_min, t_hi, skip)
    };
    g.count.end();
    blocked
}

// ---- shading -----------------------------------------------------------------------------

/// WGSL `phong_power`: `base^n`, by squaring for an integer exponent, else `pow_det` (in
/// f64, the reference, libm's `pow`); 0 where the power is subnormal.
///
/// WGSL guards the first branch with `POWERS` as well, which is off only where no material
/// has `n_int < 0`: the same result, and a kernel without `pow_det`.
pub fn phong_power<R: Real>(base: R, m: &Material) -> R {
    if m.n_int < 0 {
        if R::MIRROR {
            return flush(R::from_f32(super::exact::pow_det(base.to_f32(), m.n)));
        }
        return flush(base.powf(R::from_f32(m.n)));
    }
    let mut result = R::ONE;
    let mut b = base;
    let mut e = m.n_int as u32;
    for _ in 0..32 {
        if e == 0 {
            break;
        }
        if (e & 1) != 0 {
            result = result * b;
        }
        b = b * b;
        e >>= 1;
    }
    flush(result)
}

/// WGSL `shadow_origin`: the offset origin of a shadow ray from `p` with facing normal `n`.
pub fn shadow_origin<R: Real>(p: V3<R>, n: V3<R>) -> V3<R> {
    let scale = max2(max2(p.x.abs(), p.y.abs()), max2(p.z.abs(), R::ONE));
    let sixty_four = R::from_u32(64);
    p + n * (scale * R::EPSILON * sixty_four)
}

/// WGSL `spot_factor`: a spot light's weight at cosine `c` from its axis, 0 at or beyond
/// `cos_outer`, 1 from `cos_inner` in, the smoothstep s²(3 − 2s) between.
pub fn spot_factor<R: Real>(light: &Light, c: R) -> R {
    let outer = R::from_f32(light.cos_outer);
    let inner = R::from_f32(light.cos_inner);
    if !(c > outer) {
        return R::ZERO;
    }
    if c >= inner {
        return R::ONE;
    }
    let s = (c - outer) / (inner - outer);
    let two = R::ONE + R::ONE;
    s * s * (two + R::ONE - two * s)
}

/// WGSL `shade`: the Phong model (docs/scene-format.md) at a hit, each term only where the model has it.
pub fn shade<R: Real, C: Count>(g: &Globals<R, C>, ray: Ray<R>, hit: &Hit<R>) -> V3<R> {
    let m: &Material = &g.buf.materials[prim_material(g, hit) as usize];
    let a = super::texture::albedo(g, hit, m);
    let p = ray.origin + ray.dir * hit.t;
    let mut n = prim_normal(g, hit, p);
    if n.dot(ray.dir) > R::ZERO {
        n = -n;
    }
    let sh = shading_at(g, hit, p, n);
    let mut color = flush3(V3::from_f32(g.buf.params.ambient) * a.ka);
    if g.spec.uses_diffuse && m.model != MODEL_AMBIENT {
        // The reversed ray, as the shader has it (see there why not `origin - p`).
        let v = (-ray.dir).normalize();
        for k in 0..g.buf.params.n_lights {
            let light: &Light = &g.buf.lights[k as usize];
            let position = V3::from_f32(light.position);
            let light_color = V3::from_f32(light.color);
            let mut to_light = position - p;
            if g.spec.light_kinds && light.kind == LIGHT_DIRECTIONAL {
                to_light = -V3::from_f32(light.direction);
            }
            let l = to_light.normalize();
            let ndl = sh.n.dot(l);
            if !(ndl > R::ZERO) {
                continue;
            }
            let mut ip = light_color;
            if g.spec.light_kinds && light.kind == LIGHT_SPOT {
                let s = spot_factor(light, -l.dot(V3::from_f32(light.direction)));
                if !(s > R::ZERO) {
                    continue;
                }
                ip = ip * s;
            }
            if g.spec.shadows {
                let o = shadow_origin(sh.p, n);
                if g.spec.light_kinds && light.kind == LIGHT_DIRECTIONAL {
                    // Towards the light without end.
                    if occluded(
                        g,
                        Ray { origin: o, dir: l },
                        R::ZERO,
                        R::INFINITY,
                        hit.prim,
                        hit.inst,
                    ) {
                        continue;
                    }
                } else {
                    let d = position - o;
                    if occluded(
                        g,
                        Ray { origin: o, dir: d },
                        R::ZERO,
                        R::ONE,
                        hit.prim,
                        hit.inst,
                    ) {
                        continue;
                    }
                }
            }
            color = color + flush3(ip * a.kd * ndl);
            if g.spec.uses_phong && m.model == MODEL_PHONG {
                let two = R::ONE + R::ONE;
                let r = sh.n * (two * ndl) - l;
                let rv = max0(r.dot(v));
                color = color + flush3(ip * V3::from_f32(m.ks) * phong_power(rv, m));
            }
        }
    }
    V3::new(clamp01(color.x), clamp01(color.y), clamp01(color.z))
}

/// WGSL `trace_sample`: the colour through the point (dx, dy) of pixel (i, j) and, in w,
/// the hit distance (−1 on a miss).
pub fn trace_sample<R: Real, C: Count>(g: &Globals<R, C>, i: u32, j: u32, dx: R, dy: R) -> [R; 4] {
    let ray = camera_ray(g, i, j, dx, dy);
    g.count.next_kind(RayKind::Camera);
    let hit = closest_hit(g, ray, R::ZERO, R::INFINITY);
    if hit.prim == PRIM_NONE {
        let bg = V3::<R>::from_f32(g.buf.params.background);
        return [bg.x, bg.y, bg.z, -R::ONE];
    }
    let local = shade(g, ray, &hit);
    if g.spec.whitted {
        let c = super::whitted::secondary(g, ray, &hit, local);
        return [c.x, c.y, c.z, hit.t];
    }
    [local.x, local.y, local.z, hit.t]
}

/// WGSL `sample_offset`: (s + 0.5) / n, the position of sample s of n along a
/// pixel side.
pub fn sample_offset<R: Real>(s: u32, n: u32) -> R {
    (R::from_u32(s) + R::ONE / (R::ONE + R::ONE)) / R::from_u32(n)
}

/// WGSL `trace_pixel`: the colour of pixel (i, j) and, in w, the hit distance (−1 on a
/// miss); with antialiasing the N×N samples, rows top to bottom, summed in that order and
/// divided by N², w the nearest hit's t.
pub fn trace_pixel<R: Real, C: Count>(g: &Globals<R, C>, i: u32, j: u32) -> [R; 4] {
    let half = R::ONE / (R::ONE + R::ONE);
    if !g.spec.antialias {
        return trace_sample(g, i, j, half, half);
    }
    let n = g.cam.samples;
    let mut sum = V3::splat(R::ZERO);
    let mut t_near = -R::ONE;
    for sy in 0..n {
        let dy = sample_offset::<R>(sy, n);
        for sx in 0..n {
            let dx = sample_offset::<R>(sx, n);
            let s = trace_sample(g, i, j, dx, dy);
            sum = sum + V3::new(s[0], s[1], s[2]);
            if s[3] >= R::ZERO && (t_near < R::ZERO || s[3] < t_near) {
                t_near = s[3];
            }
        }
    }
    let c = flush3(sum / V3::splat(R::from_u32(n * n)));
    [c.x, c.y, c.z, t_near]
}

// ---- entry points ------------------------------------------------------------------------

/// WGSL `query` for one ray.
pub fn query<R: Real, C: Count>(g: &Globals<R, C>, r: &RayIn) -> HitOut {
    let ray = Ray {
        origin: V3::from_f32(r.origin),
        dir: V3::from_f32(r.dir),
    };
    let h = closest_hit(g, ray, R::from_f32(r.t_min), R::from_f32(r.t_max));
    HitOut {
        t: h.t.to_f32(),
        prim: h.prim,
        u: h.u.to_f32(),
        v: h.v.to_f32(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A ray with a zero direction component misses every box wholly on one side of its
    /// plane (an exit at -∞ stays -∞) and still hits a box across it, in f32 and f64. The
    /// heightfield's shadow ray that visited 213,264 nodes was such a ray (z = 5 exactly).
    #[test]
    fn a_parallel_ray_misses_boxes_beside_its_plane() {
        let node = |lo: [f32; 3], hi: [f32; 3]| BvhNode {
            lo,
            hi,
            ..BvhNode::default()
        };
        let o = V3::new(9.25f32, -0.09, 5.0);
        let d = V3::new(-4.25f32, 15.09, 0.0);
        let inv = V3::splat(1.0f32) / d;
        assert!(inv.z.is_infinite());
        let below = node([4.96, -0.04, -20.0], [5.03, -0.02, -19.95]);
        let above = node([4.96, -0.04, 19.0], [5.03, -0.02, 19.05]);
        let across = node([9.2, -0.1, 4.9], [9.3, 0.0, 5.1]);
        let hit = |n: &BvhNode| {
            let (t0, t1) = box_interval(n, o, inv, 0.0, 1.0);
            let o64 = V3::new(o.x as f64, o.y as f64, o.z as f64);
            let inv64 = V3::splat(1.0f64) / V3::new(d.x as f64, d.y as f64, d.z as f64);
            let (u0, u1) = box_interval(n, o64, inv64, 0.0, 1.0);
            assert_eq!(t0 <= t1, u0 <= u1, "f32 and f64 agree on {n:?}");
            t0 <= t1
        };
        assert!(!hit(&below), "a box wholly below z = 5");
        assert!(!hit(&above), "a box wholly above z = 5");
        // The twin: the box the ray starts in is hit.
        assert!(hit(&across));
    }

    /// The widening `box_interval` gives the nearest exit.
    fn widen(x: f32) -> f32 {
        x + x.abs() * <f32 as Real>::BOX_SLACK
    }

    /// The first (x, next float up) where `g` decreases, over every finite f32 of
    /// magnitude below 2^-100 or within 4096 floats of a power of two, and every 997th
    /// float elsewhere, both signs.
    fn first_decrease(g: impl Fn(f32) -> f32) -> Option<(f32, f32)> {
        let top = f32::MAX.to_bits();
        let dense = 2.0f32.powi(-100).to_bits();
        let mut bits = 0u32;
        while bits < top {
            let near_power = (bits & 0x7F_FFFF) < 4096 || (bits & 0x7F_FFFF) > 0x7F_FFFF - 4096;
            let step = if bits < dense || near_power { 1 } else { 997 };
            for b in [bits, bits | 0x8000_0000] {
                let x = f32::from_bits(b);
                // x and the float next up from it (toward +∞).
                let up = if b & 0x8000_0000 != 0 {
                    f32::from_bits(b - 1)
                } else {
                    f32::from_bits(b + 1)
                };
                let (x, up) = if b == 0x8000_0000 {
                    (-0.0, f32::from_bits(1))
                } else {
                    (x, up)
                };
                if up.is_finite() && g(up) < g(x) {
                    return Some((x, up));
                }
            }
            bits += step;
        }
        None
    }

    /// `box_interval` widens only the nearest exit, which is each exit widened and then
    /// the nearest only if the widening never decreases: checked here over every float
    /// near zero (where x·BOX_SLACK rounds) and near each power of two, and a stride
    /// elsewhere (every finite f32 was checked once).
    #[test]
    fn slack_is_monotone() {
        assert_eq!(first_decrease(widen), None);
    }

    /// The twin: a widening that does decrease (x + 4|x| falls for x < 0) is caught.
    #[test]
    fn slack_check_can_fail() {
        assert!(first_decrease(|x| x + x.abs() * 4.0).is_some());
    }

    /// The first case where `t1_of(far, t_max)` differs from three widenings (each exit
    /// widened, then the nearest taken): the same bits wherever no exit is -∞; where one
    /// is, a miss (t1 below 0, so below every t0), which the three widenings were not
    /// (-∞ widened is NaN, passed over). Over 2M triples of special and random exits.
    fn first_widening_mismatch(t1_of: impl Fn([f32; 3], f32) -> f32) -> Option<String> {
        let specials = [
            0.0f32,
            -0.0,
            1e-40,
            -1e-40,
            2.0f32.powi(-110),
            1.0,
            -1.0,
            3.5,
            1e30,
            f32::MAX,
            -f32::MAX,
            f32::INFINITY,
            f32::NEG_INFINITY,
            f32::NAN,
        ];
        let mut seed = 0x5eed_u64;
        let mut next = || {
            seed = seed
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            let r = (seed >> 40) as u32;
            if r.is_multiple_of(4) {
                specials[(r as usize / 4) % specials.len()]
            } else {
                f32::from_bits((seed >> 8) as u32)
            }
        };
        let old = |far: [f32; 3], t_max: f32| {
            let mut t1 = t_max;
            for f in far.map(widen) {
                t1 = select(t1, f, f < t1);
            }
            t1
        };
        for case in 0..2_000_000 {
            let far = [next(), next(), next()];
            let t_max = [1.0, 1e3, f32::MAX, 0.0][case % 4];
            let (was, new) = (old(far, t_max), t1_of(far, t_max));
            let agrees = if far.contains(&f32::NEG_INFINITY) {
                new < 0.0
            } else {
                new.to_bits() == was.to_bits()
            };
            if !agrees {
                return Some(format!("{far:?} t_max {t_max}: {was} -> {new}"));
            }
        }
        None
    }

    /// `box_interval` itself, on a box whose exits are `far` exactly: low corner at -∞
    /// (every entry -∞, no slab swapped), high corner `far`, origin 0, inverse direction 1.
    fn box_t1(far: [f32; 3], t_max: f32) -> f32 {
        let node = BvhNode {
            lo: [f32::NEG_INFINITY; 3],
            first: 0,
            hi: far,
            count_axis: 0,
        };
        let one = V3::new(1.0f32, 1.0, 1.0);
        box_interval(&node, V3::new(0.0, 0.0, 0.0), one, 0.0, t_max).1
    }

    /// `box_interval`'s one widening equals the three it replaced (see
    /// `first_widening_mismatch`).
    #[test]
    fn one_widening_equals_three() {
        assert_eq!(first_widening_mismatch(box_t1), None);
    }

    /// The twin: a t1 one float off, only where it is finite and positive, is caught.
    #[test]
    fn widening_check_can_fail() {
        let off = |far: [f32; 3], t_max: f32| {
            let t1 = box_t1(far, t_max);
            if t1 > 0.0 && t1 < f32::MAX {
                t1.next_up()
            } else {
                t1
            }
        };
        assert!(first_widening_mismatch(off).is_some());
    }
}
