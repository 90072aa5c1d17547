// glint's kernel, part 2 of 8: the primitives (after `common.wgsl`; see its header for
// how the parts are joined and mirrored). Everything that knows what a sphere or a
// triangle is lives here: the intersection tests, and the only switches on a primitive's
// kind, `hit_prim`, `is_triangle` (for `prim_normal` and `prim_material`) and `shading_at`
// (vertex normals are a triangle's). Mirror: `src/cpu/prims.rs`. A new primitive: its
// struct, binding and id tag in `common.wgsl`, its test and a branch in each switch
// here, its loop in `trace.wgsl`'s every-primitive search (`closest_hit_all`,
// `occluded_all`).

// ---- spheres -----------------------------------------------------------------------------

/// The nearest root of |o + t d − c| = r in (t_min, t_max), or INFINITY.
///
/// Ray Tracing Gems ch. 7: the discriminant from the perpendicular distance of the centre
/// to the ray, the roots from q = b + sign(b)·√Δ, so neither root cancels catastrophically.
/// `dir` need not be unit length.
fn hit_sphere(ray: Ray, s: Sphere, t_min: f32, t_max: f32) -> f32 {
    let f = ray.origin - s.center;
    let a = dot(ray.dir, ray.dir);
    let b = -dot(f, ray.dir);
    let perp = f + ray.dir * div_rn(b, a);
    let r2 = s.radius * s.radius;
    let disc = a * (r2 - dot(perp, perp));
    if !(disc >= 0.0) {
        return INFINITY;
    }
    let c = dot(f, f) - r2;
    let q = b + select(-1.0, 1.0, b >= 0.0) * sqrt_rn(disc);
    let t0 = div_rn(c, q);
    let t1 = div_rn(q, a);
    let near = select(t1, t0, t0 < t1);
    let far = select(t0, t1, t0 < t1);
    if in_interval(near, t_min, t_max) {
        return near;
    }
    if in_interval(far, t_min, t_max) {
        return far;
    }
    return INFINITY;
}

// ---- triangles -------------------------------------------------------------------------

/// The seed's algorithm: the plane through a, b, c, then barycentric coordinates of the
/// plane hit. Returns (t, u, v) with t = INFINITY on a miss; u, v weigh b and c.
fn hit_triangle_naive(ray: Ray, tri: Triangle, t_min: f32, t_max: f32) -> vec3<f32> {
    let miss = vec3<f32>(INFINITY, 0.0, 0.0);
    let e_ab = tri.b - tri.a;
    let e_ac = tri.c - tri.a;
    let cr = cross3(e_ac, e_ab);
    let len2 = dot(cr, cr);
    if !(len2 > 0.0) {
        return miss; // degenerate: no plane
    }
    let n = normalize_rn(cr);
    let dn = dot(ray.dir, n);
    if dn == 0.0 {
        return miss; // parallel to the plane
    }
    let t = div_rn(dot(tri.a, n) - dot(ray.origin, n), dn);
    if !in_interval(t, t_min, t_max) {
        return miss;
    }
    let p = ray.origin + ray.dir * t;
    let e_ap = p - tri.a;
    let d00 = dot(e_ab, e_ab);
    let d01 = dot(e_ab, e_ac);
    let d11 = dot(e_ac, e_ac);
    let d20 = dot(e_ap, e_ab);
    let d21 = dot(e_ap, e_ac);
    let denom = d00 * d11 - d01 * d01;
    if !(denom > d00 * d11 * NAIVE_MIN_SIN2) {
        return miss; // a sliver: denom is mostly rounding (buffers::NAIVE_MIN_SIN2)
    }
    let u = div_rn(d11 * d20 - d01 * d21, denom);
    let v = div_rn(d00 * d21 - d01 * d20, denom);
    if u >= 0.0 && v >= 0.0 && u + v <= 1.0 {
        return vec3<f32>(t, u, v);
    }
    return miss;
}

/// Möller–Trumbore, two-sided. Returns (t, u, v) with t = INFINITY on a miss.
///
/// The test `u + v <= 1` is written `(su + sv) * inv_det <= 1`: that is what lavapipe's
/// compiler turns `su * inv_det + sv * inv_det` into (NIR's inexact distributive rule),
/// while Rust rounds the two products apart, so the plain sum disagreed on rays through a
/// shared vertex or edge (13 to 20 hit/miss pixels on `tests/vertex_rays.rs`'s grid).
/// Written factored on both sides, no rule applies and both round alike.
fn hit_triangle_moller_trumbore(ray: Ray, tri: Triangle, t_min: f32, t_max: f32) -> vec3<f32> {
    let miss = vec3<f32>(INFINITY, 0.0, 0.0);
    let e1 = tri.b - tri.a;
    let e2 = tri.c - tri.a;
    let p = cross3(ray.dir, e2);
    let det = dot(e1, p);
    if det == 0.0 || det != det {
        return miss; // parallel, degenerate, or NaN
    }
    let inv_det = div_rn(1.0, det);
    let s = ray.origin - tri.a;
    let su = dot(s, p);
    let u = su * inv_det;
    if !(u >= 0.0 && u <= 1.0) {
        return miss;
    }
    let q = cross3(s, e1);
    let sv = dot(ray.dir, q);
    let v = sv * inv_det;
    if !(v >= 0.0 && (su + sv) * inv_det <= 1.0) {
        return miss;
    }
    let t = dot(e2, q) * inv_det;
    if !in_interval(t, t_min, t_max) {
        return miss;
    }
    return vec3<f32>(t, u, v);
}

