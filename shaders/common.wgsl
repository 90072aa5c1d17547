// glint's kernel, part 1 of 8: what the parts share. The override constants, the
// constants, the structs shared with Rust and their bindings, the ray and hit records and
// the small helpers.
//
// The kernel is `exact.wgsl` + `common.wgsl` + `prims.wgsl` + `texture.wgsl` + `trace.wgsl` +
// `instance.wgsl` + `whitted.wgsl` + `aov.wgsl`, joined in that order at build time (`src/gpu/mod.rs`,
// `SHADER_SOURCE`). Each part has its mirror in `src/cpu/` with the same stem (`exact.rs`,
// `common.rs`, `prims.rs`, `texture.rs`, `trace.rs`, `whitted.rs`, `aov.rs`): every
// function, with the same name, in
// the same order, with the same operations in the same order. Change both in one commit;
// the GPU-against-CPU tests catch the one that was forgotten.
//
// Rules that keep the two bit-identical on every driver that takes the SPIR-V as written:
// - only `+ - *`, `dot` and comparisons on floats, which Vulkan rounds correctly; every
//   division, square root and normalisation through `div_rn`, `sqrt_rn`, `normalize_rn`
//   (exact.wgsl), a non-integer power through `pow_det`; `fma`, `exp2`, `log2`, `pow` and
//   the trigonometric functions never;
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
/// Some material reflects or transmits (kr or kt) and `max_depth` > 0: secondary rays.
override WHITTED: bool = false;
/// Some light is directional or a spot (else every light is a point light, and `shade`
/// compiles only that).
override LIGHT_KINDS: bool = false;
/// Some triangle is textured (`uvs`, `textures`, `texels`): else `textured` compiles to
/// nothing and no texture buffer is read.
override TEXTURES: bool = false;
/// Some Phong material has a non-integer exponent: `phong_power` needs `pow_det`. Off, the
/// compiler drops `pow_det` from the kernel (present but never run, it cost lavapipe 13 %
/// of the sphere's frame).
override POWERS: bool = true;
/// The scene places meshes again (`[[instances]]`): rays go through the two-level BVH of
/// `instance.wgsl`. Off, none of it is compiled.
override INSTANCES: bool = false;

// ---- constants (each one's story is in `src/buffers.rs`) ------------------------------

const MODEL_AMBIENT: u32 = 0u;
const MODEL_DIFFUSE: u32 = 1u;
const MODEL_PHONG: u32 = 2u;
const TRIANGLE_NAIVE: u32 = 0u;
const TRIANGLE_MOLLER_TRUMBORE: u32 = 1u;
const TRIANGLE_WATERTIGHT: u32 = 2u;
const PRIM_NONE: u32 = 0xffffffffu;
const FLAT: u32 = 0u; // Triangle::normals of a flat triangle
const NO_UVS: u32 = 0u; // Triangle::uvs of an untextured triangle
const NO_TEXTURE: u32 = 0xffffffffu; // TriangleUvs::map_kd / map_ka: no map
const TRIANGLE_BIT: u32 = 0x80000000u;
// f32::MAX: a t that every real hit beats. In hexadecimal: the decimal 3.40282347e38 lies
// above f32::MAX, and Tint (Chrome) refuses a literal that is not representable.
const INFINITY: f32 = 0x1.fffffep+127f;
const SHADOW_EPSILON: f32 = 1.1920929e-7; // see buffers::SHADOW_EPSILON
const BVH_STACK: u32 = 48u; // bvh::MAX_DEPTH: the builder never makes a deeper tree
const TOP_STACK: u32 = 96u; // 2 × BVH_STACK: a top-level path, then a mesh's
const INSTANCE_IDENTITY: u32 = 0x80000000u; // Instance::root of an identity instance
const NO_MATERIAL: u32 = 0xffffffffu; // Instance::material: the mesh's own
const NO_INSTANCE: u32 = 0xffffffffu; // the two-level search is in the top level
const BOX_SLACK: f32 = 4.76837158e-7; // 4 ε ≥ 2γ(3): pbrt's conservative slab test
const NAIVE_MIN_SIN2: f32 = 1.9073486e-6; // 16 ε: see buffers::NAIVE_MIN_SIN2
const FLUSH_BELOW: f32 = 1.17549435e-38; // 2^-126, the smallest normal f32: see buffers::FLUSH_BELOW

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
    max_depth: u32,
    min_weight: f32,
    n_instances: u32,
    _pad1: u32,
    _pad2: u32,
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
    uvs: u32,
}

