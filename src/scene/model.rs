//! The scene's model: cameras, lights, materials and primitives as validated, and the
//! limits on their values.

use super::*;

/// The largest width or height accepted (the GPU renders larger frames in tiles).
pub const MAX_IMAGE_SIDE: i64 = 32_768;

/// The largest `[camera] samples` (per pixel side): the contract's [`crate::shared::layout::MAX_SAMPLES`].
pub const MAX_SAMPLES: u32 = crate::shared::layout::MAX_SAMPLES;

/// Ray/triangle intersection algorithm.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum TriangleAlgorithm {
    /// The seed's plane + barycentric test.
    Naive,
    /// Möller–Trumbore.
    MollerTrumbore,
    /// Woop, Benthin and Wald's watertight test.
    Watertight,
}

impl TriangleAlgorithm {
    /// All three, in the order of their codes.
    pub const ALL: [TriangleAlgorithm; 3] = [
        TriangleAlgorithm::Naive,
        TriangleAlgorithm::MollerTrumbore,
        TriangleAlgorithm::Watertight,
    ];

    /// The `TRIANGLE_ALGO` code of `shared::layout`.
    pub fn code(self) -> u32 {
        match self {
            TriangleAlgorithm::Naive => crate::shared::layout::TRIANGLE_NAIVE,
            TriangleAlgorithm::MollerTrumbore => crate::shared::layout::TRIANGLE_MOLLER_TRUMBORE,
            TriangleAlgorithm::Watertight => crate::shared::layout::TRIANGLE_WATERTIGHT,
        }
    }

    /// The name used in scene files and on the command line.
    pub fn name(self) -> &'static str {
        match self {
            TriangleAlgorithm::Naive => "naive",
            TriangleAlgorithm::MollerTrumbore => "moller-trumbore",
            TriangleAlgorithm::Watertight => "watertight",
        }
    }
}

impl FromStr for TriangleAlgorithm {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        match s {
            "naive" => Ok(TriangleAlgorithm::Naive),
            "moller-trumbore" => Ok(TriangleAlgorithm::MollerTrumbore),
            "watertight" => Ok(TriangleAlgorithm::Watertight),
            _ => Err(format!(
                "unknown triangle algorithm {s:?}: expected naive, moller-trumbore or watertight"
            )),
        }
    }
}

impl std::fmt::Display for TriangleAlgorithm {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

/// A material's shading model: which terms of the Phong sum it computes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Model {
    /// Ia·ka only.
    Ambient,
    /// Ambient + diffuse.
    Diffuse,
    /// Ambient + diffuse + specular.
    Phong,
}

/// The camera, as the file gives it.
#[derive(Clone, Debug, PartialEq)]
pub struct Camera {
    /// Position.
    pub eye: [f32; 3],
    /// Point looked at (≠ eye).
    pub look_at: [f32; 3],
    /// Up hint (not parallel to the view).
    pub up: [f32; 3],
    /// Vertical field of view in degrees, in (0, 180).
    pub fov: f32,
    /// Image width in pixels.
    pub width: u32,
    /// Image height in pixels.
    pub height: u32,
    /// Samples per pixel side, 1..=`MAX_SAMPLES`: N×N rays per pixel on a fixed grid, their
    /// colours averaged (1: one ray through the centre).
    pub samples: u32,
}

/// What kind of light, and its geometry beyond the position.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub enum LightKind {
    /// A point light at `Light::position`, shining every way (the default).
    #[default]
    Point,
    /// A light at infinity shining along `direction` (any length but zero): the same
    /// direction at every point, and shadow rays that go on without end.
    Directional {
        /// Where the light travels.
        direction: [f32; 3],
    },
    /// A point light at `Light::position` shining along `direction` within `angle`
    /// degrees of it: full within `angle − falloff`, none beyond `angle`, and between the
    /// two a smoothstep in the cosine (docs/features.md, "Directional and spot lights").
    Spot {
        /// The spot's axis (any length but zero).
        direction: [f32; 3],
        /// The half-angle, degrees, in (0, 90].
        angle: f32,
        /// The soft edge, degrees, in [0, angle].
        falloff: f32,
    },
}

/// A light.
#[derive(Clone, Debug, PartialEq)]
pub struct Light {
    /// What kind of light it is.
    pub kind: LightKind,
    /// Position (unused by a directional light).
    pub position: [f32; 3],
    /// Colour Ip.
    pub color: [f32; 3],
}

/// A named material.
#[derive(Clone, Debug, PartialEq)]
pub struct Material {
    /// Its name in the file (or in the MTL).
    pub name: String,
    /// Which terms it computes.
    pub model: Model,
    /// Ambient reflectance.
    pub ka: [f32; 3],
    /// Diffuse reflectance.
    pub kd: [f32; 3],
    /// Specular reflectance.
    pub ks: [f32; 3],
    /// Phong exponent, ≥ 0.
    pub n: f32,
    /// What it does to secondary rays (nothing by default).
    pub optics: Optics,
    /// The texture (an index into `Scene::textures`) whose colour multiplies kd on
    /// textured triangles, and ka too unless `map_ka` is set.
    pub map_kd: Option<u32>,
    /// The texture whose colour multiplies ka on textured triangles.
    pub map_ka: Option<u32>,
}

