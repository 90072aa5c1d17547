//! The packet twins of `prims.rs`: the three triangle tests and the sphere test as lane
//! loops (op for op the mirror's), and one primitive against the packet (`prim_lanes`).
//! Lane loops rather than the mirror's functions a lane at a time: what they bought is in
//! `docs/bench/cpu-packets.md`.

// Lane loops index several arrays in step, `for l in 0..LANES`, the form LLVM vectorises.
#![allow(clippy::needless_range_loop)]

use super::common::{LANES, Lanes, Mask, Origins, mask_of};
use crate::buffers::{
    INFINITY, NAIVE_MIN_SIN2, Sphere, TRIANGLE_BIT, TRIANGLE_MOLLER_TRUMBORE, TRIANGLE_WATERTIGHT,
    Triangle,
};
use crate::cpu::common::{Globals, Hit, Ray, in_interval, sign_nonneg};
use crate::cpu::prims::{Shear, edge_function, hit_prim};
use crate::shared::real::V3;

/// The lanes' `Shear`s as structure of arrays.
pub(super) struct ShearLanes {
    pub(super) kx: [u32; LANES],
    pub(super) ky: [u32; LANES],
    pub(super) kz: [u32; LANES],
    pub(super) sx: [f32; LANES],
    pub(super) sy: [f32; LANES],
    pub(super) sz: [f32; LANES],
    /// (kx, ky, kz) when every lane has the same (a coherent packet: most of them).
    pub(super) uniform: Option<[u32; 3]>,
}

/// `ray_shear` of every lane: `make_shear` lane by lane when `watertight` (the same
/// comparisons, the same one division), else the identity `ray_shear` gives.
#[inline(always)]
pub(super) fn shear_lanes(dir: &[[f32; LANES]; 3], watertight: bool) -> ShearLanes {
    let mut sh = ShearLanes {
        kx: [0; LANES],
        ky: [1; LANES],
        kz: [2; LANES],
        sx: [0.0; LANES],
        sy: [0.0; LANES],
        sz: [1.0; LANES],
        uniform: Some([0, 1, 2]),
    };
    if !watertight {
        return sh;
    }
    for l in 0..LANES {
        let d = [dir[0][l], dir[1][l], dir[2][l]];
        let ad = [d[0].abs(), d[1].abs(), d[2].abs()];
        let mut kz = if ad[1] > ad[0] { 1 } else { 0 };
        if ad[2] > pick(&ad, kz) {
            kz = 2;
        }
        let mut kx = (kz + 1) % 3;
        let mut ky = (kx + 1) % 3;
        if pick(&d, kz) < 0.0 {
            std::mem::swap(&mut kx, &mut ky);
        }
        let sz = 1.0 / pick(&d, kz);
        sh.kx[l] = kx;
        sh.ky[l] = ky;
        sh.kz[l] = kz;
        sh.sx[l] = pick(&d, kx) * sz;
        sh.sy[l] = pick(&d, ky) * sz;
        sh.sz[l] = sz;
    }
    let mut same = [false; LANES];
    for l in 0..LANES {
        // `&`, not `&&`: no branch a lane, so that the loop vectorises.
        same[l] = (sh.kx[l] == sh.kx[0]) & (sh.ky[l] == sh.ky[0]) & (sh.kz[l] == sh.kz[0]);
    }
    sh.uniform = (mask_of(&same) == Mask::MAX).then_some([sh.kx[0], sh.ky[0], sh.kz[0]]);
    sh
}

impl ShearLanes {
    /// Lane l's `Shear`.
    #[inline(always)]
    pub(super) fn lane(&self, l: usize) -> Shear<f32> {
        Shear {
            kx: self.kx[l],
            ky: self.ky[l],
            kz: self.kz[l],
            sx: self.sx[l],
            sy: self.sy[l],
            sz: self.sz[l],
        }
    }
}

/// Each lane's (t, u, v), t = INFINITY on a miss.
pub(super) struct TriLanes {
    pub(super) t: [f32; LANES],
    pub(super) u: [f32; LANES],
    pub(super) v: [f32; LANES],
}

impl TriLanes {
    /// Every lane a miss: t = INFINITY, u = v = 0.
    pub(super) const MISS: TriLanes = TriLanes {
        t: [INFINITY; LANES],
        u: [0.0; LANES],
        v: [0.0; LANES],
    };

