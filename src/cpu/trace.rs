//! The CPU mirror of `shaders/trace.wgsl`: the same functions, with the same names, in the
//! same order, doing the same operations in the same order.
//!
//! Written generic over [`Real`]: instantiated at f32 it is the shader's twin (bit for bit
//! on lavapipe), at f64 it is the ground truth that error is measured against. The
//! shader's module-scope globals (`params`, the buffers, the override constants) are the
//! fields of [`Globals`]. Un-idiomatic Rust (`if !(x > 0)`, index loops, early returns) is
//! kept where it keeps a line comparable with its WGSL line.

// `!(x > 0)` is not `x <= 0` for NaN; the shader writes it so, on purpose, and so does its mirror.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

use crate::buffers::{
    BvhNode, FLAT, HitOut, Light, MODEL_AMBIENT, MODEL_PHONG, Material, PRIM_NONE, RayIn,
    SceneBuffers, Specialisation, Sphere, TRIANGLE_BIT, TRIANGLE_MOLLER_TRUMBORE, TRIANGLE_NAIVE,
    TRIANGLE_WATERTIGHT, Triangle,
};
use crate::cpu::real::{Real, V3};

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

/// What the shader sees at module scope, for the CPU.
pub struct Globals<'a, R> {
    /// The camera.
    pub cam: Camera<R>,
    /// Scene buffers (colours and geometry are widened from f32 to `R` where read).
    pub buf: &'a SceneBuffers,
    /// The pipeline's override constants.
    pub spec: Specialisation,
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
}

// ---- small helpers ---------------------------------------------------------------------

/// WGSL `max0`: `x` when `x > 0`, else 0 (NaN gives 0).
pub fn max0<R: Real>(x: R) -> R {
    if x > R::ZERO { x } else { R::ZERO }
}

/// WGSL `max2`: the larger of `a` and `b` (`b` when either is NaN).
pub fn max2<R: Real>(a: R, b: R) -> R {
    if a > b { a } else { b }
}

/// WGSL `clamp01`: `x` clamped to [0, 1] (NaN gives 0).
pub fn clamp01<R: Real>(x: R) -> R {
    if !(x > R::ZERO) {
        R::ZERO
    } else if x > R::ONE {
        R::ONE
    } else {
        x
    }
}

/// WGSL `in_interval`: whether t lies in (t_min, t_max); false for NaN.
pub fn in_interval<R: Real>(t: R, t_min: R, t_max: R) -> bool {
    t > t_min && t < t_max
}

/// WGSL `select(-1.0, 1.0, b >= 0.0)`.
fn sign_nonneg<R: Real>(b: R) -> R {
    if b >= R::ZERO { R::ONE } else { -R::ONE }
}

// ---- the camera ------------------------------------------------------------------------

/// WGSL `camera_ray`: the primary ray through the point (dx, dy) of pixel (i, j), each in
/// [0, 1) from its top-left corner (the centre is (0.5, 0.5)).
pub fn camera_ray<R: Real>(g: &Globals<R>, i: u32, j: u32, dx: R, dy: R) -> Ray<R> {
    let c = &g.cam;
    let two = R::ONE + R::ONE;
    let x = ((R::from_u32(i) + dx) / R::from_u32(c.width) * two - R::ONE) * c.tan_half * c.aspect;
    let y = (R::ONE - (R::from_u32(j) + dy) / R::from_u32(c.height) * two) * c.tan_half;
    let dir = (c.forward + c.right * x + c.up * y).normalize();
    Ray { origin: c.eye, dir }
}

// ---- spheres -----------------------------------------------------------------------------

/// WGSL `hit_sphere`: the nearest root in (t_min, t_max), or INFINITY (Ray Tracing Gems ch. 7).
pub fn hit_sphere<R: Real>(ray: Ray<R>, s: &Sphere, t_min: R, t_max: R) -> R {
    let center = V3::from_f32(s.center);
    let radius = R::from_f32(s.radius);
    let f = ray.origin - center;
    let a = ray.dir.dot(ray.dir);
    let b = -f.dot(ray.dir);
    let perp = f + ray.dir * (b / a);
    let r2 = radius * radius;
    let disc = a * (r2 - perp.dot(perp));
    if !(disc >= R::ZERO) {
        return R::INFINITY;
    }
    let c = f.dot(f) - r2;
    let q = b + sign_nonneg(b) * disc.sqrt();
    let t0 = c / q;
    let t1 = q / a;
    let near = if t0 < t1 { t0 } else { t1 };
    let far = if t0 < t1 { t1 } else { t0 };
    if in_interval(near, t_min, t_max) {
        return near;
    }
    if in_interval(far, t_min, t_max) {
        return far;
    }
    R::INFINITY
}

