//! The contract at the bottom: the flat `#[repr(C)]` structs that `shaders/trace.wgsl`
//! declares and both tracers read, and the codes and constants the shader names. Imports
//! nothing from glint.
//!
//! Every struct here names the WGSL struct it must match; `tests/layout.rs` parses the
//! shader with naga and checks each size and field offset against `size_of`/`offset_of!`.
//! WGSL's `vec3<f32>` is 16-byte aligned, so each `[f32; 3]` is followed by a 4-byte field
//! or an explicit `_pad`.

use bytemuck::{Pod, Zeroable};

/// Material model `ambient`: only Ia·ka.
pub const MODEL_AMBIENT: u32 = 0;
/// Material model `diffuse`: ambient + diffuse.
pub const MODEL_DIFFUSE: u32 = 1;
/// Material model `phong`: ambient + diffuse + specular.
pub const MODEL_PHONG: u32 = 2;

/// `TRIANGLE_ALGO` for the seed's plane + barycentric test.
pub const TRIANGLE_NAIVE: u32 = 0;
/// `TRIANGLE_ALGO` for Möller–Trumbore.
pub const TRIANGLE_MOLLER_TRUMBORE: u32 = 1;
/// `TRIANGLE_ALGO` for the watertight test of Woop, Benthin and Wald.
pub const TRIANGLE_WATERTIGHT: u32 = 2;

/// `Triangle::normals` of a flat triangle (one shaded with its geometric normal). WGSL: `FLAT`.
pub const FLAT: u32 = 0;

/// The largest `samples` per pixel side (`[camera] samples`): 16×16 = 256 rays a pixel.
pub const MAX_SAMPLES: u32 = 16;

/// WGSL `WHITTED_STACK` (`shaders/whitted.wgsl`): the most secondary rays waiting at once.
pub const WHITTED_STACK: u32 = 17;

/// The largest `max_depth` a scene may ask for: the stack holds max_depth + 1 rays.
pub const MAX_WHITTED_DEPTH: u32 = WHITTED_STACK - 1;

/// `Hit::prim` of a miss.
pub const PRIM_NONE: u32 = 0xffff_ffff;
/// Set in `Hit::prim` when the index is a triangle's (else it is a sphere's).
pub const TRIANGLE_BIT: u32 = 0x8000_0000;
/// `Instance::root` bit of an instance whose maps are both the identity (neither is
/// applied). WGSL: `INSTANCE_IDENTITY`.
pub const INSTANCE_IDENTITY: u32 = 0x8000_0000;
/// `Instance::material` of an instance shaded with its mesh's own materials. WGSL:
/// `NO_MATERIAL`.
pub const NO_MATERIAL: u32 = 0xffff_ffff;
/// The two-level search's instance while it is in the top level. WGSL: `NO_INSTANCE`.
pub const NO_INSTANCE: u32 = 0xffff_ffff;

/// The `t` of "no hit yet": `f32::MAX`, so that every finite hit beats it and no
/// arithmetic on it makes an infinity. WGSL: `INFINITY`.
pub const INFINITY: f32 = f32::MAX;

/// The relative size of a shadow ray's offset along the normal, in units of the hit
/// point's largest coordinate (at least 1): 64 ε of f32, about 7.6e-6. WGSL: `SHADOW_EPSILON * 64`.
pub const SHADOW_EPSILON: f32 = f32::EPSILON;

/// The relative slack of the BVH's box test: 2γ(3) = 6u/(1 − 3u) with u = 2^-24, rounded
/// up to 4 ε (pbrt's conservative slab test). WGSL: `BOX_SLACK`.
pub const BOX_SLACK: f32 = 4.0 * f32::EPSILON;

/// The naive test's sliver bound: a triangle whose `d00·d11 − d01²` (|e_ab|²·|e_ac|²·sin²θ)
/// is at most 16 ε of `d00·d11` is a miss, as a degenerate one is. Below it the
/// difference is mostly rounding (each of the two products is good to about 7 ε), so the
/// barycentric coordinates are noise: such slivers (θ below about 0.08°) filled most of a
/// frame with false hits, and more or fewer of them through the BVH than by testing every
/// primitive (`tests/slivers.rs`). WGSL: `NAIVE_MIN_SIN2`.
pub const NAIVE_MIN_SIN2: f32 = 16.0 * f32::EPSILON;

