// glint's kernel: one invocation per pixel (`render`) or per ray (`query`).
//
// Mirror: `src/cpu/trace.rs` has every function below, with the same name, in the same
// order, with the same operations in the same order. Change both in one commit; the
// GPU-against-CPU tests catch the one that was forgotten.
//
// Rules that keep the two bit-identical on lavapipe:
// - only `+ - * /`, `sqrt`, `dot`, `normalize` and comparisons on floats; `fma` never;
//   `pow` only for a non-integer Phong exponent (the one documented difference);
// - never a sum of two products by one shared factor (`a * r + b * r`): lavapipe's NIR
//   rewrites it as `(a + b) * r` (an inexact algebraic rule), Rust does not; write the
//   factored form on both sides (see `hit_triangle_moller_trumbore`);
// - `max`/`min`/`clamp` on floats are written as `select`s, so NaN has one meaning on both
//   sides (`select(0.0, x, x > 0.0)` is 0 for NaN, where `max` would be unspecified);
// - everything Rust computes once per frame (camera basis, `tan`) arrives in `Params`.
//
// The struct layouts are owned by `src/buffers.rs`; `tests/layout.rs` checks them with naga.

// ---- specialisation (set per scene by `src/buffers.rs::Specialisation`) ---------------

/// The scene has spheres: without them the sphere loop is not compiled.
override HAS_SPHERES: bool = true;
/// The scene has triangles: without them the triangle loop is not compiled.
override HAS_TRIANGLES: bool = true;
/// 0 naive, 1 Möller–Trumbore, 2 watertight (`buffers::TRIANGLE_*`).
override TRIANGLE_ALGO: u32 = 1u;
/// Some material's model is `diffuse` or `phong`: without it only the ambient term exists.
override USES_DIFFUSE: bool = true;
/// Some material's model is `phong`.
override USES_PHONG: bool = true;
/// Hard shadows: one `occluded` ray per light.
override SHADOWS: bool = false;
/// Traverse the BVH (`nodes`, `prim_ids`); else test every primitive (tiny scenes).
override USE_BVH: bool = true;
/// Some triangle has vertex normals (`normals`): shade it with their interpolation.
override SMOOTH: bool = false;
/// `params.samples`² rays a pixel (else one through its centre).
override ANTIALIAS: bool = false;

// ---- constants (each one's story is in `src/buffers.rs`) ------------------------------

const MODEL_AMBIENT: u32 = 0u;
const MODEL_DIFFUSE: u32 = 1u;
const MODEL_PHONG: u32 = 2u;
const TRIANGLE_NAIVE: u32 = 0u;
const TRIANGLE_MOLLER_TRUMBORE: u32 = 1u;
const TRIANGLE_WATERTIGHT: u32 = 2u;
const PRIM_NONE: u32 = 0xffffffffu;
const FLAT: u32 = 0u; // Triangle::normals of a flat triangle
const TRIANGLE_BIT: u32 = 0x80000000u;
const INFINITY: f32 = 3.40282347e38; // f32::MAX: a t that every real hit beats
const SHADOW_EPSILON: f32 = 1.1920929e-7; // see buffers::SHADOW_EPSILON
const SPLITTER: f32 = 4097.0; // 2^12 + 1, Veltkamp's split for f32
const BVH_STACK: u32 = 48u; // bvh::MAX_DEPTH: the builder never makes a deeper tree
const BOX_SLACK: f32 = 4.76837158e-7; // 4 ε ≥ 2γ(3): pbrt's conservative slab test
const NAIVE_MIN_SIN2: f32 = 1.9073486e-6; // 16 ε: see buffers::NAIVE_MIN_SIN2

// ---- shared structs (Rust: src/buffers.rs) --------------------------------------------

struct Params {
    eye: vec3<f32>,
    width: u32,
    forward: vec3<f32>,
    height: u32,
    right: vec3<f32>,
    tan_half: f32,
    up: vec3<f32>,
    aspect: f32,
    ambient: vec3<f32>,
    n_spheres: u32,
    background: vec3<f32>,
    n_triangles: u32,
    n_lights: u32,
    tile_x: u32,
    tile_y: u32,
    tile_width: u32,
    tile_height: u32,
    n_nodes: u32,
    samples: u32,
    _pad0: u32,
}

struct Sphere {
    center: vec3<f32>,
    radius: f32,
    material: u32,
    _pad0: u32,
    _pad1: u32,
    _pad2: u32,
}