/// The textbook sphere test (b² − 4ac, both roots by the quadratic formula), kept only so
/// the hard-case suite can measure what the stable form buys. Not used by any tracer.
pub fn hit_sphere_textbook<R: Real>(ray: Ray<R>, s: &Sphere, t_min: R, t_max: R) -> R {
    let center = V3::from_f32(s.center);
    let radius = R::from_f32(s.radius);
    let f = ray.origin - center;
    let a = ray.dir.dot(ray.dir);
    let b = f.dot(ray.dir);
    let c = f.dot(f) - radius * radius;
    let disc = b * b - a * c;
    if !(disc >= R::ZERO) {
        return R::INFINITY;
    }
    let sq = disc.sqrt();
    let t0 = (-b - sq) / a;
    let t1 = (-b + sq) / a;
    if in_interval(t0, t_min, t_max) {
        return t0;
    }
    if in_interval(t1, t_min, t_max) {
        return t1;
    }
    R::INFINITY
}

// ---- triangles -------------------------------------------------------------------------

/// (t, u, v) of a triangle hit; t = INFINITY on a miss. WGSL: `vec3<f32>`.
pub type TriHit<R> = (R, R, R);

fn tri_vertices<R: Real>(tri: &Triangle) -> (V3<R>, V3<R>, V3<R>) {
    (
        V3::from_f32(tri.a),
        V3::from_f32(tri.b),
        V3::from_f32(tri.c),
    )
}

/// WGSL `hit_triangle_naive`: the seed's plane + barycentric test.
pub fn hit_triangle_naive<R: Real>(ray: Ray<R>, tri: &Triangle, t_min: R, t_max: R) -> TriHit<R> {
    let miss = (R::INFINITY, R::ZERO, R::ZERO);
    let (ta, tb, tc) = tri_vertices::<R>(tri);
    let e_ab = tb - ta;
    let e_ac = tc - ta;
    let cr = e_ac.cross(e_ab);
    let len2 = cr.dot(cr);
    if !(len2 > R::ZERO) {
        return miss; // degenerate: no plane
    }
    let n = cr.normalize();
    let dn = ray.dir.dot(n);
    if dn == R::ZERO {
        return miss; // parallel to the plane
    }
    let t = (ta.dot(n) - ray.origin.dot(n)) / dn;
    if !in_interval(t, t_min, t_max) {
        return miss;
    }
    let p = ray.origin + ray.dir * t;
    let e_ap = p - ta;
    let d00 = e_ab.dot(e_ab);
    let d01 = e_ab.dot(e_ac);
    let d11 = e_ac.dot(e_ac);
    let d20 = e_ap.dot(e_ab);
    let d21 = e_ap.dot(e_ac);
    let denom = d00 * d11 - d01 * d01;
    if !(denom > d00 * d11 * R::NAIVE_MIN_SIN2) {
        return miss; // a sliver: denom is mostly rounding (buffers::NAIVE_MIN_SIN2)
    }
    let u = (d11 * d20 - d01 * d21) / denom;
    let v = (d00 * d21 - d01 * d20) / denom;
    if u >= R::ZERO && v >= R::ZERO && u + v <= R::ONE {
        return (t, u, v);
    }
    miss
}