    /// Lane l's result: (t, u, v) where `hit`, else the miss (a select each, so the lane
    /// loops that call it vectorise).
    #[inline(always)]
    fn keep(&mut self, l: usize, hit: bool, t: f32, u: f32, v: f32) {
        self.t[l] = if hit { t } else { INFINITY };
        self.u[l] = if hit { u } else { 0.0 };
        self.v[l] = if hit { v } else { 0.0 };
    }
}

/// `V3::get`: component k of (x, y, z), as selects so that a lane loop vectorises.
#[inline(always)]
pub(super) fn pick(v: &[f32; 3], k: u32) -> f32 {
    if k == 0 {
        v[0]
    } else if k == 1 {
        v[1]
    } else {
        v[2]
    }
}

/// The mirror's `hit_prim` for one lane, out of line: the packets call it only where a
/// triangle is not in hand (a scene whose triangles are all tested one by one, never in a
/// render's BVH), and a call marked cold keeps the lane loops' registers as they are.
#[cold]
#[inline(never)]
pub(super) fn hit_prim_lane(
    g: &Globals<f32>,
    ray: Ray<f32>,
    sh: crate::cpu::prims::Shear<f32>,
    id: u32,
    t_min: f32,
    t_max: f32,
) -> (f32, f32, f32) {
    hit_prim(g, ray, sh, id, t_min, t_max)
}

/// The sheared vertices (ax, ay, bx, by, cx, cy) of `hit_triangle_watertight` for lane l,
/// from the vertices relative to the origin.
#[inline(always)]
pub(super) fn sheared(
    a: &[f32; 3],
    b: &[f32; 3],
    c: &[f32; 3],
    sh: &ShearLanes,
    l: usize,
) -> [f32; 6] {
    let (kx, ky, kz) = (sh.kx[l], sh.ky[l], sh.kz[l]);
    [
        pick(a, kx) - sh.sx[l] * pick(a, kz),
        pick(a, ky) - sh.sy[l] * pick(a, kz),
        pick(b, kx) - sh.sx[l] * pick(b, kz),
        pick(b, ky) - sh.sy[l] * pick(b, kz),
        pick(c, kx) - sh.sx[l] * pick(c, kz),
        pick(c, ky) - sh.sy[l] * pick(c, kz),
    ]
}

/// `hit_triangle_watertight` of one triangle for every lane, with lane l's `t_max` =
/// `t_max[l]`: the same operations in the same order, lane by lane. An edge function
/// that comes out exactly 0 is recomputed by `edge_function` itself (its exact
/// fallback), so that every lane's (t, u, v) is the scalar test's, bit for bit.
#[inline(always)]
pub(super) fn watertight_lanes<O: Origins>(
    tri: &Triangle,
    r: &Lanes<O>,
    sh: &ShearLanes,
    mask: Mask,
    t_min: f32,
    t_max: &[f32; LANES],
) -> TriLanes {
    let Edges { mut e, z, zero } = match sh.uniform {
        Some(k) => edges_uniform(tri, r, sh, k),
        None => edges_general(tri, r, sh),
    };
    let mut fix = zero & mask;
    while fix != 0 {
        let l = fix.trailing_zeros() as usize;
        fix &= fix - 1;
        let (a, b, c) = (
            r.origin.rel(&tri.a, l),
            r.origin.rel(&tri.b, l),
            r.origin.rel(&tri.c, l),
        );
        let [ax, ay, bx, by, cx, cy] = sheared(&a, &b, &c, sh, l);
        e[0][l] = edge_function(cx, by, cy, bx);
        e[1][l] = edge_function(ax, cy, ay, cx);
        e[2][l] = edge_function(bx, ay, by, ax);
    }
    let mut out = TriLanes::MISS;
    for l in 0..LANES {
        let (u, v, w) = (e[0][l], e[1][l], e[2][l]);
        let outside = (u < 0.0 || v < 0.0 || w < 0.0) && (u > 0.0 || v > 0.0 || w > 0.0);
        let det = u + v + w;
        #[allow(clippy::eq_op)]
        let degenerate = det == 0.0 || det != det;
        let az = sh.sz[l] * z[0][l];
        let bz = sh.sz[l] * z[1][l];
        let cz = sh.sz[l] * z[2][l];
        let t_scaled = u * az + v * bz + w * cz;
        let inv_det = 1.0 / det;
        let t = t_scaled * inv_det;
        let hit = !outside && !degenerate && in_interval(t, t_min, t_max[l]);
        out.keep(l, hit, t, v * inv_det, w * inv_det);
    }
    out
}