/// The smallest normal f32 (2^-126): a shading term below it is taken as 0 (WGSL
/// `flush`), on every tracer. Mesa's lavapipe flushes subnormal results and operands to
/// zero in compute shaders from 26.1 on (the worker threads run with x86's FTZ and DAZ), as
/// most GPUs may; 22.3 and 25.0 keep them. Flushing explicitly where glint's values can
/// become subnormal (the Phong power of a small base, and the products that scale it) makes
/// the image the same on both kinds of driver and on the CPU. WGSL: `FLUSH_BELOW`.
pub const FLUSH_BELOW: f32 = f32::MIN_POSITIVE;

/// Veltkamp's splitter for f32 (2^12 + 1), used by Dekker's exact product. WGSL: `SPLITTER`.
pub const SPLITTER: f32 = 4097.0;

/// Per-frame constants. Must match WGSL `struct Params` (128 bytes).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct Params {
    /// Camera position. Offset 0.
    pub eye: [f32; 3],
    /// Image width in pixels. Offset 12.
    pub width: u32,
    /// Unit view direction. Offset 16.
    pub forward: [f32; 3],
    /// Image height in pixels. Offset 28.
    pub height: u32,
    /// Unit right vector. Offset 32.
    pub right: [f32; 3],
    /// tan(fov / 2), computed in Rust. Offset 44.
    pub tan_half: f32,
    /// Camera up, `cross(right, forward)`. Offset 48.
    pub up: [f32; 3],
    /// width / height. Offset 60.
    pub aspect: f32,
    /// Ia. Offset 64.
    pub ambient: [f32; 3],
    /// Number of spheres in use. Offset 76.
    pub n_spheres: u32,
    /// Colour of rays that hit nothing. Offset 80.
    pub background: [f32; 3],
    /// Number of triangles in use. Offset 92.
    pub n_triangles: u32,
    /// Number of lights. Offset 96.
    pub n_lights: u32,
    /// Left column of the tile being rendered. Offset 100.
    pub tile_x: u32,
    /// Top row of the tile being rendered. Offset 104.
    pub tile_y: u32,
    /// Tile width in pixels. Offset 108.
    pub tile_width: u32,
    /// Tile height in pixels. Offset 112.
    pub tile_height: u32,
    /// Number of BVH nodes (0 for an empty scene). Offset 116.
    pub n_nodes: u32,
    /// Samples per pixel side: N gives N×N rays per pixel, read only when the pipeline's
    /// `ANTIALIAS` is on (N > 1); 1 is one ray through the pixel's centre. Offset 120.
    pub samples: u32,
    /// The most reflections plus refractions along a path (the scene's `max_depth`), read
    /// only when the pipeline's `WHITTED` is on. Offset 124.
    pub max_depth: u32,
    /// A secondary ray whose weight's largest channel is below this is not traced (the
    /// scene's `min_weight`; 0 traces every one). Offset 128.
    pub min_weight: f32,
    /// Number of instances (0 without `[[instances]]`); each is four node slots after
    /// the `n_nodes` nodes. Offset 132.
    pub n_instances: u32,
    /// Offset 136.
    pub _pad1: u32,
    /// Offset 140.
    pub _pad2: u32,
}

/// A sphere. Must match WGSL `struct Sphere` (32 bytes).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct Sphere {
    /// Centre. Offset 0.
    pub center: [f32; 3],
    /// Radius, > 0. Offset 12.
    pub radius: f32,
    /// Index into the material buffer. Offset 16.
    pub material: u32,
    /// Offset 20.
    pub _pad0: u32,
    /// Offset 24.
    pub _pad1: u32,
    /// Offset 28.
    pub _pad2: u32,
}

/// A triangle. Must match WGSL `struct Triangle` (48 bytes).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct Triangle {
    /// First vertex. Offset 0.
    pub a: [f32; 3],
    /// Index into the material buffer. Offset 12.
    pub material: u32,
    /// Second vertex. Offset 16.
    pub b: [f32; 3],
    /// Index of its [`VertexNormals`] in the normals buffer, or [`FLAT`] (0: the buffer's
    /// entry 0 is never used) for a triangle shaded with its geometric normal. Read only
    /// when the pipeline's `SMOOTH` is on. Offset 28.
    pub normals: u32,
    /// Third vertex. Offset 32.
    pub c: [f32; 3],
    /// Index of its [`TriangleUvs`] in the uvs buffer, or [`NO_UVS`] (0: the buffer's
    /// entry 0 is never used) for an untextured triangle. Read only when the pipeline's
    /// `TEXTURES` is on. Offset 44.
    pub uvs: u32,
}