/// WGSL `hit_triangle_moller_trumbore`: Möller–Trumbore, two-sided.
pub fn hit_triangle_moller_trumbore<R: Real>(
    ray: Ray<R>,
    tri: &Triangle,
    t_min: R,
    t_max: R,
) -> TriHit<R> {
    let miss = (R::INFINITY, R::ZERO, R::ZERO);
    let (ta, tb, tc) = tri_vertices::<R>(tri);
    let e1 = tb - ta;
    let e2 = tc - ta;
    let p = ray.dir.cross(e2);
    let det = e1.dot(p);
    #[allow(clippy::eq_op)]
    if det == R::ZERO || det != det {
        return miss; // parallel, degenerate, or NaN
    }
    let inv_det = R::ONE / det;
    let s = ray.origin - ta;
    let su = s.dot(p);
    let u = su * inv_det;
    if !(u >= R::ZERO && u <= R::ONE) {
        return miss;
    }
    let q = s.cross(e1);
    let sv = ray.dir.dot(q);
    let v = sv * inv_det;
    // u + v in the factored form lavapipe compiles it to (see the WGSL doc comment).
    if !(v >= R::ZERO && (su + sv) * inv_det <= R::ONE) {
        return miss;
    }
    let t = e2.dot(q) * inv_det;
    if !in_interval(t, t_min, t_max) {
        return miss;
    }
    (t, u, v)
}

/// WGSL `Shear`: what the watertight test needs of a ray, once per ray.
#[derive(Clone, Copy, Debug)]
pub struct Shear<R> {
    /// First sheared axis.
    pub kx: u32,
    /// Second sheared axis.
    pub ky: u32,
    /// The axis where |dir| is largest.
    pub kz: u32,
    /// `dir[kx] / dir[kz]`.
    pub sx: R,
    /// `dir[ky] / dir[kz]`.
    pub sy: R,
    /// `1 / dir[kz]`.
    pub sz: R,
}

/// WGSL `make_shear`.
pub fn make_shear<R: Real>(dir: V3<R>) -> Shear<R> {
    let ad = V3::new(dir.x.abs(), dir.y.abs(), dir.z.abs());
    let mut kz = 0u32;
    if ad.y > ad.x {
        kz = 1;
    }
    if ad.z > ad.get(kz) {
        kz = 2;
    }
    let mut kx = (kz + 1) % 3;
    let mut ky = (kx + 1) % 3;
    if dir.get(kz) < R::ZERO {
        std::mem::swap(&mut kx, &mut ky);
    }
    let sz = R::ONE / dir.get(kz);
    Shear {
        kx,
        ky,
        kz,
        sx: dir.get(kx) * sz,
        sy: dir.get(ky) * sz,
        sz,
    }
}

/// WGSL `product_error`: Dekker's exact rounding error of the product `a * b == p`.
pub fn product_error<R: Real>(a: R, b: R, p: R) -> R {
    let ca = R::SPLITTER * a;
    let a_hi = ca - (ca - a);
    let a_lo = a - a_hi;
    let cb = R::SPLITTER * b;
    let b_hi = cb - (cb - b);
    let b_lo = b - b_hi;
    ((a_hi * b_hi - p) + a_hi * b_lo + a_lo * b_hi) + a_lo * b_lo
}

/// WGSL `edge_function`: x1·y2 − y1·x2 with an exact sign (a returned 0 is an exact 0).
pub fn edge_function<R: Real>(x1: R, y2: R, y1: R, x2: R) -> R {
    let p1 = x1 * y2;
    let p2 = y1 * x2;
    let e = p1 - p2;
    if e != R::ZERO {
        return e;
    }
    product_error(x1, y2, p1) - product_error(y1, x2, p2)
}

/// WGSL `hit_triangle_watertight`: Woop, Benthin and Wald's watertight test, two-sided.
pub fn hit_triangle_watertight<R: Real>(
    ray: Ray<R>,
    sh: Shear<R>,
    tri: &Triangle,
    t_min: R,
    t_max: R,
) -> TriHit<R> {
    let miss = (R::INFINITY, R::ZERO, R::ZERO);
    let (ta, tb, tc) = tri_vertices::<R>(tri);
    let a = ta - ray.origin;
    let b = tb - ray.origin;
    let c = tc - ray.origin;
    let ax = a.get(sh.kx) - sh.sx * a.get(sh.kz);
    let ay = a.get(sh.ky) - sh.sy * a.get(sh.kz);
    let bx = b.get(sh.kx) - sh.sx * b.get(sh.kz);
    let by = b.get(sh.ky) - sh.sy * b.get(sh.kz);
    let cx = c.get(sh.kx) - sh.sx * c.get(sh.kz);
    let cy = c.get(sh.ky) - sh.sy * c.get(sh.kz);
    let u = edge_function(cx, by, cy, bx);
    let v = edge_function(ax, cy, ay, cx);
    let w = edge_function(bx, ay, by, ax);
    if (u < R::ZERO || v < R::ZERO || w < R::ZERO) && (u > R::ZERO || v > R::ZERO || w > R::ZERO) {
        return miss;
    }
    let det = u + v + w;
    #[allow(clippy::eq_op)]
    if det == R::ZERO || det != det {
        return miss;
    }
    let az = sh.sz * a.get(sh.kz);
    let bz = sh.sz * b.get(sh.kz);
    let cz = sh.sz * c.get(sh.kz);
    let t_scaled = u * az + v * bz + w * cz;
    let inv_det = R::ONE / det;
    let t = t_scaled * inv_det;
    if !in_interval(t, t_min, t_max) {
        return miss;
    }
    (t, v * inv_det, w * inv_det)
}