/// The first half of [`watertight_lanes`], per lane: the three edge functions (before the
/// exact fallback), each vertex's kz component relative to the origin (for t), and the
/// lanes with an edge function of exactly 0.
struct Edges {
    e: [[f32; LANES]; 3],
    z: [[f32; LANES]; 3],
    zero: Mask,
}

/// [`Edges`] with each lane's own axes, picked by selects.
#[inline(always)]
fn edges_general<O: Origins>(tri: &Triangle, r: &Lanes<O>, sh: &ShearLanes) -> Edges {
    let mut e = [[0.0f32; LANES]; 3];
    let mut z = [[0.0f32; LANES]; 3];
    let mut zero_flags = [false; LANES];
    for l in 0..LANES {
        let (a, b, c) = (
            r.origin.rel(&tri.a, l),
            r.origin.rel(&tri.b, l),
            r.origin.rel(&tri.c, l),
        );
        let [ax, ay, bx, by, cx, cy] = sheared(&a, &b, &c, sh, l);
        e[0][l] = cx * by - cy * bx;
        e[1][l] = ax * cy - ay * cx;
        e[2][l] = bx * ay - by * ax;
        zero_flags[l] = (e[0][l] == 0.0) | (e[1][l] == 0.0) | (e[2][l] == 0.0);
        let kz = sh.kz[l];
        z[0][l] = pick(&a, kz);
        z[1][l] = pick(&b, kz);
        z[2][l] = pick(&c, kz);
    }
    Edges {
        e,
        z,
        zero: mask_of(&zero_flags),
    }
}

/// [`Edges`] when every lane shares the axes `k` = (kx, ky, kz): the same operations on
/// the same values, with the triangle's and the origins' components picked once for the
/// packet instead of by selects in every lane (component kx of `tri.a - origin` is
/// `tri.a[kx] - origin[kx]`). The origins are permuted whole before the lane loop: read by
/// a run-time component index inside it, they keep the loop scalar
/// (`docs/bench/cpu-packets.md`).
#[inline(always)]
fn edges_uniform<O: Origins>(tri: &Triangle, r: &Lanes<O>, sh: &ShearLanes, k: [u32; 3]) -> Edges {
    let [kx, ky, kz] = k.map(|k| k as usize);
    let pa = [tri.a[kx], tri.a[ky], tri.a[kz]];
    let pb = [tri.b[kx], tri.b[ky], tri.b[kz]];
    let pc = [tri.c[kx], tri.c[ky], tri.c[kz]];
    let mut e = [[0.0f32; LANES]; 3];
    let mut z = [[0.0f32; LANES]; 3];
    let mut zero_flags = [false; LANES];
    let po = r.origin.permuted([kx, ky, kz]);
    for l in 0..LANES {
        let (a, b, c) = (po.rel(&pa, l), po.rel(&pb, l), po.rel(&pc, l));
        let (ax, ay) = (a[0] - sh.sx[l] * a[2], a[1] - sh.sy[l] * a[2]);
        let (bx, by) = (b[0] - sh.sx[l] * b[2], b[1] - sh.sy[l] * b[2]);
        let (cx, cy) = (c[0] - sh.sx[l] * c[2], c[1] - sh.sy[l] * c[2]);
        e[0][l] = cx * by - cy * bx;
        e[1][l] = ax * cy - ay * cx;
        e[2][l] = bx * ay - by * ax;
        zero_flags[l] = (e[0][l] == 0.0) | (e[1][l] == 0.0) | (e[2][l] == 0.0);
        z[0][l] = a[2];
        z[1][l] = b[2];
        z[2][l] = c[2];
    }
    Edges {
        e,
        z,
        zero: mask_of(&zero_flags),
    }
}