/// `Triangle::uvs` of an untextured triangle. WGSL: `NO_UVS`.
pub const NO_UVS: u32 = 0;

/// `TriangleUvs::map_kd` or `map_ka` where the material has no such map. WGSL: `NO_TEXTURE`.
pub const NO_TEXTURE: u32 = 0xffff_ffff;

/// A textured triangle's texture coordinates at a, b and c (v up, OBJ's convention) and
/// the textures its material applies. Must match WGSL `struct TriangleUvs` (32 bytes).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct TriangleUvs {
    /// (u, v) at a. Offset 0.
    pub uv_a: [f32; 2],
    /// (u, v) at b. Offset 8.
    pub uv_b: [f32; 2],
    /// (u, v) at c. Offset 16.
    pub uv_c: [f32; 2],
    /// The texture that multiplies kd (an index into the textures buffer), or
    /// [`NO_TEXTURE`]. Offset 24.
    pub map_kd: u32,
    /// The texture that multiplies ka, or [`NO_TEXTURE`]. Offset 28.
    pub map_ka: u32,
}

/// Where a texture's texels lie in the texels buffer. Must match WGSL `struct Texture`
/// (16 bytes).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct Texture {
    /// The index in the texels buffer (of f32s) of its first texel's red. Offset 0.
    pub offset: u32,
    /// Texels a row. Offset 4.
    pub width: u32,
    /// Rows, bottom (v = 0) first. Offset 8.
    pub height: u32,
    /// Offset 12.
    pub _pad0: u32,
}

/// The unit vertex normals of a smooth triangle, at a, b and c (the mesh's, transformed by
/// the inverse transpose). Must match WGSL `struct VertexNormals` (48 bytes).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct VertexNormals {
    /// Normal at a. Offset 0.
    pub na: [f32; 3],
    /// Offset 12.
    pub _pad0: u32,
    /// Normal at b. Offset 16.
    pub nb: [f32; 3],
    /// Offset 28.
    pub _pad1: u32,
    /// Normal at c. Offset 32.
    pub nc: [f32; 3],
    /// Offset 44.
    pub _pad2: u32,
}

/// A node of the flattened BVH (see [`crate::bvh`]). Must match WGSL `struct BvhNode`
/// (32 bytes).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct BvhNode {
    /// Lower corner of the box. Offset 0.
    pub lo: [f32; 3],
    /// Interior: index of the second child (the first is the next node). Leaf: index of
    /// the first primitive id in `prim_ids`. Offset 12.
    pub first: u32,
    /// Upper corner of the box. Offset 16.
    pub hi: [f32; 3],
    /// `count << 2 | axis`: a leaf has count > 0 (and axis 0); an interior node has
    /// count 0 and its split axis, which orders the visit. Offset 28.
    pub count_axis: u32,
}

/// An instance: a mesh's BVH placed by an affine map (see `shaders/instance.wgsl`). The
/// kernel reads it from four [`BvhNode`] slots after the nodes (WGSL `instance_at`), so
/// that `render` binds no more storage buffers; each integer sits where a slot holds a
/// `u32` (`first` or `count_axis`), never where it holds a float. 128 bytes.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct Instance {
    /// World to object space, rows `[m0, m1, m2, t]`. Offset 0.
    pub to_object: [[f32; 4]; 3],
    /// Object to world space, rows `[m0, m1, m2, t]`. Offset 48.
    pub to_world: [[f32; 4]; 3],
    /// Offset 96.
    pub _pad0: [u32; 3],
    /// The root node of the mesh's BVH, with [`INSTANCE_IDENTITY`] where both maps are
    /// the identity. Offset 108 (the fourth slot's `first`).
    pub root: u32,
    /// Offset 112.
    pub _pad1: [u32; 3],
    /// The material replacing the mesh's, or [`NO_MATERIAL`]. Offset 124 (the fourth
    /// slot's `count_axis`).
    pub material: u32,
}

