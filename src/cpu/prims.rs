//! The CPU mirror of `shaders/prims.wgsl`: the primitives. The intersection tests, and
//! the only switches on a primitive's kind: [`hit_prim`], [`is_triangle`] (for
//! [`prim_normal`] and [`prim_material`]) and [`shading_at`] (see [`super::common`] for
//! the mirror's rules).

// The tests and the helpers they use are `#[inline]`: the packet tracer (another module)
// calls them lane by lane, and when they moved here from trace.rs LLVM stopped inlining
// them there without the hint (peers_2 primary rays 1.16× slower in the A/B; 1.01 with it).

// `!(x > 0)` is not `x <= 0` for NaN; the shader writes it so, on purpose, and so does its mirror.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

use super::common::{Globals, Hit, Ray, in_interval, max0, sign_nonneg};
use super::count::Count;
use super::exact::product_error;
use super::instance::{normals_of, triangle_of};
use crate::buffers::{
    FLAT, Sphere, TRIANGLE_BIT, TRIANGLE_MOLLER_TRUMBORE, TRIANGLE_NAIVE, TRIANGLE_WATERTIGHT,
    Triangle,
};
use crate::shared::real::{Real, V3};

// ---- spheres -----------------------------------------------------------------------------

/// WGSL `hit_sphere`: the nearest root in (t_min, t_max), or INFINITY (Ray Tracing Gems ch. 7).
#[inline]
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

/// (t, u, v) of a triangle hit; t = INFINITY on a miss. WGSL: `vec3<f32>`.
pub type TriHit<R> = (R, R, R);
fn tri_vertices<R: Real>(tri: &Triangle) -> (V3<R>, V3<R>, V3<R>) {
    (
        V3::from_f32(tri.a),
        V3::from_f32(tri.b),
        V3::from_f32(tri.c),
    )
}

// ---- triangles -------------------------------------------------------------------------

/// WGSL `hit_triangle_naive`: the seed's plane + barycentric test.
#[inline]
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
#[inline]
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
#[inline]
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

/// WGSL `edge_function`: x1·y2 − y1·x2 with an exact sign (a returned 0 is an exact 0).
#[inline]
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
#[inline]
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
#[inline]
pub fn ray_shear<R: Real, C: Count>(g: &Globals<R, C>, dir: V3<R>) -> Shear<R> {
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
#[inline]
pub fn hit_triangle<R: Real, C: Count>(
    g: &Globals<R, C>,
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

/// WGSL `hit_prim`: primitive `id`, (t, u, v) with t = INFINITY on a miss.
#[inline]
pub fn hit_prim<R: Real, C: Count>(
    g: &Globals<R, C>,
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

/// WGSL `is_triangle`: whether primitive `id` (a hit's, never PRIM_NONE) is a triangle; a
/// constant where the scene has one kind only (the shader then compiles one branch).
pub fn is_triangle<R: Real, C: Count>(g: &Globals<R, C>, id: u32) -> bool {
    if !g.spec.has_spheres {
        return true;
    }
    if !g.spec.has_triangles {
        return false;
    }
    (id & TRIANGLE_BIT) != 0
}

/// WGSL `prim_normal`: the unit geometric normal at `p` (not yet facing the ray).
pub fn prim_normal<R: Real, C: Count>(g: &Globals<R, C>, hit: &Hit<R>, p: V3<R>) -> V3<R> {
    if is_triangle(g, hit.prim) {
        let tri = triangle_of(g, hit);
        return (tri.b - tri.a).cross(tri.c - tri.a).normalize();
    }
    let s = &g.buf.spheres[hit.prim as usize];
    (p - V3::from_f32(s.center)).normalize()
}

/// WGSL `prim_material`: the material index of the hit primitive.
pub fn prim_material<R: Real, C: Count>(g: &Globals<R, C>, hit: &Hit<R>) -> u32 {
    if is_triangle(g, hit.prim) {
        if g.spec.instances {
            return triangle_of(g, hit).material;
        }
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
pub fn shading_at<R: Real, C: Count>(
    g: &Globals<R, C>,
    hit: &Hit<R>,
    p: V3<R>,
    n: V3<R>,
) -> Shading<R> {
    if !g.spec.smooth || (hit.prim & TRIANGLE_BIT) == 0 {
        return Shading { n, p };
    }
    let tri = triangle_of(g, hit);
    if tri.normals == FLAT {
        return Shading { n, p };
    }
    let [mut na, mut nb, mut nc] = normals_of(g, hit, &tri);
    let (ta, tb, tc) = (tri.a, tri.b, tri.c);
    let w = R::ONE - hit.u - hit.v;
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