struct Triangle {
    a: vec3<f32>,
    material: u32,
    b: vec3<f32>,
    normals: u32,
    c: vec3<f32>,
    _pad0: u32,
}

struct VertexNormals {
    na: vec3<f32>,
    _pad0: u32,
    nb: vec3<f32>,
    _pad1: u32,
    nc: vec3<f32>,
    _pad2: u32,
}

struct BvhNode {
    lo: vec3<f32>,
    first: u32,
    hi: vec3<f32>,
    count_axis: u32,
}

struct Material {
    ka: vec3<f32>,
    model: u32,
    kd: vec3<f32>,
    n: f32,
    ks: vec3<f32>,
    n_int: i32,
}

struct Light {
    position: vec3<f32>,
    _pad0: u32,
    color: vec3<f32>,
    _pad1: u32,
}

struct RayIn {
    origin: vec3<f32>,
    t_min: f32,
    dir: vec3<f32>,
    t_max: f32,
}

struct HitOut {
    t: f32,
    prim: u32,
    u: f32,
    v: f32,
}

@group(0) @binding(0) var<uniform> params: Params;
@group(0) @binding(1) var<storage, read> spheres: array<Sphere>;
@group(0) @binding(2) var<storage, read> triangles: array<Triangle>;
@group(0) @binding(3) var<storage, read> materials: array<Material>;
@group(0) @binding(4) var<storage, read> lights: array<Light>;
@group(0) @binding(5) var<storage, read_write> image: array<vec4<f32>>;
@group(0) @binding(6) var<storage, read> rays: array<RayIn>;
@group(0) @binding(7) var<storage, read_write> hits: array<HitOut>;
@group(0) @binding(8) var<storage, read> nodes: array<BvhNode>;
@group(0) @binding(9) var<storage, read> prim_ids: array<u32>;
@group(0) @binding(10) var<storage, read> normals: array<VertexNormals>;

// ---- small helpers ---------------------------------------------------------------------

struct Ray {
    origin: vec3<f32>,
    dir: vec3<f32>,
}

struct Hit {
    t: f32,
    prim: u32,
    u: f32,
    v: f32,
}

/// `x` when `x > 0`, else 0 (NaN gives 0).
fn max0(x: f32) -> f32 {
    return select(0.0, x, x > 0.0);
}

/// The larger of `a` and `b` (`b` when either is NaN).
fn max2(a: f32, b: f32) -> f32 {
    return select(b, a, a > b);
}

/// `x` clamped to [0, 1] (NaN gives 0).
fn clamp01(x: f32) -> f32 {
    return select(select(x, 1.0, x > 1.0), 0.0, !(x > 0.0));
}

/// `a × b`, written out so that both tracers round the same products.
fn cross3(a: vec3<f32>, b: vec3<f32>) -> vec3<f32> {
    return vec3<f32>(a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x);
}

/// Whether `t` lies in the open interval (t_min, t_max); false for NaN.
fn in_interval(t: f32, t_min: f32, t_max: f32) -> bool {
    return t > t_min && t < t_max;
}

// ---- the camera ------------------------------------------------------------------------

/// The primary ray through the point (dx, dy) of pixel (i, j), each in [0, 1) from its
/// top-left corner; SPEC.md's formula, left to right (the centre is (0.5, 0.5)).
fn camera_ray(i: u32, j: u32, dx: f32, dy: f32) -> Ray {
    let x = ((f32(i) + dx) / f32(params.width) * 2.0 - 1.0) * params.tan_half * params.aspect;
    let y = (1.0 - (f32(j) + dy) / f32(params.height) * 2.0) * params.tan_half;
    let dir = normalize(params.forward + params.right * x + params.up * y);
    return Ray(params.eye, dir);
}

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
    let perp = f + ray.dir * (b / a);
    let r2 = s.radius * s.radius;
    let disc = a * (r2 - dot(perp, perp));
    if !(disc >= 0.0) {
        return INFINITY;
    }
    let c = dot(f, f) - r2;
    let q = b + select(-1.0, 1.0, b >= 0.0) * sqrt(disc);
    let t0 = c / q;
    let t1 = q / a;
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
    let n = normalize(cr);
    let dn = dot(ray.dir, n);
    if dn == 0.0 {
        return miss; // parallel to the plane
    }
    let t = (dot(tri.a, n) - dot(ray.origin, n)) / dn;
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
    let u = (d11 * d20 - d01 * d21) / denom;
    let v = (d00 * d21 - d01 * d20) / denom;
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
    let inv_det = 1.0 / det;
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
    let sz = 1.0 / dir[kz];
    return Shear(kx, ky, kz, dir[kx] * sz, dir[ky] * sz, sz);
}

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
    let inv_det = 1.0 / det;
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