/// `hit_triangle_moller_trumbore` of one triangle for every lane, lane l against
/// `t_max[l]`: the same operations in the same order (the mirror's own `V3` arithmetic),
/// lane by lane, its early returns as selects (a lane that misses computes values it never
/// uses).
#[inline(always)]
pub(super) fn moller_trumbore_lanes<O: Origins>(
    tri: &Triangle,
    r: &Lanes<O>,
    t_min: f32,
    t_max: &[f32; LANES],
) -> TriLanes {
    let ta = V3::from_f32(tri.a);
    let e1 = V3::from_f32(tri.b) - ta;
    let e2 = V3::from_f32(tri.c) - ta;
    let mut out = TriLanes::MISS;
    for l in 0..LANES {
        let d = V3::new(r.dir[0][l], r.dir[1][l], r.dir[2][l]);
        let p = d.cross(e2);
        let det = e1.dot(p);
        #[allow(clippy::eq_op)]
        let degenerate = det == 0.0 || det != det;
        let inv_det = 1.0 / det;
        let s = V3::from_f32(r.origin.from(&tri.a, l));
        let su = s.dot(p);
        let u = su * inv_det;
        // The mirror's comparisons, as written there.
        #[allow(clippy::manual_range_contains)]
        let u_in = u >= 0.0 && u <= 1.0;
        let q = s.cross(e1);
        let sv = d.dot(q);
        let v = sv * inv_det;
        let v_in = v >= 0.0 && (su + sv) * inv_det <= 1.0;
        let t = e2.dot(q) * inv_det;
        let hit = !degenerate && u_in && v_in && in_interval(t, t_min, t_max[l]);
        out.keep(l, hit, t, u, v);
    }
    out
}

/// `hit_triangle_naive` of one triangle for every lane, lane l against `t_max[l]`: the
/// same operations in the same order (the mirror's own `V3` arithmetic), lane by lane;
/// what depends on the triangle alone (its plane, its sliver check) is computed once, and
/// the early returns are selects.
#[inline(always)]
pub(super) fn naive_lanes<O: Origins>(
    tri: &Triangle,
    r: &Lanes<O>,
    t_min: f32,
    t_max: &[f32; LANES],
) -> TriLanes {
    let mut out = TriLanes::MISS;
    let ta = V3::from_f32(tri.a);
    let e_ab = V3::from_f32(tri.b) - ta;
    let e_ac = V3::from_f32(tri.c) - ta;
    let cr = e_ac.cross(e_ab);
    // Negated so that a NaN is degenerate too, as in the mirror.
    #[allow(clippy::neg_cmp_op_on_partial_ord)]
    if !(cr.dot(cr) > 0.0) {
        return out; // degenerate: no plane
    }
    let n = cr.normalize();
    let d00 = e_ab.dot(e_ab);
    let d01 = e_ab.dot(e_ac);
    let d11 = e_ac.dot(e_ac);
    let denom = d00 * d11 - d01 * d01;
    #[allow(clippy::neg_cmp_op_on_partial_ord)]
    if !(denom > d00 * d11 * NAIVE_MIN_SIN2) {
        return out; // a sliver (buffers::NAIVE_MIN_SIN2)
    }
    let ta_n = ta.dot(n);
    for l in 0..LANES {
        let d = V3::new(r.dir[0][l], r.dir[1][l], r.dir[2][l]);
        let o = V3::from_f32(r.origin.at(l));
        let dn = d.dot(n);
        let t = (ta_n - o.dot(n)) / dn;
        let e_ap = (o + d * t) - ta;
        let d20 = e_ap.dot(e_ab);
        let d21 = e_ap.dot(e_ac);
        let u = (d11 * d20 - d01 * d21) / denom;
        let v = (d00 * d21 - d01 * d20) / denom;
        let hit =
            dn != 0.0 && in_interval(t, t_min, t_max[l]) && u >= 0.0 && v >= 0.0 && u + v <= 1.0;
        out.keep(l, hit, t, u, v);
    }
    out
}

/// The scene's triangle test (`hit_triangle`) of one triangle for every lane in `mask`,
/// lane l against `t_max[l]`, as lane loops.
#[inline(always)]
pub(super) fn triangle_lanes<O: Origins>(
    g: &Globals<f32>,
    tri: &Triangle,
    r: &Lanes<O>,
    sh: &ShearLanes,
    mask: Mask,
    t_min: f32,
    t_max: &[f32; LANES],
) -> TriLanes {
    match g.spec.triangle_algo {
        TRIANGLE_WATERTIGHT => watertight_lanes(tri, r, sh, mask, t_min, t_max),
        TRIANGLE_MOLLER_TRUMBORE => moller_trumbore_lanes(tri, r, t_min, t_max),
        _ => naive_lanes(tri, r, t_min, t_max),
    }
}