/// WGSL `ray_shear`: the ray's shear when the watertight test is in use, else an identity.
pub fn ray_shear<R: Real>(g: &Globals<R>, dir: V3<R>) -> Shear<R> {
    if g.spec.triangle_algo == TRIANGLE_WATERTIGHT {
        return make_shear(dir);
    }
    Shear {
        kx: 0,
        ky: 1,
        kz: 2,
        sx: R::ZERO,
        sy: R::ZERO,
        sz: R::ONE,
    }
}

/// WGSL `hit_triangle`: the scene's triangle algorithm.
pub fn hit_triangle<R: Real>(
    g: &Globals<R>,
    ray: Ray<R>,
    sh: Shear<R>,
    tri: &Triangle,
    t_min: R,
    t_max: R,
) -> TriHit<R> {
    if g.spec.triangle_algo == TRIANGLE_NAIVE {
        return hit_triangle_naive(ray, tri, t_min, t_max);
    }
    if g.spec.triangle_algo == TRIANGLE_MOLLER_TRUMBORE {
        return hit_triangle_moller_trumbore(ray, tri, t_min, t_max);
    }
    hit_triangle_watertight(ray, sh, tri, t_min, t_max)
}

// ---- the scene ---------------------------------------------------------------------------

/// WGSL `closest_sphere`: `best`, or the nearest sphere hit in (t_min, best.t); the first
/// sphere wins ties.
pub fn closest_sphere<R: Real>(g: &Globals<R>, ray: Ray<R>, t_min: R, best: Hit<R>) -> Hit<R> {
    let mut b = best;
    for k in 0..g.buf.params.n_spheres {
        let t = hit_sphere(ray, &g.buf.spheres[k as usize], t_min, b.t);
        if t < b.t {
            b = Hit {
                t,
                prim: k,
                u: R::ZERO,
                v: R::ZERO,
            };
        }
    }
    b
}

/// WGSL `sphere_blocks`: whether a sphere other than `skip` lies on the ray in (t_min,
/// t_max); stops at the first hit.
pub fn sphere_blocks<R: Real>(g: &Globals<R>, ray: Ray<R>, t_min: R, t_max: R, skip: u32) -> bool {
    for k in 0..g.buf.params.n_spheres {
        if k != skip && hit_sphere(ray, &g.buf.spheres[k as usize], t_min, t_max) < t_max {
            return true;
        }
    }
    false
}

/// WGSL `closest_hit_all`: the nearest hit in (t_min, t_max), spheres first; the first
/// primitive wins ties.
pub fn closest_hit_all<R: Real>(g: &Globals<R>, ray: Ray<R>, t_min: R, t_max: R) -> Hit<R> {
    let mut best = Hit {
        t: t_max,
        prim: PRIM_NONE,
        u: R::ZERO,
        v: R::ZERO,
    };
    if g.spec.has_spheres {
        best = closest_sphere(g, ray, t_min, best);
    }
    if g.spec.has_triangles {
        let sh = ray_shear(g, ray.dir);
        for k in 0..g.buf.params.n_triangles {
            let h = hit_triangle(g, ray, sh, &g.buf.triangles[k as usize], t_min, best.t);
            if h.0 < best.t {
                best = Hit {
                    t: h.0,
                    prim: k | TRIANGLE_BIT,
                    u: h.1,
                    v: h.2,
                };
            }
        }
    }
    best
}