// ---- the scene ---------------------------------------------------------------------------

/// `best`, or the nearest sphere hit in (t_min, best.t) if there is one; the first sphere
/// wins ties. Every sphere is tested (also by the ray-query tracer, `trace_rq.wgsl`).
fn closest_sphere(ray: Ray, t_min: f32, best: Hit) -> Hit {
    var b = best;
    for (var k = 0u; k < params.n_spheres; k = k + 1u) {
        let t = hit_sphere(ray, spheres[k], t_min, b.t);
        if t < b.t {
            b = Hit(t, k, 0.0, 0.0);
        }
    }
    return b;
}

/// Whether a sphere other than primitive `skip` lies on the ray in (t_min, t_max), testing
/// every sphere; stops at the first hit.
fn sphere_blocks(ray: Ray, t_min: f32, t_max: f32, skip: u32) -> bool {
    for (var k = 0u; k < params.n_spheres; k = k + 1u) {
        if k != skip && hit_sphere(ray, spheres[k], t_min, t_max) < t_max {
            return true;
        }
    }
    return false;
}

/// The nearest hit in (t_min, t_max) over every sphere, then every triangle; the first
/// primitive wins ties. `prim` is PRIM_NONE on a miss.
fn closest_hit_all(ray: Ray, t_min: f32, t_max: f32) -> Hit {
    var best = Hit(t_max, PRIM_NONE, 0.0, 0.0);
    if HAS_SPHERES {
        best = closest_sphere(ray, t_min, best);
    }
    if HAS_TRIANGLES {
        let sh = ray_shear(ray.dir);
        for (var k = 0u; k < params.n_triangles; k = k + 1u) {
            let h = hit_triangle(ray, sh, triangles[k], t_min, best.t);
            if h.x < best.t {
                best = Hit(h.x, k | TRIANGLE_BIT, h.y, h.z);
            }
        }
    }
    return best;
}

/// Whether anything but primitive `skip` lies on the ray in (t_min, t_max), testing every
/// primitive; stops at the first hit.
fn occluded_all(ray: Ray, t_min: f32, t_max: f32, skip: u32) -> bool {
    if HAS_SPHERES && sphere_blocks(ray, t_min, t_max, skip) {
        return true;
    }
    if HAS_TRIANGLES {
        let sh = ray_shear(ray.dir);
        for (var k = 0u; k < params.n_triangles; k = k + 1u) {
            if (k | TRIANGLE_BIT) != skip && hit_triangle(ray, sh, triangles[k], t_min, t_max).x < t_max {
                return true;
            }
        }
    }
    return false;
}

// ---- the BVH -----------------------------------------------------------------------------

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

/// The part (t0, t1) of the ray's interval (t_min, t_max) inside the node's box; the box
/// is hit when t0 <= t1. The slab test, each exit distance widened by 2γ(3) of itself
/// (pbrt), so rounding never loses a box that the exact ray enters. NaN slabs (a zero
/// direction component at a slab's plane) constrain nothing. `inv_dir` is 1 / dir per
/// component (±inf for a zero component).
fn box_interval(node: BvhNode, origin: vec3<f32>, inv_dir: vec3<f32>, t_min: f32, t_max: f32) -> vec2<f32> {
    let t_lo = (node.lo - origin) * inv_dir;
    let t_hi = (node.hi - origin) * inv_dir;
    let swap = t_hi < t_lo;
    let near = select(t_lo, t_hi, swap);
    var far = select(t_hi, t_lo, swap);
    far = far + abs(far) * BOX_SLACK;
    var t0 = t_min;
    var t1 = t_max;
    t0 = select(t0, near.x, near.x > t0);
    t0 = select(t0, near.y, near.y > t0);
    t0 = select(t0, near.z, near.z > t0);
    t1 = select(t1, far.x, far.x < t1);
    t1 = select(t1, far.y, far.y < t1);
    t1 = select(t1, far.z, far.z < t1);
    return vec2<f32>(t0, t1);
}