/// How far past the radius a ray must pass, relative to `radius + |f|₁`, for
/// [`sphere_lanes`] to call it a miss without the test (see there).
const CULL_SLACK: f32 = 1.0 / 1024.0;

/// `hit_sphere` of `s` for every lane, lane l against `t_max[l]` (INFINITY on a miss): the
/// same operations in the same order, lane by lane, its early return on `disc` as a
/// select (a lane that misses computes a NaN root it never uses). Only the lanes in
/// `mask` are meaningful.
///
/// With `cull`, when every lane in `mask` passes well clear of the sphere, the test (three divisions
/// and a root a lane) is skipped and every lane misses, which is what the test would
/// give: with f = origin − centre, a ray's distance from the centre is |f × d| / |d|,
/// and the lane is clear when |f × d|² > |d|² (r + ε)², ε = `CULL_SLACK`·(r + |f|₁). The
/// test's own `perp` carries an error of a few ULPs of |f| (far below ε), and the check's
/// own rounding is as small, so a clear lane's `perp · perp` exceeds r² and its `disc` is
/// negative: a miss. The check is skipped (the test run) where it could round otherwise:
/// an infinite |f × d|², or a bound under 2⁻¹⁰⁰ where products may be subnormal.
/// `tests`, below, tries rays just outside and inside the slack against `hit_sphere`.
/// Shadow rays cull, and so do camera rays in the search over every primitive: with
/// sixteen lanes the check is one vector (AVX-512) (`docs/bench/cpu-packets.md`).
#[inline(always)]
pub(super) fn sphere_lanes<O: Origins>(
    s: &Sphere,
    r: &Lanes<O>,
    mask: Mask,
    cull: bool,
    t_min: f32,
    t_max: &[f32; LANES],
) -> [f32; LANES] {
    let mut out = [INFINITY; LANES];
    let radius = s.radius;
    if cull && mask & !clear_lanes(s, r, CULL_SLACK) == 0 {
        return out;
    }
    for l in 0..LANES {
        let f = r.origin.from(&s.center, l);
        let d = [r.dir[0][l], r.dir[1][l], r.dir[2][l]];
        let a = r.dd[l];
        let b = -(f[0] * d[0] + f[1] * d[1] + f[2] * d[2]);
        let k = b / a;
        let perp = [f[0] + d[0] * k, f[1] + d[1] * k, f[2] + d[2] * k];
        let r2 = radius * radius;
        let disc = a * (r2 - (perp[0] * perp[0] + perp[1] * perp[1] + perp[2] * perp[2]));
        let c = (f[0] * f[0] + f[1] * f[1] + f[2] * f[2]) - r2;
        let q = b + sign_nonneg(b) * disc.sqrt();
        let t0 = c / q;
        let t1 = q / a;
        let near = if t0 < t1 { t0 } else { t1 };
        let far = if t0 < t1 { t1 } else { t0 };
        let t = if in_interval(near, t_min, t_max[l]) {
            near
        } else if in_interval(far, t_min, t_max[l]) {
            far
        } else {
            INFINITY
        };
        out[l] = if disc >= 0.0 { t } else { INFINITY };
    }
    out
}

/// 2⁻¹⁰⁰: below it `sphere_lanes` does not trust its clearance check.
const TINY: f32 = 7.888_609e-31;

/// The lanes whose ray passes clear of `s` by `slack` (see [`sphere_lanes`]).
#[inline(always)]
fn clear_lanes<O: Origins>(s: &Sphere, r: &Lanes<O>, slack: f32) -> Mask {
    let mut clear = [false; LANES];
    for l in 0..LANES {
        let f = r.origin.from(&s.center, l);
        let d = [r.dir[0][l], r.dir[1][l], r.dir[2][l]];
        let cx = f[1] * d[2] - f[2] * d[1];
        let cy = f[2] * d[0] - f[0] * d[2];
        let cz = f[0] * d[1] - f[1] * d[0];
        let c2 = cx * cx + cy * cy + cz * cz;
        let reach = s.radius + slack * (s.radius + (f[0].abs() + f[1].abs() + f[2].abs()));
        let bound = r.dd[l] * (reach * reach);
        clear[l] = c2 > bound && c2 < INFINITY && bound >= TINY;
    }
    mask_of(&clear)
}