/// WGSL `occluded_all`: whether anything but `skip` lies on the ray, testing every primitive.
pub fn occluded_all<R: Real>(g: &Globals<R>, ray: Ray<R>, t_min: R, t_max: R, skip: u32) -> bool {
    if g.spec.has_spheres && sphere_blocks(g, ray, t_min, t_max, skip) {
        return true;
    }
    if g.spec.has_triangles {
        let sh = ray_shear(g, ray.dir);
        for k in 0..g.buf.params.n_triangles {
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

/// WGSL `hit_prim`: primitive `id`, (t, u, v) with t = INFINITY on a miss.
pub fn hit_prim<R: Real>(
    g: &Globals<R>,
    ray: Ray<R>,
    sh: Shear<R>,
    id: u32,
    t_min: R,
    t_max: R,
) -> TriHit<R> {
    if (id & TRIANGLE_BIT) != 0 {
        if g.spec.has_triangles {
            let tri = &g.buf.triangles[(id & !TRIANGLE_BIT) as usize];
            return hit_triangle(g, ray, sh, tri, t_min, t_max);
        }
        return (R::INFINITY, R::ZERO, R::ZERO);
    }
    if g.spec.has_spheres {
        let s = &g.buf.spheres[id as usize];
        return (hit_sphere(ray, s, t_min, t_max), R::ZERO, R::ZERO);
    }
    (R::INFINITY, R::ZERO, R::ZERO)
}

/// WGSL `box_interval`: the part (t0, t1) of (t_min, t_max) inside the node's box, by the
/// conservative slab test; hit when t0 <= t1.
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
    let mut far = V3::new(
        select(t_hi.x, t_lo.x, swap.0),
        select(t_hi.y, t_lo.y, swap.1),
        select(t_hi.z, t_lo.z, swap.2),
    );
    far = far + far.abs() * R::BOX_SLACK;
    let mut t0 = t_min;
    let mut t1 = t_max;
    t0 = select(t0, near.x, near.x > t0);
    t0 = select(t0, near.y, near.y > t0);
    t0 = select(t0, near.z, near.z > t0);
    t1 = select(t1, far.x, far.x < t1);
    t1 = select(t1, far.y, far.y < t1);
    t1 = select(t1, far.z, far.z < t1);
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
pub fn closest_hit_bvh<R: Real>(g: &Globals<R>, ray: Ray<R>, t_min: R, t_max: R) -> Hit<R> {
    let mut best = Hit {
        t: t_max,
        prim: PRIM_NONE,
        u: R::ZERO,
        v: R::ZERO,
    };
    let sh = ray_shear(g, ray.dir);
    let inv_dir = V3::splat(R::ONE) / ray.dir;
    let nodes = &g.buf.nodes;
    if g.buf.params.n_nodes == 0 {
        return best;
    }
    let root = box_interval(&nodes[0], ray.origin, inv_dir, t_min, t_max);
    if !(root.0 <= root.1) {
        return best;
    }
    let mut stack = [0u32; BVH_STACK];
    let mut sp = 0usize;
    let mut at = 0u32;
    for _step in 0..g.buf.params.n_nodes {
        let node = &nodes[at as usize];
        let count = node.count_axis >> 2;
        if count == 0 {
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
            for k in node.first..node.first + count {
                let id = g.buf.prim_ids[k as usize];
                let h = hit_prim(g, ray, sh, id, t_min, tie_bound(&best));
                if nearer(h.0, id, &best) {
                    best = Hit {
                        t: h.0,
                        prim: id,
                        u: h.1,
                        v: h.2,
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
pub fn occluded_bvh<R: Real>(g: &Globals<R>, ray: Ray<R>, t_min: R, t_max: R, skip: u32) -> bool {
    let sh = ray_shear(g, ray.dir);
    let inv_dir = V3::splat(R::ONE) / ray.dir;
    let nodes = &g.buf.nodes;
    if g.buf.params.n_nodes == 0 {
        return false;
    }
    let root = box_interval(&nodes[0], ray.origin, inv_dir, t_min, t_max);
    if !(root.0 <= root.1) {
        return false;
    }
    let mut stack = [0u32; BVH_STACK];
    let mut sp = 0usize;
    let mut at = 0u32;
    for _step in 0..g.buf.params.n_nodes {
        let node = &nodes[at as usize];
        let count = node.count_axis >> 2;
        if count == 0 {
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
            for k in node.first..node.first + count {
                let id = g.buf.prim_ids[k as usize];
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
pub fn closest_hit<R: Real>(g: &Globals<R>, ray: Ray<R>, t_min: R, t_max: R) -> Hit<R> {
    let t_hi = finite_bound(t_max);
    if g.spec.use_bvh {
        return closest_hit_bvh(g, ray, t_min, t_hi);
    }
    closest_hit_all(g, ray, t_min, t_hi)
}

/// WGSL `occluded`: whether anything but primitive `skip` lies on the ray in (t_min,
/// t_max). A convex primitive cannot shadow a point of its own where N·L > 0, so skipping
/// the one that was hit loses no shadow.
pub fn occluded<R: Real>(g: &Globals<R>, ray: Ray<R>, t_min: R, t_max: R, skip: u32) -> bool {
    let t_hi = finite_bound(t_max);
    if g.spec.use_bvh {
        return occluded_bvh(g, ray, t_min, t_hi, skip);
    }
    occluded_all(g, ray, t_min, t_hi, skip)
}

// ---- shading -----------------------------------------------------------------------------

/// WGSL `phong_power`: `base^n`, by squaring for an integer exponent, else `pow`.
pub fn phong_power<R: Real>(base: R, m: &Material) -> R {
    if m.n_int < 0 {
        return base.powf(R::from_f32(m.n));
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
    result
}

/// WGSL `surface_normal`: the unit geometric normal at `p` (not yet facing the ray).
pub fn surface_normal<R: Real>(g: &Globals<R>, hit: &Hit<R>, p: V3<R>) -> V3<R> {
    if (hit.prim & TRIANGLE_BIT) != 0 {
        let tri = &g.buf.triangles[(hit.prim & !TRIANGLE_BIT) as usize];
        let (ta, tb, tc) = tri_vertices::<R>(tri);
        return (tb - ta).cross(tc - ta).normalize();
    }
    let s = &g.buf.spheres[hit.prim as usize];
    (p - V3::from_f32(s.center)).normalize()
}

/// WGSL `hit_material`: the material index of the hit primitive.
pub fn hit_material<R: Real>(g: &Globals<R>, hit: &Hit<R>) -> u32 {
    if (hit.prim & TRIANGLE_BIT) != 0 {
        return g.buf.triangles[(hit.prim & !TRIANGLE_BIT) as usize].material;
    }
    g.buf.spheres[hit.prim as usize].material
}

/// WGSL `Shading`: the normal that lights a hit and the point its shadow rays leave.
#[derive(Clone, Copy, Debug)]
pub struct Shading<R> {
    /// Unit shading normal, on the side of the facing geometric normal.
    pub n: V3<R>,
    /// Where shadow rays start (before `shadow_origin`'s offset).
    pub p: V3<R>,
}

/// WGSL `shading_at`: `n` and `p` themselves, unless the hit triangle is smooth; then the
/// interpolated vertex normal and Hanika's lifted point (see the WGSL doc comment).
pub fn shading_at<R: Real>(g: &Globals<R>, hit: &Hit<R>, p: V3<R>, n: V3<R>) -> Shading<R> {
    if !g.spec.smooth || (hit.prim & TRIANGLE_BIT) == 0 {
        return Shading { n, p };
    }
    let tri = &g.buf.triangles[(hit.prim & !TRIANGLE_BIT) as usize];
    if tri.normals == FLAT {
        return Shading { n, p };
    }
    let vn = &g.buf.normals[tri.normals as usize];
    let (ta, tb, tc) = tri_vertices::<R>(tri);
    let w = R::ONE - hit.u - hit.v;
    let mut na = V3::<R>::from_f32(vn.na);
    let mut nb = V3::<R>::from_f32(vn.nb);
    let mut nc = V3::<R>::from_f32(vn.nc);
    let mut mixed = na * w + nb * hit.u + nc * hit.v;
    if mixed.dot(n) < R::ZERO {
        na = -na;
        nb = -nb;
        nc = -nc;
        mixed = -mixed;
    }
    if !(mixed.dot(mixed) > R::ZERO) {
        return Shading { n, p }; // opposite vertex normals cancel: nothing to interpolate
    }
    let da = max0((ta - p).dot(na));
    let db = max0((tb - p).dot(nb));
    let dc = max0((tc - p).dot(nc));
    let lifted = p + na * (w * da) + nb * (hit.u * db) + nc * (hit.v * dc);
    Shading {
        n: mixed.normalize(),
        p: lifted,
    }
}

/// WGSL `shadow_origin`: the offset origin of a shadow ray from `p` with facing normal `n`.
pub fn shadow_origin<R: Real>(p: V3<R>, n: V3<R>) -> V3<R> {
    let scale = max2(max2(p.x.abs(), p.y.abs()), max2(p.z.abs(), R::ONE));
    let sixty_four = R::from_u32(64);
    p + n * (scale * R::EPSILON * sixty_four)
}

/// WGSL `shade`: SPEC.md's Phong model at a hit, each term only where the model has it.
pub fn shade<R: Real>(g: &Globals<R>, ray: Ray<R>, hit: &Hit<R>) -> V3<R> {
    let m: &Material = &g.buf.materials[hit_material(g, hit) as usize];
    let p = ray.origin + ray.dir * hit.t;
    let mut n = surface_normal(g, hit, p);
    if n.dot(ray.dir) > R::ZERO {
        n = -n;
    }
    let sh = shading_at(g, hit, p, n);
    let mut color = V3::from_f32(g.buf.params.ambient) * V3::from_f32(m.ka);
    if g.spec.uses_diffuse && m.model != MODEL_AMBIENT {
        // The reversed ray, as the shader has it (see there why not `origin - p`).
        let v = (-ray.dir).normalize();
        for k in 0..g.buf.params.n_lights {
            let light: &Light = &g.buf.lights[k as usize];
            let position = V3::from_f32(light.position);
            let light_color = V3::from_f32(light.color);
            let to_light = position - p;
            let l = to_light.normalize();
            let ndl = sh.n.dot(l);
            if !(ndl > R::ZERO) {
                continue;
            }
            if g.spec.shadows {
                let o = shadow_origin(sh.p, n);
                let d = position - o;
                if occluded(g, Ray { origin: o, dir: d }, R::ZERO, R::ONE, hit.prim) {
                    continue;
                }
            }
            color = color + light_color * V3::from_f32(m.kd) * ndl;
            if g.spec.uses_phong && m.model == MODEL_PHONG {
                let two = R::ONE + R::ONE;
                let r = sh.n * (two * ndl) - l;
                let rv = max0(r.dot(v));
                color = color + light_color * V3::from_f32(m.ks) * phong_power(rv, m);
            }
        }
    }
    V3::new(clamp01(color.x), clamp01(color.y), clamp01(color.z))
}

/// WGSL `trace_sample`: the colour through the point (dx, dy) of pixel (i, j) and, in w,
/// the hit distance (−1 on a miss).
pub fn trace_sample<R: Real>(g: &Globals<R>, i: u32, j: u32, dx: R, dy: R) -> [R; 4] {
    let ray = camera_ray(g, i, j, dx, dy);
    let hit = closest_hit(g, ray, R::ZERO, R::INFINITY);
    if hit.prim == PRIM_NONE {
        let bg = V3::<R>::from_f32(g.buf.params.background);
        return [bg.x, bg.y, bg.z, -R::ONE];
    }
    let c = shade(g, ray, &hit);
    [c.x, c.y, c.z, hit.t]
}

/// WGSL `sample_offset`: (s + 0.5) / n, the position of sample s of n along a
/// pixel side.
pub fn sample_offset<R: Real>(s: u32, n: u32) -> R {
    (R::from_u32(s) + R::ONE / (R::ONE + R::ONE)) / R::from_u32(n)
}

/// WGSL `trace_pixel`: the colour of pixel (i, j) and, in w, the hit distance (−1 on a
/// miss); with antialiasing the N×N samples, rows top to bottom, summed in that order and
/// divided by N², w the nearest hit's t.
pub fn trace_pixel<R: Real>(g: &Globals<R>, i: u32, j: u32) -> [R; 4] {
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
    let c = sum / V3::splat(R::from_u32(n * n));
    [c.x, c.y, c.z, t_near]
}

// ---- entry points ------------------------------------------------------------------------

/// WGSL `query` for one ray.
pub fn query<R: Real>(g: &Globals<R>, r: &RayIn) -> HitOut {
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