/// The bound to test against when `best` is the nearest hit so far: one ULP past best.t,
/// so that a tie is seen and the lower id can win it, whatever order the BVH visits in.
fn tie_bound(best: Hit) -> f32 {
    if best.prim != PRIM_NONE && best.t > 0.0 && best.t <= INFINITY {
        return bitcast<f32>(bitcast<u32>(best.t) + 1u);
    }
    return best.t;
}

/// Whether a hit at t on primitive `id` beats `best`: nearer, or as near with a lower id
/// (the rule that `closest_hit_all` keeps by visiting in id order).
fn nearer(t: f32, id: u32, best: Hit) -> bool {
    return t < best.t || (t == best.t && id < best.prim && best.prim != PRIM_NONE);
}

/// `closest_hit` through the BVH, depth first: at an interior node both children's boxes
/// are tested, the nearer entered first and the other pushed. A fixed stack (the builder
/// bounds the depth) and at most one step per node, so a NaN ray cannot loop. Same result
/// as `closest_hit_all`.
fn closest_hit_bvh(ray: Ray, t_min: f32, t_max: f32) -> Hit {
    var best = Hit(t_max, PRIM_NONE, 0.0, 0.0);
    let sh = ray_shear(ray.dir);
    let inv_dir = 1.0 / ray.dir;
    if params.n_nodes == 0u {
        return best;
    }
    let root = box_interval(nodes[0], ray.origin, inv_dir, t_min, t_max);
    if !(root.x <= root.y) {
        return best;
    }
    var stack: array<u32, BVH_STACK>;
    var sp = 0u;
    var at = 0u;
    for (var step = 0u; step < params.n_nodes; step = step + 1u) {
        let node = nodes[at];
        let count = node.count_axis >> 2u;
        if count == 0u {
            let bound = tie_bound(best);
            let left = box_interval(nodes[at + 1u], ray.origin, inv_dir, t_min, bound);
            let right = box_interval(nodes[node.first], ray.origin, inv_dir, t_min, bound);
            let hit_left = left.x <= left.y;
            let hit_right = right.x <= right.y;
            if hit_left && hit_right {
                if right.x < left.x {
                    stack[sp] = at + 1u;
                    at = node.first;
                } else {
                    stack[sp] = node.first;
                    at = at + 1u;
                }
                sp = sp + 1u;
                continue;
            }
            if hit_left {
                at = at + 1u;
                continue;
            }
            if hit_right {
                at = node.first;
                continue;
            }
        } else {
            for (var k = node.first; k < node.first + count; k = k + 1u) {
                let id = prim_ids[k];
                let h = hit_prim(ray, sh, id, t_min, tie_bound(best));
                if nearer(h.x, id, best) {
                    best = Hit(h.x, id, h.y, h.z);
                }
            }
        }
        if sp == 0u {
            break;
        }
        sp = sp - 1u;
        at = stack[sp];
    }
    return best;
}

/// `occluded` through the BVH, in `closest_hit_bvh`'s order; stops at the first hit.
/// It repeats `closest_hit_bvh`'s loop rather than sharing a helper: with one push and one
/// pop site per loop, lavapipe runs fewer per-lane stack accesses (a shared `descend`
/// helper measured 40% slower; docs/bench/meshes.md).
fn occluded_bvh(ray: Ray, t_min: f32, t_max: f32, skip: u32) -> bool {
    let sh = ray_shear(ray.dir);
    let inv_dir = 1.0 / ray.dir;
    if params.n_nodes == 0u {
        return false;
    }
    let root = box_interval(nodes[0], ray.origin, inv_dir, t_min, t_max);
    if !(root.x <= root.y) {
        return false;
    }
    var stack: array<u32, BVH_STACK>;
    var sp = 0u;
    var at = 0u;
    for (var step = 0u; step < params.n_nodes; step = step + 1u) {
        let node = nodes[at];
        let count = node.count_axis >> 2u;
        if count == 0u {
            let left = box_interval(nodes[at + 1u], ray.origin, inv_dir, t_min, t_max);
            let right = box_interval(nodes[node.first], ray.origin, inv_dir, t_min, t_max);
            let hit_left = left.x <= left.y;
            let hit_right = right.x <= right.y;
            if hit_left && hit_right {
                if right.x < left.x {
                    stack[sp] = at + 1u;
                    at = node.first;
                } else {
                    stack[sp] = node.first;
                    at = at + 1u;
                }
                sp = sp + 1u;
                continue;
            }
            if hit_left {
                at = at + 1u;
                continue;
            }
            if hit_right {
                at = node.first;
                continue;
            }
        } else {
            for (var k = node.first; k < node.first + count; k = k + 1u) {
                let id = prim_ids[k];
                if id != skip && hit_prim(ray, sh, id, t_min, t_max).x < t_max {
                    return true;
                }
            }
        }
        if sp == 0u {
            break;
        }
        sp = sp - 1u;
        at = stack[sp];
    }
    return false;
}