impl Material {
    /// The textures that multiply (ka, kd): `map_ka` or else `map_kd` for ka (POV-Ray's
    /// pigment: the texture colours the ambient term too), `map_kd` for kd.
    pub fn maps(&self) -> (Option<u32>, Option<u32>) {
        (self.map_ka.or(self.map_kd), self.map_kd)
    }
}

/// What a material does to secondary rays (Whitted): the local terms stay what they are,
/// and kr·L(reflected) + kt·L(refracted) is added.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Optics {
    /// Mirror reflectance.
    pub kr: [f32; 3],
    /// Transmittance.
    pub kt: [f32; 3],
    /// Index of refraction (the outside medium is 1), > 0.
    pub ior: f32,
    /// Weights kr·F and kt·(1 − F), F the exact unpolarised dielectric Fresnel
    /// reflectance; else kr and kt as given.
    pub fresnel: bool,
}

impl Default for Optics {
    /// No reflection, no transmission, index 1, no Fresnel.
    fn default() -> Optics {
        Optics {
            kr: [0.0; 3],
            kt: [0.0; 3],
            ior: 1.0,
            fresnel: false,
        }
    }
}

/// The default `max_depth`: the most reflections plus refractions along a path.
pub const DEFAULT_MAX_DEPTH: u32 = 5;

/// The largest `max_depth` (the shader's stack holds max_depth + 1 rays).
pub const MAX_DEPTH: u32 = crate::shared::layout::MAX_WHITTED_DEPTH;

/// The default `min_weight`, 1/255 (POV-Ray's adaptive depth control): a secondary ray
/// whose weight's largest channel is below it is not traced.
pub const DEFAULT_MIN_WEIGHT: f32 = 1.0 / 255.0;

/// A sphere.
#[derive(Clone, Debug, PartialEq)]
pub struct Sphere {
    /// Centre.
    pub center: [f32; 3],
    /// Radius, > 0.
    pub radius: f32,
    /// Index into `Scene::materials`.
    pub material: u32,
}

/// A triangle.
#[derive(Clone, Debug, PartialEq)]
pub struct Triangle {
    /// a, b, c.
    pub vertices: [[f32; 3]; 3],
    /// Index into `Scene::materials`.
    pub material: u32,
}

/// The vertex normals of one smooth mesh's triangles.
#[derive(Clone, Debug, PartialEq)]
pub struct SmoothNormals {
    /// Index in `Scene::triangles` of the mesh's first triangle.
    pub first: usize,
    /// Unit normals at a, b and c of each of the mesh's triangles, in order.
    pub normals: Vec<[[f32; 3]; 3]>,
}

/// The texture coordinates of a run of textured triangles (a mesh's, or one
/// `[[triangles]]` entry's).
#[derive(Clone, Debug, PartialEq)]
pub struct TextureCoords {
    /// Index in `Scene::triangles` of the run's first triangle.
    pub first: usize,
    /// (u, v) at a, b and c of each triangle of the run, in order; v up (OBJ's convention).
    pub uvs: Vec<[[f32; 2]; 3]>,
}

/// The largest colour component (light colour, ka, kd, ks, ambient, background) a scene
/// may give. Shading sums, per light, products of a light colour and a reflectance: with
/// both at most 1e6, a term is at most 1e12 and no sum of them overflows f32 (an infinite
/// term times a zero factor would make NaN, written as black). Every physical scene is far
/// below it.
pub const MAX_COLOUR: f32 = 1e6;

/// A `[[meshes]]` entry with a `name`: the triangles it placed, which `[[instances]]`
/// place again (their object space is the mesh as its own entry placed it).
#[derive(Clone, Debug, PartialEq)]
pub struct NamedMesh {
    /// The entry's `name`.
    pub name: String,
    /// Its triangles in [`Scene::triangles`].
    pub triangles: std::ops::Range<usize>,
    /// Drawn only where an instance places it (`hidden = true`).
    pub hidden: bool,
}

/// An affine map as the tracers read it: three rows `[m0, m1, m2, t]`, so that a point
/// `p` maps to `(m0·p.x + m1·p.y) + m2·p.z + t` per row.
pub type Affine = [[f32; 4]; 3];

/// The identity map.
pub const IDENTITY: Affine = [
    [1.0, 0.0, 0.0, 0.0],
    [0.0, 1.0, 0.0, 0.0],
    [0.0, 0.0, 1.0, 0.0],
];

/// An `[[instances]]` entry: a named mesh placed again.
///
/// Both maps are computed in f64 from the entry's scale, rotation and translation and
/// rounded to f32 once: `to_world` = T·R·S, `to_object` = S⁻¹·Rᵀ·T⁻¹. They are the scene's
/// values, as a triangle's f32 vertices are; the tracers take rays into object space by
/// `to_object` and carry shading back by `to_world` (vertices) and `to_object`ᵀ (normals).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Instance {
    /// The mesh: an index into [`Scene::named`].
    pub mesh: usize,
    /// Object space to world space.
    pub to_world: Affine,
    /// World space to object space.
    pub to_object: Affine,
    /// The material that replaces the mesh's own, if any.
    pub material: Option<u32>,
}