/// `hit_prim` of primitive `id` for the lanes in `mask`, lane l against `t_max[l]`; `tri`
/// is its triangle when it is one (`triangles[id]` or its copy in `leaf_triangles`). A
/// triangle goes through `watertight_lanes` under the watertight algorithm, else through
/// the mirror's `hit_triangle` lane by lane; a sphere through the mirror's `hit_prim`.
/// Only the lanes in `mask` are meaningful.
#[allow(clippy::too_many_arguments)]
#[inline(always)]
pub(super) fn prim_lanes<O: Origins>(
    g: &Globals<f32>,
    ray: impl Fn(usize) -> Ray<f32>,
    r: &Lanes<O>,
    sh: &ShearLanes,
    id: u32,
    tri: Option<&Triangle>,
    mask: Mask,
    t_min: f32,
    t_max: &[f32; LANES],
) -> TriLanes {
    let tri = tri.filter(|_| g.spec.has_triangles);
    if let Some(tri) = tri {
        return triangle_lanes(g, tri, r, sh, mask, t_min, t_max);
    }
    let mut h = TriLanes::MISS;
    if (id & TRIANGLE_BIT) == 0 {
        if g.spec.has_spheres {
            h.t = sphere_lanes(&g.buf.spheres[id as usize], r, mask, false, t_min, t_max);
        }
        return h;
    }
    // A triangle not in hand: the mirror's `hit_prim`, lane by lane.
    let mut m = mask;
    while m != 0 {
        let l = m.trailing_zeros() as usize;
        m &= m - 1;
        (h.t[l], h.u[l], h.v[l]) = hit_prim_lane(g, ray(l), sh.lane(l), id, t_min, t_max[l]);
    }
    h
}

/// The mirror's `prim_material` for one lane's hit; `tri` gives the hit triangle (from
/// where the traversal read it) and is called only for a triangle.
#[inline(always)]
pub(super) fn prim_material<'a>(
    g: &'a Globals<f32>,
    hit: &Hit<f32>,
    tri: impl FnOnce() -> &'a Triangle,
) -> u32 {
    if (hit.prim & TRIANGLE_BIT) != 0 {
        return tri().material;
    }
    g.buf.spheres[hit.prim as usize].material
}

/// The mirror's `prim_normal` for one lane's hit at `p`, before its normalize (the shader
/// normalizes lane-wise after, `normalize_lanes`); `tri` as in [`prim_material`].
#[inline(always)]
pub(super) fn prim_normal<'a>(
    g: &'a Globals<f32>,
    hit: &Hit<f32>,
    p: [f32; 3],
    tri: impl FnOnce() -> &'a Triangle,
) -> [f32; 3] {
    if (hit.prim & TRIANGLE_BIT) != 0 {
        let tri = tri();
        return triangle_normal(tri.a.into(), tri.b.into(), tri.c.into()).into();
    }
    let c = g.buf.spheres[hit.prim as usize].center;
    [p[0] - c[0], p[1] - c[1], p[2] - c[2]]
}

/// A triangle's normal before its normalize, as the mirror's `prim_normal` makes it (with
/// its own `V3` arithmetic): (b - a) × (c - a).
#[inline(always)]
pub(super) fn triangle_normal(a: V3<f32>, b: V3<f32>, c: V3<f32>) -> V3<f32> {
    (b - a).cross(c - a)
}

/// The leaf's own copy of primitive `id`, at slot `k` of `prim_ids`, when it is a
/// triangle (what [`prim_lanes`] tests, in the memory the traversal is reading); `None`
/// for a sphere.
#[inline(always)]
pub(super) fn leaf_triangle<'a>(g: &'a Globals<'a, f32>, id: u32, k: u32) -> Option<&'a Triangle> {
    ((id & TRIANGLE_BIT) != 0).then(|| &g.buf.leaf_triangles()[k as usize])
}

#[cfg(test)]
pub(super) mod tests {
    use super::super::common::{LANES, Lanes, PerLane, Shared};
    use super::*;
    use crate::cpu::prims::hit_sphere;
    use crate::shared::real::V3;