/// What the watertight test needs of a ray, computed once per ray (Woop et al. 2013, §3).
struct Shear {
    kx: u32,
    ky: u32,
    kz: u32,
    sx: f32,
    sy: f32,
    sz: f32,
}

/// The ray's shear: kz is the dimension where |dir| is largest, kx and ky follow it,
/// swapped when dir[kz] < 0 to keep the winding.
fn make_shear(dir: vec3<f32>) -> Shear {
    let ad = vec3<f32>(abs(dir.x), abs(dir.y), abs(dir.z));
    var kz = 0u;
    if ad.y > ad.x {
        kz = 1u;
    }
    if ad.z > ad[kz] {
        kz = 2u;
    }
    var kx = (kz + 1u) % 3u;
    var ky = (kx + 1u) % 3u;
    if dir[kz] < 0.0 {
        let tmp = kx;
        kx = ky;
        ky = tmp;
    }
    let sz = div_rn(1.0, dir[kz]);
    return Shear(kx, ky, kz, dir[kx] * sz, dir[ky] * sz, sz);
}

/// The edge function x1·y2 − y1·x2 with an exact sign.
///
/// Where the paper recomputes an edge function in f64 when it rounds to 0, glint keeps
/// f32: a difference of two rounded products is 0 only when the products round equal, and
/// then the exact value is the difference of their rounding errors, which Dekker's
/// TwoProduct gives exactly. So a returned 0 is an exact 0, on both tracers and without f64.
fn edge_function(x1: f32, y2: f32, y1: f32, x2: f32) -> f32 {
    let p1 = x1 * y2;
    let p2 = y1 * x2;
    let e = p1 - p2;
    if e != 0.0 {
        return e;
    }
    return product_error(x1, y2, p1) - product_error(y1, x2, p2);
}

/// Watertight ray/triangle intersection (Woop, Benthin, Wald, JCGT 2013), two-sided:
/// no ray passes between two triangles that share an edge or a vertex.
/// Returns (t, u, v) with t = INFINITY on a miss.
fn hit_triangle_watertight(ray: Ray, sh: Shear, tri: Triangle, t_min: f32, t_max: f32) -> vec3<f32> {
    let miss = vec3<f32>(INFINITY, 0.0, 0.0);
    let a = tri.a - ray.origin;
    let b = tri.b - ray.origin;
    let c = tri.c - ray.origin;
    let ax = a[sh.kx] - sh.sx * a[sh.kz];
    let ay = a[sh.ky] - sh.sy * a[sh.kz];
    let bx = b[sh.kx] - sh.sx * b[sh.kz];
    let by = b[sh.ky] - sh.sy * b[sh.kz];
    let cx = c[sh.kx] - sh.sx * c[sh.kz];
    let cy = c[sh.ky] - sh.sy * c[sh.kz];
    let u = edge_function(cx, by, cy, bx);
    let v = edge_function(ax, cy, ay, cx);
    let w = edge_function(bx, ay, by, ax);
    if (u < 0.0 || v < 0.0 || w < 0.0) && (u > 0.0 || v > 0.0 || w > 0.0) {
        return miss;
    }
    let det = u + v + w;
    if det == 0.0 || det != det {
        return miss;
    }
    let az = sh.sz * a[sh.kz];
    let bz = sh.sz * b[sh.kz];
    let cz = sh.sz * c[sh.kz];
    let t_scaled = u * az + v * bz + w * cz;
    let inv_det = div_rn(1.0, det);
    let t = t_scaled * inv_det;
    if !in_interval(t, t_min, t_max) {
        return miss;
    }
    return vec3<f32>(t, v * inv_det, w * inv_det);
}

/// The ray's shear when the watertight test is compiled in, else an unused identity.
fn ray_shear(dir: vec3<f32>) -> Shear {
    if TRIANGLE_ALGO == TRIANGLE_WATERTIGHT {
        return make_shear(dir);
    }
    return Shear(0u, 1u, 2u, 0.0, 0.0, 1.0);
}