/// t_max with +inf lowered to INFINITY (f32::MAX), the miss value of every intersection
/// test: a miss must never be nearer than the bound. NaN stays NaN (nothing is hit).
fn finite_bound(t_max: f32) -> f32 {
    return select(t_max, INFINITY, t_max > INFINITY);
}

/// The nearest hit in (t_min, t_max); of hits at the same t, the lowest primitive id
/// (spheres before triangles). `prim` is PRIM_NONE on a miss.
fn closest_hit(ray: Ray, t_min: f32, t_max: f32) -> Hit {
    let t_hi = finite_bound(t_max);
    if USE_BVH {
        return closest_hit_bvh(ray, t_min, t_hi);
    }
    return closest_hit_all(ray, t_min, t_hi);
}

/// Whether anything but primitive `skip` lies on the ray in (t_min, t_max); stops at the
/// first hit. A convex primitive (a sphere, a flat triangle) cannot shadow a point of its
/// own where N·L > 0, so skipping the one that was hit loses no shadow and removes all
/// self-shadowing, whatever the rounding of the hit point.
fn occluded(ray: Ray, t_min: f32, t_max: f32, skip: u32) -> bool {
    let t_hi = finite_bound(t_max);
    if USE_BVH {
        return occluded_bvh(ray, t_min, t_hi, skip);
    }
    return occluded_all(ray, t_min, t_hi, skip);
}

// ---- shading -----------------------------------------------------------------------------

/// `base^n` for the material's exponent: by squaring when `n_int >= 0` (so lavapipe and
/// Rust agree bit for bit, and 0^0 = 1 on both), else `pow` (differs by a few ULP).
fn phong_power(base: f32, m: Material) -> f32 {
    if m.n_int < 0 {
        return pow(base, m.n);
    }
    var result = 1.0;
    var b = base;
    var e = u32(m.n_int);
    for (var k = 0u; k < 32u; k = k + 1u) {
        if e == 0u {
            break;
        }
        if (e & 1u) != 0u {
            result = result * b;
        }
        b = b * b;
        e = e >> 1u;
    }
    return result;
}

/// The unit geometric normal at hit point `p` (not yet facing the ray).
fn surface_normal(hit: Hit, p: vec3<f32>) -> vec3<f32> {
    if (hit.prim & TRIANGLE_BIT) != 0u {
        let tri = triangles[hit.prim & ~TRIANGLE_BIT];
        return normalize(cross3(tri.b - tri.a, tri.c - tri.a));
    }
    let s = spheres[hit.prim];
    return normalize(p - s.center);
}