    /// A small deterministic generator (xorshift64*), uniform in [0, 1); the packet
    /// tests' (`trace.rs` uses it too).
    pub(in crate::cpu::packet) struct Rng(pub(in crate::cpu::packet) u64);
    impl Rng {
        fn next(&mut self) -> f32 {
            self.0 ^= self.0 >> 12;
            self.0 ^= self.0 << 25;
            self.0 ^= self.0 >> 27;
            (self.0.wrapping_mul(0x2545_F491_4F6C_DD1D) >> 40) as f32 / (1u64 << 24) as f32
        }
        pub(in crate::cpu::packet) fn range(&mut self, lo: f32, hi: f32) -> f32 {
            lo + (hi - lo) * self.next()
        }
    }

    /// Rays passing the sphere at distances around the radius and around the clearance
    /// bound, in packets of `LANES` (each lane its own origin), at scales 1e-3 to 1e4.
    /// Returns (lanes cleared with `slack` whose `hit_sphere` is not a miss, lanes
    /// cleared, lanes where `sphere_lanes` differs from `hit_sphere`).
    fn try_rays(slack: f32) -> (usize, usize, usize) {
        let mut rng = Rng(0x5eed_cafe);
        let (mut unsound, mut cleared, mut differ) = (0, 0, 0);
        for case in 0..4000 {
            let scale = [1e-3f32, 1.0, 1e2, 1e4][case % 4];
            let s = Sphere {
                center: [0, 1, 2].map(|_| rng.range(-10.0, 10.0) * scale),
                radius: rng.range(0.01, 5.0) * scale,
                ..Sphere::default()
            };
            let c = V3::new(s.center[0], s.center[1], s.center[2]);
            let mut o = [[0.0f32; LANES]; 3];
            let mut d = [[0.0f32; LANES]; 3];
            for l in 0..LANES {
                let dir = V3::new(
                    rng.range(-1.0, 1.0),
                    rng.range(-1.0, 1.0),
                    rng.range(-1.0, 1.0),
                ) * rng.range(0.1, 10.0);
                let any = V3::new(
                    rng.range(-1.0, 1.0),
                    rng.range(-1.0, 1.0),
                    rng.range(-1.0, 1.0),
                );
                let w = any.cross(dir);
                let w = w * (1.0 / w.dot(w).sqrt());
                let back = rng.range(-30.0, 30.0) * scale;
                let f_len = (back * back + s.radius * s.radius).sqrt();
                // Half the lanes near the surface, half near the clearance bound.
                let eps = CULL_SLACK * (s.radius + f_len);
                let rho = if l % 2 == 0 {
                    s.radius * (1.0 + rng.range(-1e-3, 1e-3))
                } else {
                    s.radius + eps * rng.range(0.0, 2.0)
                };
                let p = c + w * rho - dir * (back / dir.dot(dir).sqrt());
                for k in 0..3 {
                    o[k][l] = [p.x, p.y, p.z][k];
                    d[k][l] = [dir.x, dir.y, dir.z][k];
                }
            }
            let r = Lanes::new(PerLane(o), &d);
            let clear = clear_lanes(&s, &r, slack);
            let (t_min, t_max) = (0.0f32, [f32::MAX; LANES]);
            let lanes = sphere_lanes(&s, &r, Mask::MAX, true, t_min, &t_max);
            for l in 0..LANES {
                let ray = Ray {
                    origin: V3::new(o[0][l], o[1][l], o[2][l]),
                    dir: V3::new(d[0][l], d[1][l], d[2][l]),
                };
                let t = hit_sphere(ray, &s, t_min, f32::MAX);
                if (clear >> l) & 1 != 0 {
                    cleared += 1;
                    unsound += (t != INFINITY) as usize;
                }
                differ += (lanes[l].to_bits() != t.to_bits()) as usize;
            }
        }
        (unsound, cleared, differ)
    }

    #[test]
    fn cleared_lanes_are_misses_and_sphere_lanes_is_hit_sphere() {
        let (unsound, cleared, differ) = try_rays(CULL_SLACK);
        assert_eq!(unsound, 0, "a lane cleared with CULL_SLACK hits the sphere");
        assert!(
            cleared > 1000,
            "only {cleared} lanes cleared: the bound went untried"
        );
        assert_eq!(differ, 0, "sphere_lanes differs from hit_sphere");
    }