/// A material. Must match WGSL `struct Material` (80 bytes).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct Material {
    /// Ambient reflectance. Offset 0.
    pub ka: [f32; 3],
    /// `MODEL_AMBIENT`, `MODEL_DIFFUSE` or `MODEL_PHONG`. Offset 12.
    pub model: u32,
    /// Diffuse reflectance. Offset 16.
    pub kd: [f32; 3],
    /// Phong exponent. Offset 28.
    pub n: f32,
    /// Specular reflectance. Offset 32.
    pub ks: [f32; 3],
    /// `n` as an integer when it is one (0..=2^24), else −1: then the power is taken by
    /// squaring, identically on both tracers. Offset 44.
    pub n_int: i32,
    /// Mirror reflectance, kr. Offset 48.
    pub kr: [f32; 3],
    /// Index of refraction (1 where the material transmits nothing). Offset 60.
    pub ior: f32,
    /// Transmittance, kt. Offset 64.
    pub kt: [f32; 3],
    /// 1: kr and kt are weighted by the dielectric Fresnel reflectance F (kr·F, kt·(1 − F));
    /// 0: used as given. Offset 76.
    pub fresnel: u32,
}

/// [`Light::kind`] of a point light.
pub const LIGHT_POINT: u32 = 0;
/// [`Light::kind`] of a directional light.
pub const LIGHT_DIRECTIONAL: u32 = 1;
/// [`Light::kind`] of a spot light.
pub const LIGHT_SPOT: u32 = 2;

/// A light. Must match WGSL `struct Light` (48 bytes).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct Light {
    /// Position (point and spot lights). Offset 0.
    pub position: [f32; 3],
    /// `LIGHT_POINT`, `LIGHT_DIRECTIONAL` or `LIGHT_SPOT`. Offset 12.
    pub kind: u32,
    /// Colour, Ip. Offset 16.
    pub color: [f32; 3],
    /// A spot's cosine of its angle: no light at or beyond it. Offset 28.
    pub cos_outer: f32,
    /// The unit direction the light travels (directional and spot lights; zero for a
    /// point light). Offset 32.
    pub direction: [f32; 3],
    /// A spot's cosine of its angle less its falloff: full light from it in. Offset 44.
    pub cos_inner: f32,
}

/// A ray for the `query` entry point. Must match WGSL `struct RayIn` (32 bytes).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct RayIn {
    /// Origin. Offset 0.
    pub origin: [f32; 3],
    /// Hits at t ≤ t_min are ignored. Offset 12.
    pub t_min: f32,
    /// Direction (any length). Offset 16.
    pub dir: [f32; 3],
    /// Hits at t ≥ t_max are ignored. Offset 28.
    pub t_max: f32,
}

/// One pixel's arbitrary output variables (AOVs): what the primary ray through the pixel's
/// centre hit, written by WGSL `render_aov` and its mirror `cpu::aov::aov_pixel`. Must
/// match WGSL `struct AovOut` (64 bytes). On a miss `t` and `depth` are −1, `prim` and
/// `material` are `PRIM_NONE` and the vectors are 0. What each field means, its units and
/// frame: docs/aov.md.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct AovOut {
    /// The hit point, origin + dir·t, world space. Offset 0.
    pub position: [f32; 3],
    /// Distance along the (unit) primary ray. Offset 12.
    pub t: f32,
    /// The geometric normal, unit, turned to face the ray. Offset 16.
    pub geo_normal: [f32; 3],
    /// Camera-space depth: t · (dir · forward), along the camera's forward axis. Offset 28.
    pub depth: f32,
    /// The shading normal: the geometric one, or the interpolated vertex normals of a
    /// smooth triangle, turned to the geometric normal's side. Offset 32.
    pub normal: [f32; 3],
    /// The primitive hit, as `HitOut::prim` (`TRIANGLE_BIT` for triangles). Offset 44.
    pub prim: u32,
    /// kd after textures (the diffuse albedo). Offset 48.
    pub albedo: [f32; 3],
    /// The material's index in [`crate::scene::Scene::materials`]. Offset 60.
    pub material: u32,
}

/// The answer to one query ray. Must match WGSL `struct HitOut` (16 bytes).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct HitOut {
    /// Distance along the ray (in units of |dir|); t_max on a miss. Offset 0.
    pub t: f32,
    /// Primitive index, with `TRIANGLE_BIT` for triangles; `PRIM_NONE` on a miss. Offset 4.
    pub prim: u32,
    /// Barycentric weight of vertex b (triangles). Offset 8.
    pub u: f32,
    /// Barycentric weight of vertex c (triangles). Offset 12.
    pub v: f32,
}