/// The material index of the hit primitive.
fn hit_material(hit: Hit) -> u32 {
    if (hit.prim & TRIANGLE_BIT) != 0u {
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
    let tri = triangles[hit.prim & ~TRIANGLE_BIT];
    if tri.normals == FLAT {
        return Shading(n, p);
    }
    let vn = normals[tri.normals];
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
    return Shading(normalize(mixed), lifted);
}

/// The offset origin of a shadow ray from `p` with facing normal `n` (buffers::SHADOW_EPSILON).
fn shadow_origin(p: vec3<f32>, n: vec3<f32>) -> vec3<f32> {
    let scale = max2(max2(abs(p.x), abs(p.y)), max2(abs(p.z), 1.0));
    return p + n * (scale * SHADOW_EPSILON * 64.0);
}

/// SPEC.md's Phong model at a hit: I = Ia·ka + Σ Ip·kd·max(0, N·L) + Ip·ks·max(0, R·V)^n,
/// each term only if the material's model has it, clamped to [0, 1].
fn shade(ray: Ray, hit: Hit) -> vec3<f32> {
    let m = materials[hit_material(hit)];
    let p = ray.origin + ray.dir * hit.t;
    var n = surface_normal(hit, p);
    if dot(n, ray.dir) > 0.0 {
        n = -n;
    }
    let sh = shading_at(hit, p, n);
    var color = params.ambient * m.ka;
    if USES_DIFFUSE && m.model != MODEL_AMBIENT {
        // The view vector is the reversed ray. Not `normalize(ray.origin - p)`: that is
        // origin − (origin + dir·t), which loses low bits to cancellation, and which
        // lavapipe's compiler folds to −dir·t while Rust rounds p first, so the two
        // tracers disagreed in low bits under sharp highlights.
        let v = normalize(-ray.dir);
        for (var k = 0u; k < params.n_lights; k = k + 1u) {
            let light = lights[k];
            let to_light = light.position - p;
            let l = normalize(to_light);
            let ndl = dot(sh.n, l);
            if !(ndl > 0.0) {
                continue;
            }
            if SHADOWS {
                let o = shadow_origin(sh.p, n);
                let d = light.position - o;
                if occluded(Ray(o, d), 0.0, 1.0, hit.prim) {
                    continue;
                }
            }
            color = color + light.color * m.kd * ndl;
            if USES_PHONG && m.model == MODEL_PHONG {
                let r = sh.n * (2.0 * ndl) - l;
                let rv = max0(dot(r, v));
                color = color + light.color * m.ks * phong_power(rv, m);
            }
        }
    }
    return vec3<f32>(clamp01(color.x), clamp01(color.y), clamp01(color.z));
}

/// The colour seen through the point (dx, dy) of pixel (i, j) and, in w, the hit
/// distance (−1 for a miss).
fn trace_sample(i: u32, j: u32, dx: f32, dy: f32) -> vec4<f32> {
    let ray = camera_ray(i, j, dx, dy);
    let hit = closest_hit(ray, 0.0, INFINITY);
    if hit.prim == PRIM_NONE {
        return vec4<f32>(params.background, -1.0);
    }
    return vec4<f32>(shade(ray, hit), hit.t);
}

/// The position of sample s of n along a pixel side: (s + 0.5) / n.
fn sample_offset(s: u32, n: u32) -> f32 {
    return (f32(s) + 0.5) / f32(n);
}

/// The colour of pixel (i, j) and, in w, the hit distance (−1 for a miss). With
/// antialiasing, N = params.samples: the N×N points ((sx + 0.5) / N, (sy + 0.5) / N), rows
/// sy top to bottom, each row sx left to right; their colours summed in that order and
/// divided by N² (a box filter); w is the nearest hit's t (−1 when every sample misses).
/// One sample is one ray through the centre, the image without antialiasing to the bit.
fn trace_pixel(i: u32, j: u32) -> vec4<f32> {
    if !ANTIALIAS {
        return trace_sample(i, j, 0.5, 0.5);
    }
    let n = params.samples;
    var sum = vec3<f32>(0.0, 0.0, 0.0);
    var t_near = -1.0;
    for (var sy = 0u; sy < n; sy = sy + 1u) {
        let dy = sample_offset(sy, n);
        for (var sx = 0u; sx < n; sx = sx + 1u) {
            let dx = sample_offset(sx, n);
            let s = trace_sample(i, j, dx, dy);
            sum = sum + s.xyz;
            if s.w >= 0.0 && (t_near < 0.0 || s.w < t_near) {
                t_near = s.w;
            }
        }
    }
    return vec4<f32>(sum / f32(n * n), t_near);
}

// ---- entry points ------------------------------------------------------------------------

/// One invocation per pixel of the current tile.
@compute @workgroup_size(8, 8, 1)
fn render(@builtin(global_invocation_id) gid: vec3<u32>) {
    if gid.x >= params.tile_width || gid.y >= params.tile_height {
        return;
    }
    image[gid.y * params.tile_width + gid.x] = trace_pixel(params.tile_x + gid.x, params.tile_y + gid.y);
}

/// One invocation per query ray: the nearest hit, as `closest_hit` gives it.
@compute @workgroup_size(64, 1, 1)
fn query(@builtin(global_invocation_id) gid: vec3<u32>) {
    if gid.x >= arrayLength(&rays) {
        return;
    }
    let r = rays[gid.x];
    let h = closest_hit(Ray(r.origin, r.dir), r.t_min, r.t_max);
    hits[gid.x] = HitOut(h.t, h.prim, h.u, h.v);
}
