//! The TOML scene format as serde reads it (docs/scene-format.md). Unknown keys are
//! errors; values that need checking keep their position (`Spanned`) so that an error can
//! name the line.

use std::collections::BTreeMap;

use serde::Deserialize;
use toml::Spanned;

/// A 3-vector as written in the file.
pub type Vec3File = Spanned<[f32; 3]>;

/// The whole file.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SceneFile {
    /// Ia.
    pub ambient: Option<Vec3File>,
    /// Colour of rays that hit nothing.
    pub background: Option<Vec3File>,
    /// `naive`, `moller-trumbore` or `watertight`.
    pub triangle: Option<Spanned<String>>,
    /// Hard shadows.
    pub shadows: Option<bool>,
    /// The most reflections plus refractions along a path (0..=16, default 5).
    pub max_depth: Option<Spanned<i64>>,
    /// Secondary rays of a smaller weight are not traced (≥ 0, default 1/255).
    pub min_weight: Option<Spanned<f32>>,
    /// The camera.
    pub camera: Spanned<CameraFile>,
    /// Point lights.
    #[serde(default)]
    pub lights: Vec<Spanned<LightFile>>,
    /// Named materials.
    #[serde(default)]
    pub materials: BTreeMap<String, Spanned<MaterialFile>>,
    /// Spheres.
    #[serde(default)]
    pub spheres: Vec<Spanned<SphereFile>>,
    /// Triangles.
    #[serde(default)]
    pub triangles: Vec<Spanned<TriangleFile>>,
    /// OBJ meshes.
    #[serde(default)]
    pub meshes: Vec<Spanned<MeshFile>>,
    /// Named meshes placed again.
    #[serde(default)]
    pub instances: Vec<Spanned<InstanceFile>>,
    /// How the image is written.
    pub output: Option<OutputFile>,
}

/// `[output]`.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct OutputFile {
    /// A PNG's bytes: `linear` (the default) or `srgb`.
    pub encoding: Option<Spanned<String>>,
}

/// `[camera]`.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CameraFile {
    /// Position.
    pub eye: Vec3File,
    /// Point looked at.
    pub look_at: Vec3File,
    /// Up hint.
    pub up: Option<Vec3File>,
    /// Vertical field of view, degrees.
    pub fov: Spanned<f32>,
    /// Image width.
    pub width: Spanned<i64>,
    /// Image height.
    pub height: Spanned<i64>,
    /// Antialiasing: N gives N×N rays per pixel (default 1).
    pub samples: Option<Spanned<i64>>,
    /// `[[camera.keys]]`: the camera path ([`crate::scene::camera_path`]).
    pub keys: Option<Vec<Spanned<CameraKeyFile>>>,
}

/// `[[camera.keys]]`: one key of the camera path.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CameraKeyFile {
    /// The frame number.
    pub frame: Spanned<i64>,
    /// Position (default: the previous key's).
    pub eye: Option<Vec3File>,
    /// Point looked at (default: the previous key's).
    pub look_at: Option<Vec3File>,
    /// Up hint (default: the previous key's).
    pub up: Option<Vec3File>,
    /// Vertical field of view, degrees (default: the previous key's).
    pub fov: Option<Spanned<f32>>,
}

/// `[[lights]]`.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct LightFile {
    /// `point` (the default), `directional` or `spot`.
    pub kind: Option<Spanned<String>>,
    /// Position (point and spot lights).
    pub position: Option<Vec3File>,
    /// Where the light shines (directional and spot lights).
    pub direction: Option<Vec3File>,
    /// A spot's half-angle, degrees.
    pub angle: Option<Spanned<f32>>,
    /// A spot's soft edge, degrees inside `angle`.
    pub falloff: Option<Spanned<f32>>,
    /// Ip.
    pub color: Vec3File,
}

/// `[materials.NAME]`.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MaterialFile {
    /// `ambient`, `diffuse` or `phong`.
    pub model: Spanned<String>,
    /// Ambient reflectance.
    pub ka: Vec3File,
    /// Diffuse reflectance (needed by `diffuse` and `phong`).
    pub kd: Option<Vec3File>,
    /// Specular reflectance (needed by `phong`).
    pub ks: Option<Vec3File>,
    /// Phong exponent (needed by `phong`).
    pub n: Option<Spanned<f32>>,
    /// Mirror reflectance.
    pub kr: Option<Vec3File>,
    /// Transmittance (needs `ior`).
    pub kt: Option<Vec3File>,
    /// Index of refraction, > 0.
    pub ior: Option<Spanned<f32>>,
    /// Weight kr and kt by the dielectric Fresnel reflectance.
    pub fresnel: Option<bool>,
    /// An image (PNG or JPEG, relative to the scene file) whose colour multiplies kd, and
    /// ka unless `map_ka` is given, on triangles with `uvs`.
    pub map_kd: Option<Spanned<String>>,
    /// An image whose colour multiplies ka on triangles with `uvs`.
    pub map_ka: Option<Spanned<String>>,
}

/// `[[spheres]]`.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SphereFile {
    /// Centre.
    pub center: Vec3File,
    /// Radius.
    pub radius: Spanned<f32>,
    /// Material name.
    pub material: Spanned<String>,
}

/// `[[triangles]]`.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct TriangleFile {
    /// Three vertices.
    pub vertices: Spanned<[[f32; 3]; 3]>,
    /// Material name.
    pub material: Spanned<String>,
    /// Texture coordinates (u, v) at the three vertices, v up.
    pub uvs: Option<Spanned<[[f32; 2]; 3]>>,
}

/// `[[meshes]]`.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MeshFile {
    /// The mesh file (`.obj`, `.ply`, optionally `.gz`), relative to the scene file.
    pub file: Spanned<String>,
    /// Material name; optional when the OBJ has an MTL.
    pub material: Option<Spanned<String>>,
    /// Per-axis scale.
    pub scale: Option<Vec3File>,
    /// Rotation in degrees about x, then y, then z.
    pub rotate: Option<Vec3File>,
    /// Translation.
    pub translate: Option<Vec3File>,
    /// Shade with interpolated vertex normals (the OBJ's `vn`, else computed).
    pub smooth: Option<bool>,
    /// The name `[[instances]]` place it by.
    pub name: Option<Spanned<String>>,
    /// Drawn only where an instance places it (default false).
    pub hidden: Option<Spanned<bool>>,
}

/// `[[instances]]`: a named mesh placed again.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct InstanceFile {
    /// The `[[meshes]]` entry's name.
    pub mesh: Spanned<String>,
    /// Per-axis scale (no component 0).
    pub scale: Option<Vec3File>,
    /// Rotation in degrees about x, then y, then z.
    pub rotate: Option<Vec3File>,
    /// Translation.
    pub translate: Option<Vec3File>,
    /// The whole object-to-world map as three rows `[m0, m1, m2, t]`, instead of `scale`,
    /// `rotate` and `translate`.
    pub matrix: Option<Spanned<[[f64; 4]; 3]>>,
    /// A material that replaces the mesh's own for this instance.
    pub material: Option<Spanned<String>>,
}