struct VertexNormals {
    na: vec3<f32>,
    _pad0: u32,
    nb: vec3<f32>,
    _pad1: u32,
    nc: vec3<f32>,
    _pad2: u32,
}

struct TriangleUvs {
    uv_a: vec2<f32>,
    uv_b: vec2<f32>,
    uv_c: vec2<f32>,
    map_kd: u32,
    map_ka: u32,
}

struct Texture {
    offset: u32,
    width: u32,
    height: u32,
    _pad0: u32,
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
    kr: vec3<f32>,
    ior: f32,
    kt: vec3<f32>,
    fresnel: u32,
}

struct Light {
    position: vec3<f32>,
    kind: u32,
    color: vec3<f32>,
    cos_outer: f32,
    direction: vec3<f32>,
    cos_inner: f32,
}

const LIGHT_POINT: u32 = 0u;
const LIGHT_DIRECTIONAL: u32 = 1u;
const LIGHT_SPOT: u32 = 2u;

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
/// The textured triangles' texture coordinates (entry 0 unused): read by `shade` only.
@group(0) @binding(15) var<storage, read> uvs: array<TriangleUvs>;
/// The textures, in words: each texture's place (a `Texture`, four words), then every
/// texture's linear RGB texels as f32 bit patterns, three each, rows bottom to top. One
/// buffer, so that `render` binds ten storage buffers (WebGPU's adapters offer 8 to 10).
@group(0) @binding(17) var<storage, read> texels: array<u32>;
/// The lean frame (`render_rgba8`): each pixel's colour as `pack_rgba8` gives it.
@group(0) @binding(14) var<storage, read_write> image_rgba8: array<u32>;

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
    inst: u32,
}

/// `x` when `x > 0`, else 0 (NaN gives 0).
fn max0(x: f32) -> f32 {
    return select(0.0, x, x > 0.0);
}

/// The larger of `a` and `b` (`b` when either is NaN).
fn max2(a: f32, b: f32) -> f32 {
    return select(b, a, a > b);
}

/// `x`, or 0 where |x| is below the smallest normal f32: what a driver that flushes
/// subnormals computes, made explicit so that every driver agrees (buffers::FLUSH_BELOW).
fn flush(x: f32) -> f32 {
    return select(x, 0.0, abs(x) < FLUSH_BELOW);
}

/// `flush` of each component.
fn flush3(v: vec3<f32>) -> vec3<f32> {
    return vec3<f32>(flush(v.x), flush(v.y), flush(v.z));
}

/// `x` clamped to [0, 1] (NaN gives 0).
fn clamp01(x: f32) -> f32 {
    return select(select(x, 1.0, x > 1.0), 0.0, !(x > 0.0));
}

/// One channel to 8 bits, as the PNG holds it: clamped to [0, 1] (NaN gives 0), scaled
/// by 255, rounded half up.
fn to_u8(x: f32) -> u32 {
    return u32(clamp01(x) * 255.0 + 0.5);
}

/// A colour as four bytes, red in the lowest: `to_u8` of r, g, b, and an opaque alpha.
fn pack_rgba8(c: vec4<f32>) -> u32 {
    return to_u8(c.x) | (to_u8(c.y) << 8u) | (to_u8(c.z) << 16u) | (255u << 24u);
}

/// `a × b`, written out so that both tracers round the same products.
fn cross3(a: vec3<f32>, b: vec3<f32>) -> vec3<f32> {
    return vec3<f32>(a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x);
}

/// Whether `t` lies in the open interval (t_min, t_max); false for NaN.
fn in_interval(t: f32, t_min: f32, t_max: f32) -> bool {
    return t > t_min && t < t_max;
}