/// The scene's triangle algorithm (a pipeline constant, so only one is compiled).
fn hit_triangle(ray: Ray, sh: Shear, tri: Triangle, t_min: f32, t_max: f32) -> vec3<f32> {
    if TRIANGLE_ALGO == TRIANGLE_NAIVE {
        return hit_triangle_naive(ray, tri, t_min, t_max);
    }
    if TRIANGLE_ALGO == TRIANGLE_MOLLER_TRUMBORE {
        return hit_triangle_moller_trumbore(ray, tri, t_min, t_max);
    }
    return hit_triangle_watertight(ray, sh, tri, t_min, t_max);
}

// ---- the switches on a primitive's kind -------------------------------------------------

/// Primitive `id` (a sphere index, or a triangle index with TRIANGLE_BIT): (t, u, v) with
/// t = INFINITY on a miss.
fn hit_prim(ray: Ray, sh: Shear, id: u32, t_min: f32, t_max: f32) -> vec3<f32> {
    if (id & TRIANGLE_BIT) != 0u {
        if HAS_TRIANGLES {
            return hit_triangle(ray, sh, triangles[id & ~TRIANGLE_BIT], t_min, t_max);
        }
        return vec3<f32>(INFINITY, 0.0, 0.0);
    }
    if HAS_SPHERES {
        return vec3<f32>(hit_sphere(ray, spheres[id], t_min, t_max), 0.0, 0.0);
    }
    return vec3<f32>(INFINITY, 0.0, 0.0);
}

/// Whether primitive `id` (a hit's, never PRIM_NONE) is a triangle. Where the scene has
/// one kind only, the answer is a constant, so the other kind's loads are not compiled:
/// lavapipe 22.3 runs both sides of every `if`, each load a per-lane loop.
fn is_triangle(id: u32) -> bool {
    if !HAS_SPHERES {
        return true;
    }
    if !HAS_TRIANGLES {
        return false;
    }
    return (id & TRIANGLE_BIT) != 0u;
}

/// The unit geometric normal at hit point `p` (not yet facing the ray).
fn prim_normal(hit: Hit, p: vec3<f32>) -> vec3<f32> {
    if is_triangle(hit.prim) {
        let tri = triangle_of(hit);
        return normalize_rn(cross3(tri.b - tri.a, tri.c - tri.a));
    }
    let s = spheres[hit.prim];
    return normalize_rn(p - s.center);
}

/// The material index of the hit primitive.
fn prim_material(hit: Hit) -> u32 {
    if is_triangle(hit.prim) {
        if INSTANCES {
            return triangle_of(hit).material;
        }
        return triangles[hit.prim & ~TRIANGLE_BIT].material;
    }
    return spheres[hit.prim].material;
}

/// How a hit is shaded: the normal that lights it and the point its shadow rays leave.
struct Shading {
    n: vec3<f32>,
    p: vec3<f32>,
}

/// The shading of a hit at `p` whose geometric normal, turned to face the ray, is `n`: `n`
/// and `p` themselves, unless the hit triangle has vertex normals. Then the normal is their
/// interpolation with the hit's barycentrics (w, u, v for a, b, c; all three turned when
/// it would face away from `n`), and shadow rays leave from Hanika's point ("Hacking the
/// Shadow Terminator", Ray Tracing Gems II, ch. 4): `p` lifted onto the mean of its
/// projections on the vertices' tangent planes (only planes that lie above `p` lift it).
/// That curved point sees the light past the neighbouring triangles that the smooth
/// normal pretends away, so the terminator does not fall in blocks of whole triangles.
fn shading_at(hit: Hit, p: vec3<f32>, n: vec3<f32>) -> Shading {
    if !SMOOTH || (hit.prim & TRIANGLE_BIT) == 0u {
        return Shading(n, p);
    }
    let tri = triangle_of(hit);
    if tri.normals == FLAT {
        return Shading(n, p);
    }
    let vn = normals_of(hit, tri);
    let w = 1.0 - hit.u - hit.v;
    var na = vn.na;
    var nb = vn.nb;
    var nc = vn.nc;
    var mixed = na * w + nb * hit.u + nc * hit.v;
    if dot(mixed, n) < 0.0 {
        na = -na;
        nb = -nb;
        nc = -nc;
        mixed = -mixed;
    }
    if !(dot(mixed, mixed) > 0.0) {
        return Shading(n, p); // opposite vertex normals cancel: nothing to interpolate
    }
    let da = max0(dot(tri.a - p, na));
    let db = max0(dot(tri.b - p, nb));
    let dc = max0(dot(tri.c - p, nc));
    let lifted = p + na * (w * da) + nb * (hit.u * db) + nc * (hit.v * dc);
    return Shading(normalize_rn(mixed), lifted);
}