    /// The watertight test's shortcut for packets whose lanes share (kx, ky, kz) gives the
    /// general lane loop's (t, u, v) in every bit: random triangles (some tiny, some
    /// sharing an edge with the ray's path) against packets that point one way (uniform)
    /// or every way (not), from one origin and from an origin per lane.
    #[test]
    fn the_uniform_watertight_path_is_the_general_one() {
        let mut rng = Rng(0x7a7e_71f1);
        let (mut uniform, mut mixed) = (0, 0);
        for case in 0..3000 {
            let spread = [0.05f32, 2.0][case % 2];
            let axis = [0, 1, 2].map(|_| rng.range(-1.0, 1.0));
            let mut o = [[0.0f32; LANES]; 3];
            let mut d = [[0.0f32; LANES]; 3];
            let shared = V3::new(
                rng.range(-5.0, 5.0),
                rng.range(-5.0, 5.0),
                rng.range(-5.0, 5.0),
            );
            for l in 0..LANES {
                for k in 0..3 {
                    d[k][l] = axis[k] + spread * rng.range(-1.0, 1.0);
                    o[k][l] = [shared.x, shared.y, shared.z][k] + rng.range(-0.5, 0.5);
                }
            }
            let size = [1e-4f32, 1.0, 100.0][case % 3];
            let p = |rng: &mut Rng| [0, 1, 2].map(|_| rng.range(-2.0, 2.0) * size);
            let tri = Triangle {
                a: p(&mut rng),
                b: p(&mut rng),
                c: p(&mut rng),
                ..Triangle::default()
            };
            let sh = shear_lanes(&d, true);
            let general = ShearLanes {
                uniform: None,
                ..sh
            };
            match sh.uniform {
                Some(_) => uniform += 1,
                None => mixed += 1,
            }
            let t_max = [f32::MAX; LANES];
            let same = |a: &TriLanes, b: &TriLanes| {
                (0..LANES).all(|l| {
                    [a.t[l], a.u[l], a.v[l]].map(f32::to_bits)
                        == [b.t[l], b.u[l], b.v[l]].map(f32::to_bits)
                })
            };
            let per_lane = Lanes::new(PerLane(o), &d);
            let one = Lanes::new(Shared(shared), &d);
            assert!(same(
                &watertight_lanes(&tri, &per_lane, &sh, Mask::MAX, 0.0, &t_max),
                &watertight_lanes(&tri, &per_lane, &general, Mask::MAX, 0.0, &t_max)
            ));
            assert!(same(
                &watertight_lanes(&tri, &one, &sh, Mask::MAX, 0.0, &t_max),
                &watertight_lanes(&tri, &one, &general, Mask::MAX, 0.0, &t_max)
            ));
        }
        assert!(
            uniform > 500 && mixed > 500,
            "{uniform} uniform, {mixed} mixed packets"
        );
    }

    /// The twin: the same comparison sees a shear one ULP off in one lane.
    #[test]
    fn a_shear_one_ulp_off_is_seen() {
        let d = [[0.05f32; LANES], [0.01f32; LANES], [1.0f32; LANES]];
        let tri = Triangle {
            a: [-1.0, -1.0, 5.0],
            b: [1.0, -1.0, 5.0],
            c: [0.0, 1.0, 5.0],
            ..Triangle::default()
        };
        let sh = shear_lanes(&d, true);
        assert!(sh.uniform.is_some());
        let mut off = ShearLanes {
            uniform: None,
            ..sh
        };
        off.sz[5] = f32::from_bits(off.sz[5].to_bits() + 1);
        let r = Lanes::new(Shared(V3::new(0.0, 0.0, 0.0)), &d);
        let t_max = [f32::MAX; LANES];
        let a = watertight_lanes(&tri, &r, &sh, Mask::MAX, 0.0, &t_max);
        let b = watertight_lanes(&tri, &r, &off, Mask::MAX, 0.0, &t_max);
        assert!(
            a.t[5] < INFINITY,
            "the ray must hit for the twin to mean anything"
        );
        assert_ne!(a.t[5].to_bits(), b.t[5].to_bits());
    }

    /// The twin: a slack that lets rays through the sphere's edge be cleared is caught.
    #[test]
    fn a_negative_slack_is_caught() {
        let (unsound, _, _) = try_rays(-CULL_SLACK);
        assert!(
            unsound > 0,
            "clearing rays that graze inside went unnoticed"
        );
    }
}
