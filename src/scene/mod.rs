//! Scenes: the TOML format, its validation (every error names file, line and key), and
//! OBJ meshes.

pub mod camera_path;
mod error;
mod format;
mod gltf;
mod mesh;
mod obj;
mod ply;
pub mod range;
pub mod set;
pub mod texture;
pub(crate) mod validate;

use std::path::{Path, PathBuf};
use std::str::FromStr;
use std::sync::Arc;

pub use camera_path::{CameraKey, CameraPathError, MAX_FRAME};
pub use error::{SceneError, line_of};
use format::{SceneFile, Vec3File};
pub use gltf::GltfError;
pub use mesh::{FaceError, MeshError};
pub use obj::ObjError;
pub use ply::PlyError;
pub use texture::{Texture, TextureError};
use toml::Spanned;

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

/// A loaded, validated scene.
#[derive(Clone, Debug, PartialEq)]
pub struct Scene {
    /// Where it came from.
    pub path: PathBuf,
    /// Ia.
    pub ambient: [f32; 3],
    /// Colour of rays that hit nothing.
    pub background: [f32; 3],
    /// The scene's triangle algorithm.
    pub triangle: TriangleAlgorithm,
    /// Hard shadows on.
    pub shadows: bool,
    /// The most reflections plus refractions along a path, 0..=[`MAX_DEPTH`].
    pub max_depth: u32,
    /// Secondary rays of a smaller weight (largest channel) are not traced; ≥ 0.
    pub min_weight: f32,
    /// The camera.
    pub camera: Camera,
    /// How a PNG's bytes encode the linear image (`[output] encoding`, default linear);
    /// EXR and in-memory images are always linear.
    pub encoding: crate::shared::encoding::Encoding,
    /// Point lights.
    pub lights: Vec<Light>,
    /// Materials: the file's, sorted by name, then those of MTL files.
    pub materials: Vec<Material>,
    /// Spheres.
    pub spheres: Vec<Sphere>,
    /// Triangles: the file's, then each mesh's.
    pub triangles: Vec<Triangle>,
    /// The vertex normals of the meshes marked `smooth`, in mesh order.
    pub smooth: Vec<SmoothNormals>,
    /// The texture coordinates of the triangles that have them, in triangle order.
    pub uvs: Vec<TextureCoords>,
    /// The textures the materials name (decoded, linear, within the texel budget).
    pub textures: Vec<Texture>,
    /// Every file the scene was read from, in the order read: the scene file, then its
    /// meshes, MTLs, textures and glTF buffers (what a viewer watches for changes).
    pub inputs: Vec<PathBuf>,
    /// Things that are allowed but probably not meant (zero-area triangles, ...), each
    /// naming file, line and key.
    pub warnings: Vec<String>,
    /// Where each sphere was written: `file:line: spheres[i]`.
    pub sphere_sources: Vec<String>,
    /// Where the triangles came from, in order: (index of the first, `file:line: key`),
    /// one entry per `[[triangles]]` and per mesh.
    pub triangle_sources: Vec<(usize, String)>,
    /// The cache the scene was loaded with ([`LoadOptions::cache`]), for the BVH build
    /// ([`crate::buffers::SceneBuffers::new`]) to use too; `None` caches nothing. Scenes
    /// compare equal only when they hold the same cache, or none (a cache equals only
    /// itself: see [`crate::cache::Cache`]).
    pub cache: Option<Arc<crate::cache::Cache>>,
    /// How long each stage of reading it took (read, parse, transform, textures; see
    /// [`crate::stages`]); not part of what the scene is, so scenes compare equal whatever
    /// their reading took.
    pub load_stages: crate::stages::Timings,
    /// The camera path (`[[camera.keys]]`, in increasing frames; empty: none): see
    /// [`Scene::camera_at`].
    pub camera_keys: Vec<CameraKey>,
}

/// How a scene is read: settings as values (the command line makes them from its flags and
/// environment).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct LoadOptions {
    /// The most bytes read from one input file, and unpacked from one `.gz`
    /// ([`DEFAULT_MAX_INPUT_MIB`] MiB by default; `GLINT_MAX_INPUT_MIB` on the command
    /// line). It keeps `/dev/zero`, `/dev/urandom` or a gzip bomb from filling memory.
    pub max_input_bytes: u64,
    /// Read only files below the scene's own folder (after following symbolic links); a
    /// mesh or MTL anywhere else is an error naming it.
    pub confine: bool,
    /// Where large meshes as placed, and large scenes' BVHs, are cached (see
    /// [`crate::cache`]); `None` (the default) caches nothing. The scene keeps it for its
    /// BVH ([`Scene::cache`]).
    pub cache: Option<Arc<crate::cache::Cache>>,
    /// Keys changed before the scene is read (`--set camera.fov=30`), in order; errors and
    /// warnings still name the file's own lines (see [`set`]).
    pub settings: Vec<set::Setting>,
}

impl Default for LoadOptions {
    fn default() -> LoadOptions {
        LoadOptions {
            max_input_bytes: DEFAULT_MAX_INPUT_MIB << 20,
            confine: false,
            cache: None,
            settings: Vec::new(),
        }
    }
}

impl Scene {
    /// Reads and validates the scene file at `path` (meshes relative to it), with the
    /// default [`LoadOptions`].
    pub fn load(path: impl AsRef<Path>) -> Result<Scene, SceneError> {
        Scene::load_with(path, &LoadOptions::default())
    }

    /// [`Scene::load`] in confined mode ([`LoadOptions::confine`]).
    pub fn load_confined(path: impl AsRef<Path>) -> Result<Scene, SceneError> {
        Scene::load_with(
            path,
            &LoadOptions {
                confine: true,
                ..LoadOptions::default()
            },
        )
    }

    /// Reads and validates the scene file at `path` as `options` say.
    pub fn load_with(path: impl AsRef<Path>, options: &LoadOptions) -> Result<Scene, SceneError> {
        let path = path.as_ref();
        let text = read_scene_text(path, options.max_input_bytes)?;
        Scene::parse_options(&text, path, options)
    }

    /// Parses and validates scene text; `path` names it in errors and anchors mesh paths.
    pub fn parse(src: &str, path: &Path) -> Result<Scene, SceneError> {
        Scene::parse_with(src, path, &read_from_disk)
    }

    /// [`Scene::parse`] as `options` say (limits, cache, settings; `confine` anchored at
    /// the folder of `path`).
    pub fn parse_options(
        src: &str,
        path: &Path,
        options: &LoadOptions,
    ) -> Result<Scene, SceneError> {
        let limit = options.max_input_bytes;
        if !options.confine {
            let read = move |p: &Path| read_from_disk_limited(p, limit);
            return Scene::parse_limited(src, path, &read, options);
        }
        let root = path
            .parent()
            .filter(|p| !p.as_os_str().is_empty())
            .unwrap_or(Path::new("."));
        let root = std::fs::canonicalize(root).map_err(|error| SceneError::Io {
            file: root.to_owned(),
            error,
        })?;
        let read = confined_reader_limited(root, limit);
        Scene::parse_limited(src, path, &read, options)
    }

    /// [`Scene::parse`], reading meshes and MTLs through `read` (a fuzzer or an embedder
    /// can serve them from memory).
    pub fn parse_with(src: &str, path: &Path, read: &ReadFile<'_>) -> Result<Scene, SceneError> {
        Scene::parse_limited(src, path, read, &LoadOptions::default())
    }

    /// [`Scene::parse_with`] with [`LoadOptions::max_input_bytes`] unpacked at most from one
    /// `.gz` mesh, [`LoadOptions::cache`] and [`LoadOptions::settings`]; `options.confine`
    /// is `read`'s to apply.
    fn parse_limited(
        src: &str,
        path: &Path,
        read: &ReadFile<'_>,
        options: &LoadOptions,
    ) -> Result<Scene, SceneError> {
        if options.settings.is_empty() {
            return Scene::parse_text(src, path, read, options);
        }
        let applied = set::apply(src, &options.settings).map_err(|error| SceneError::Set {
            file: path.to_owned(),
            error,
        })?;
        let file = path.display().to_string();
        match Scene::parse_text(&applied.text, path, read, options) {
            Ok(mut scene) => {
                let remap = |s: &mut String| *s = applied.remap_located(s, &file);
                scene.warnings.iter_mut().for_each(remap);
                scene.sphere_sources.iter_mut().for_each(remap);
                scene
                    .triangle_sources
                    .iter_mut()
                    .for_each(|(_, s)| remap(s));
                Ok(scene)
            }
            Err(e) => Err(e.through_settings(&applied)),
        }
    }

    /// [`Scene::parse_limited`] of text with its settings made.
    fn parse_text(
        src: &str,
        path: &Path,
        read: &ReadFile<'_>,
        options: &LoadOptions,
    ) -> Result<Scene, SceneError> {
        let file: SceneFile = toml::from_str(src).map_err(|e| syntax_error(src, path, &e))?;
        let inputs = std::cell::RefCell::new(vec![path.to_owned()]);
        let recording = |p: &Path| {
            inputs.borrow_mut().push(p.to_owned());
            read(p)
        };
        let stages = crate::stages::Stages::new();
        let mut scene = Validator {
            src,
            path,
            read: &recording,
            limit: options.max_input_bytes,
            cache: options.cache.as_ref(),
            stages: &stages,
        }
        .scene(file)?;
        scene.load_stages = crate::stages::Timings(stages.into_times());
        let mut seen = std::collections::HashSet::new();
        scene.inputs = inputs
            .into_inner()
            .into_iter()
            .filter(|p| seen.insert(p.clone()))
            .collect();
        Ok(scene)
    }

    /// The sizes the scene's camera asks for.
    pub fn size(&self) -> (u32, u32) {
        (self.camera.width, self.camera.height)
    }
}

/// A scene file's text: a regular file within the input limit, in UTF-8 (else an error
/// naming the line where it stops being UTF-8).
fn read_scene_text(path: &Path, limit: u64) -> Result<String, SceneError> {
    let bytes = read_limited(path, limit).map_err(|e| match e {
        ReadError::Io(error) => SceneError::Io {
            file: path.to_owned(),
            error,
        },
        other => SceneError::Syntax {
            file: path.to_owned(),
            line: 1,
            key: "(file)".into(),
            message: other.to_string(),
        },
    })?;
    String::from_utf8(bytes).map_err(|e| {
        let pos = e.utf8_error().valid_up_to();
        let text = String::from_utf8_lossy(e.as_bytes()).into_owned();
        SceneError::Syntax {
            file: path.to_owned(),
            line: line_of(&text, pos),
            key: "(file)".into(),
            message: format!("not UTF-8 at byte {pos}"),
        }
    })
}

fn syntax_error(src: &str, path: &Path, e: &toml::de::Error) -> SceneError {
    let span = e.span().unwrap_or(0..0);
    let message = e.message().trim().to_string();
    // serde names the field in backticks ("unknown field `foo`", "missing field `bar`");
    // otherwise the key is the one assigned on the error's line, or the text under the span.
    let line = line_of(src, span.start);
    let line_key = src.lines().nth(line - 1).and_then(|l| {
        let (k, _) = l.split_once('=')?;
        let k = k.trim();
        (!k.is_empty() && !k.starts_with('[') && !k.starts_with('#')).then(|| k.to_string())
    });
    let key = message
        .split('`')
        .nth(1)
        .map(str::to_string)
        .or(line_key)
        .or_else(|| {
            let s = src.get(span.clone())?.trim();
            (!s.is_empty() && s.len() <= 40 && !s.contains('\n')).then(|| s.to_string())
        })
        .unwrap_or_else(|| "(document)".into());
    // The key's whole path: `camera.focal`, `lights[1].colour`, not `focal`.
    let key = match table_at(src, span.start) {
        Some(t)
            if !key.starts_with('(')
                && !key.contains(['.', '['])
                && t != key
                && !t.ends_with(&format!(".{key}"))
                && !t.starts_with(&format!("{key}[")) =>
        {
            format!("{t}.{key}")
        }
        _ => key,
    };
    SceneError::Syntax {
        file: path.to_owned(),
        line: line_of(src, span.start),
        key,
        message,
    }
}

/// The table that holds byte `offset` of a scene's text, as a key path (`camera`,
/// `lights[1]`, `materials.red`, `meshes[0].transform`); `None` at the top level. Read from
/// the table headers above the offset, line by line, as TOML defines them: `[[name]]`
/// appends to an array of tables, `[name]` opens a table, and a header below an array's
/// name extends its last element.
fn table_at(src: &str, offset: usize) -> Option<String> {
    let is_path = |s: &str| {
        s.starts_with(|c: char| c.is_ascii_alphabetic() || c == '"' || c == '_')
            && s.chars()
                .all(|c| c.is_ascii_alphanumeric() || "_-.\" ".contains(c))
    };
    let mut counts: std::collections::HashMap<String, usize> = Default::default();
    let mut table = None;
    let mut start = 0;
    for line in src.split_inclusive('\n') {
        if start > offset {
            break;
        }
        start += line.len();
        let t = line.split('#').next().unwrap_or("").trim();
        let (name, array) = if let Some(n) = t.strip_prefix("[[").and_then(|r| r.strip_suffix("]]"))
        {
            (n.trim(), true)
        } else if let Some(n) = t.strip_prefix('[').and_then(|r| r.strip_suffix(']')) {
            (n.trim(), false)
        } else {
            continue;
        };
        if !is_path(name) {
            continue;
        }
        // Below an array of tables: `[a.b]` is `a[last].b`.
        let (head, rest) = name.split_once('.').unwrap_or((name, ""));
        let mut path = match counts.get(head) {
            Some(&n) if !rest.is_empty() => format!("{head}[{}].{rest}", n - 1),
            _ => name.to_string(),
        };
        if array {
            let n = counts.entry(name.to_string()).or_insert(0);
            path = format!("{path}[{n}]");
            *n += 1;
        }
        table = Some(path);
    }
    table
}

/// The largest colour component (light colour, ka, kd, ks, ambient, background) a scene
/// may give. Shading sums, per light, products of a light colour and a reflectance: with
/// both at most 1e6, a term is at most 1e12 and no sum of them overflows f32 (an infinite
/// term times a zero factor would make NaN, written as black). Every physical scene is far
/// below it.
pub const MAX_COLOUR: f32 = 1e6;

/// Checks values and turns the file's structs into the scene's.
struct Validator<'a> {
    src: &'a str,
    path: &'a Path,
    read: &'a ReadFile<'a>,
    /// The most bytes unpacked from one `.gz` mesh ([`LoadOptions::max_input_bytes`]).
    limit: u64,
    /// [`LoadOptions::cache`].
    cache: Option<&'a Arc<crate::cache::Cache>>,
    /// Where the stages of reading are timed ([`Scene::load_stages`]).
    stages: &'a crate::stages::Stages,
}

/// How a scene reads the files it names (meshes and their MTLs): the bytes, or why not.
pub type ReadFile<'a> = dyn Fn(&Path) -> Result<Vec<u8>, ReadError> + 'a;

/// [`ReadFile`] from the file system: regular files only, at most the default input limit
/// ([`LoadOptions`]).
pub fn read_from_disk(path: &Path) -> Result<Vec<u8>, ReadError> {
    read_from_disk_limited(path, LoadOptions::default().max_input_bytes)
}

/// [`read_from_disk`] with at most `limit` bytes.
pub fn read_from_disk_limited(path: &Path, limit: u64) -> Result<Vec<u8>, ReadError> {
    read_limited(path, limit)
}

/// A [`ReadFile`] that reads only files whose real path (symbolic links followed) lies
/// below `root`, which must itself be canonical; at most the default input limit.
pub fn confined_reader(root: PathBuf) -> impl Fn(&Path) -> Result<Vec<u8>, ReadError> {
    confined_reader_limited(root, LoadOptions::default().max_input_bytes)
}

/// [`confined_reader`] with at most `limit` bytes a file.
pub fn confined_reader_limited(
    root: PathBuf,
    limit: u64,
) -> impl Fn(&Path) -> Result<Vec<u8>, ReadError> {
    move |path: &Path| {
        let real = std::fs::canonicalize(path).map_err(ReadError::Io)?;
        if !real.starts_with(&root) {
            return Err(ReadError::Outside {
                path: real,
                root: root.clone(),
            });
        }
        read_from_disk_limited(&real, limit)
    }
}

/// The default of [`LoadOptions::max_input_bytes`], MiB: 2 GiB, twice the largest mesh
/// glint is meant for (an OBJ of about 15 million triangles).
pub const DEFAULT_MAX_INPUT_MIB: u64 = 2048;

/// Why an input file was not read.
#[derive(Debug, thiserror::Error)]
pub enum ReadError {
    /// The OS refused.
    #[error("cannot read: {0}")]
    Io(std::io::Error),
    /// A FIFO, a device, a socket or a folder: glint reads regular files only (a named pipe
    /// would block forever, a device never ends).
    #[error("not a regular file (it is {0}): glint reads only regular files")]
    NotRegular(&'static str),
    /// Longer than the limit.
    #[error(
        "larger than the input limit of {} MiB (set GLINT_MAX_INPUT_MIB to raise it)",
        .0 >> 20
    )]
    TooLarge(u64),
    /// In confined mode ([`LoadOptions::confine`]), a file whose real path is not below the
    /// scene's folder.
    #[error("{path} is outside the scene's folder {root} (--confine)")]
    Outside {
        /// The file's real path (symbolic links followed).
        path: PathBuf,
        /// The scene's folder, canonical.
        root: PathBuf,
    },
    /// Any other reason a [`ReadFile`] gives, printed as it is (a reader that serves files
    /// from memory has reasons of its own).
    #[error("{0}")]
    Other(String),
}

fn kind_of(t: std::fs::FileType) -> &'static str {
    #[cfg(unix)]
    {
        use std::os::unix::fs::FileTypeExt;
        if t.is_fifo() {
            return "a named pipe";
        }
        if t.is_char_device() || t.is_block_device() {
            return "a device";
        }
        if t.is_socket() {
            return "a socket";
        }
    }
    if t.is_dir() { "a folder" } else { "not a file" }
}

/// Reads a regular file of at most `limit` bytes. The type is checked before the file is
/// opened (opening a named pipe blocks) and again on the open file.
pub fn read_limited(path: &Path, limit: u64) -> Result<Vec<u8>, ReadError> {
    use std::io::Read;
    let meta = std::fs::metadata(path).map_err(ReadError::Io)?;
    if !meta.is_file() {
        return Err(ReadError::NotRegular(kind_of(meta.file_type())));
    }
    let mut opts = std::fs::OpenOptions::new();
    opts.read(true);
    #[cfg(target_os = "linux")]
    {
        use std::os::unix::fs::OpenOptionsExt;
        opts.custom_flags(0o4000); // O_NONBLOCK: a FIFO swapped in after the check does not block
    }
    let file = opts.open(path).map_err(ReadError::Io)?;
    let meta = file.metadata().map_err(ReadError::Io)?;
    if !meta.is_file() {
        return Err(ReadError::NotRegular(kind_of(meta.file_type())));
    }
    if meta.len() > limit {
        return Err(ReadError::TooLarge(limit));
    }
    let mut out = Vec::with_capacity(meta.len() as usize);
    file.take(limit + 1)
        .read_to_end(&mut out)
        .map_err(ReadError::Io)?;
    if out.len() as u64 > limit {
        return Err(ReadError::TooLarge(limit));
    }
    Ok(out)
}

impl Validator<'_> {
    fn err<T>(
        &self,
        span: std::ops::Range<usize>,
        key: &str,
        message: String,
    ) -> Result<T, SceneError> {
        Err(SceneError::Invalid {
            file: self.path.to_owned(),
            line: line_of(self.src, span.start),
            key: key.to_string(),
            message,
        })
    }

    /// `check`'s verdict on `v`, its failure placed at `span` under `key`.
    fn check<T, U>(
        &self,
        v: T,
        span: std::ops::Range<usize>,
        key: &str,
        check: impl FnOnce(T) -> Result<U, String>,
    ) -> Result<U, SceneError> {
        check(v).or_else(|m| self.err(span, key, m))
    }

    fn finite3(&self, v: &Vec3File, key: &str) -> Result<[f32; 3], SceneError> {
        self.check(*v.get_ref(), v.span(), key, validate::finite3)
    }

    fn colour(&self, v: &Vec3File, key: &str) -> Result<[f32; 3], SceneError> {
        self.check(*v.get_ref(), v.span(), key, validate::colour)
    }

    fn material_index(
        &self,
        names: &[String],
        name: &Spanned<String>,
        key: &str,
    ) -> Result<u32, SceneError> {
        match names.iter().position(|n| n == name.get_ref()) {
            Some(i) => Ok(i as u32),
            None => self.err(
                name.span(),
                key,
                validate::no_material(name.get_ref(), names),
            ),
        }
    }

    fn scene(&self, f: SceneFile) -> Result<Scene, SceneError> {
        let mut warnings = Vec::new();
        let ambient = match &f.ambient {
            Some(v) => self.colour(v, "ambient")?,
            None => [0.0; 3],
        };
        let background = match &f.background {
            Some(v) => self.colour(v, "background")?,
            None => [0.0; 3],
        };
        let triangle = match &f.triangle {
            Some(s) => match s.get_ref().parse() {
                Ok(a) => a,
                Err(m) => return self.err(s.span(), "triangle", m),
            },
            None => TriangleAlgorithm::MollerTrumbore,
        };
        let camera = self.camera(&f.camera)?;
        let camera_keys = self.camera_keys(f.camera.get_ref(), &camera)?;

        let mut lights = Vec::new();
        for (i, l) in f.lights.iter().enumerate() {
            let l = l.get_ref();
            lights.push(self.light(i, l)?);
        }

        let mut textures = texture::TextureSet::default();
        let mut materials = Vec::new();
        for (name, m) in &f.materials {
            materials.push(self.material(name, m, &mut textures)?);
        }
        if lights.is_empty() && materials.iter().any(|m| m.model != Model::Ambient) {
            warnings.push(format!(
                "{}: lights: none, so only the ambient term shows",
                self.path.display()
            ));
        }
        let names: Vec<String> = materials.iter().map(|m| m.name.clone()).collect();

        let mut spheres = Vec::new();
        let mut sphere_sources = Vec::new();
        for (i, s) in f.spheres.iter().enumerate() {
            let s = s.get_ref();
            let center = self.finite3(&s.center, &format!("spheres[{i}].center"))?;
            let radius = self.check(
                *s.radius.get_ref(),
                s.radius.span(),
                &format!("spheres[{i}].radius"),
                validate::radius,
            )?;
            let material =
                self.material_index(&names, &s.material, &format!("spheres[{i}].material"))?;
            spheres.push(Sphere {
                center,
                radius,
                material,
            });
            sphere_sources.push(format!(
                "{}:{}: spheres[{i}]",
                self.path.display(),
                line_of(self.src, s.center.span().start)
            ));
        }

        let mut triangles = Vec::new();
        let mut uvs = Vec::new();
        let mut triangle_sources = Vec::new();
        for (i, t) in f.triangles.iter().enumerate() {
            let t = t.get_ref();
            let key = format!("triangles[{i}].vertices");
            let v = *t.vertices.get_ref();
            if v.iter().flatten().any(|x| !x.is_finite()) {
                return self.err(t.vertices.span(), &key, format!("{v:?} is not finite"));
            }
            if mesh::is_degenerate(&v) {
                warnings.push(format!(
                    "{}:{}: {key}: zero area: never hit",
                    self.path.display(),
                    line_of(self.src, t.vertices.span().start)
                ));
            }
            let material =
                self.material_index(&names, &t.material, &format!("triangles[{i}].material"))?;
            let textured = materials[material as usize].maps() != (None, None);
            match &t.uvs {
                Some(uv) => {
                    let key = format!("triangles[{i}].uvs");
                    let u = *uv.get_ref();
                    if u.iter().flatten().any(|x| !x.is_finite()) {
                        return self.err(uv.span(), &key, format!("{u:?} is not finite"));
                    }
                    if textured {
                        uvs.push(TextureCoords {
                            first: triangles.len(),
                            uvs: vec![u],
                        });
                    } else {
                        warnings.push(format!(
                            "{}:{}: {key}: material {:?} has no map_kd or map_ka: unused",
                            self.path.display(),
                            line_of(self.src, uv.span().start),
                            t.material.get_ref()
                        ));
                    }
                }
                None if textured => warnings.push(format!(
                    "{}:{}: triangles[{i}].uvs: material {:?} is textured but the triangle has no uvs: untextured",
                    self.path.display(),
                    line_of(self.src, t.vertices.span().start),
                    t.material.get_ref()
                )),
                None => {}
            }
            triangle_sources.push((
                triangles.len(),
                format!(
                    "{}:{}: {key}",
                    self.path.display(),
                    line_of(self.src, t.vertices.span().start)
                ),
            ));
            triangles.push(Triangle {
                vertices: v,
                material,
            });
        }

        let mut smooth = Vec::new();
        for (i, m) in f.meshes.iter().enumerate() {
            triangle_sources.push((
                triangles.len(),
                format!(
                    "{}:{}: meshes[{i}].file ({})",
                    self.path.display(),
                    line_of(self.src, m.get_ref().file.span().start),
                    m.get_ref().file.get_ref()
                ),
            ));
            mesh::load(
                self,
                i,
                m.get_ref(),
                mesh::Out {
                    materials: &mut materials,
                    triangles: &mut triangles,
                    smooth: &mut smooth,
                    uvs: &mut uvs,
                    textures: &mut textures,
                    warnings: &mut warnings,
                },
            )?;
        }
        let (textures, downscaled) = textures.into_fitted();
        warnings.extend(downscaled);

        Ok(Scene {
            path: self.path.to_owned(),
            ambient,
            background,
            triangle,
            shadows: f.shadows.unwrap_or(false),
            max_depth: self.max_depth(&f.max_depth)?,
            min_weight: self.min_weight(&f.min_weight)?,
            camera,
            encoding: match f.output.as_ref().and_then(|o| o.encoding.as_ref()) {
                Some(e) => match e.get_ref().parse() {
                    Ok(e) => e,
                    Err(m) => return self.err(e.span(), "output.encoding", m.to_string()),
                },
                None => crate::shared::encoding::Encoding::Linear,
            },
            lights,
            materials,
            spheres,
            triangles,
            smooth,
            uvs,
            textures,
            inputs: Vec::new(),
            warnings,
            sphere_sources,
            triangle_sources,
            cache: self.cache.cloned(),
            camera_keys,
            load_stages: crate::stages::Timings::default(),
        })
    }

    /// `[[lights]]` entry `i`: the keys its kind needs, and no others.
    fn light(&self, i: usize, l: &format::LightFile) -> Result<Light, SceneError> {
        let key = |k: &str| format!("lights[{i}].{k}");
        let kind_name = l.kind.as_ref().map_or("point", |k| k.get_ref().as_str());
        let kind_span = l.kind.as_ref().map_or(l.color.span(), |k| k.span());
        let needs = |present: bool, k: &str, wanted: bool| -> Result<(), SceneError> {
            match (present, wanted) {
                (false, true) => self.err(
                    kind_span.clone(),
                    &key(k),
                    format!("missing: a {kind_name} light needs it"),
                ),
                (true, false) => self.err(
                    kind_span.clone(),
                    &key(k),
                    format!("a {kind_name} light has none"),
                ),
                _ => Ok(()),
            }
        };
        let (point, dir, spot) = match kind_name {
            "point" => (true, false, false),
            "directional" => (false, true, false),
            "spot" => (true, true, true),
            other => {
                return self.err(
                    kind_span,
                    &key("kind"),
                    format!("unknown kind {other:?}: expected point, directional or spot"),
                );
            }
        };
        needs(l.position.is_some(), "position", point)?;
        needs(l.direction.is_some(), "direction", dir)?;
        needs(l.angle.is_some(), "angle", spot)?;
        if !spot && l.falloff.is_some() {
            needs(true, "falloff", false)?;
        }
        let position = match &l.position {
            Some(v) => self.finite3(v, &key("position"))?,
            None => [0.0; 3],
        };
        let direction = match &l.direction {
            Some(v) => self.check(
                *v.get_ref(),
                v.span(),
                &key("direction"),
                validate::direction,
            )?,
            None => [0.0; 3],
        };
        let kind = match (dir, spot) {
            (false, _) => LightKind::Point,
            (true, false) => LightKind::Directional { direction },
            (true, true) => {
                let a = l.angle.as_ref().expect("checked above");
                let angle =
                    self.check(*a.get_ref(), a.span(), &key("angle"), validate::spot_angle)?;
                let falloff = match &l.falloff {
                    Some(f) => self.check(*f.get_ref(), f.span(), &key("falloff"), |x| {
                        validate::spot_falloff(x, angle)
                    })?,
                    None => 0.0,
                };
                LightKind::Spot {
                    direction,
                    angle,
                    falloff,
                }
            }
        };
        Ok(Light {
            kind,
            position,
            color: self.colour(&l.color, &key("color"))?,
        })
    }

    fn camera(&self, c: &Spanned<format::CameraFile>) -> Result<Camera, SceneError> {
        let span = c.span();
        let c = c.get_ref();
        let eye = self.finite3(&c.eye, "camera.eye")?;
        let look_at = self.finite3(&c.look_at, "camera.look_at")?;
        let up = match &c.up {
            Some(v) => self.finite3(v, "camera.up")?,
            None => [0.0, 1.0, 0.0],
        };
        let fov = self.check(*c.fov.get_ref(), c.fov.span(), "camera.fov", validate::fov)?;
        let side =
            |v: &Spanned<i64>, key: &str| self.check(*v.get_ref(), v.span(), key, validate::side);
        let width = side(&c.width, "camera.width")?;
        let height = side(&c.height, "camera.height")?;
        let samples = match &c.samples {
            None => 1,
            Some(v) => self.check(*v.get_ref(), v.span(), "camera.samples", validate::samples)?,
        };
        match validate::view(eye, look_at, up) {
            Ok(()) => {}
            Err(validate::ViewFault::LookAt(m)) => {
                return self.err(c.look_at.span(), "camera.look_at", m);
            }
            Err(validate::ViewFault::Up(m)) => {
                let up_span = c.up.as_ref().map(|u| u.span()).unwrap_or(span);
                return self.err(up_span, "camera.up", m);
            }
        }
        Ok(Camera {
            eye,
            look_at,
            up,
            fov,
            width,
            height,
            samples,
        })
    }

    /// `[[camera.keys]]`: each key's values, its own or the previous key's (the first's
    /// `camera`'s), checked as `[camera]`'s are; frames in 0..=[`MAX_FRAME`], increasing.
    fn camera_keys(
        &self,
        c: &format::CameraFile,
        camera: &Camera,
    ) -> Result<Vec<CameraKey>, SceneError> {
        let mut keys: Vec<CameraKey> = Vec::new();
        for (i, k) in c.keys.iter().flatten().enumerate() {
            let span = k.span();
            let k = k.get_ref();
            let key = |name: &str| format!("camera.keys[{i}].{name}");
            let frame = *k.frame.get_ref();
            if !(0..=MAX_FRAME).contains(&frame) {
                return self.err(
                    k.frame.span(),
                    &key("frame"),
                    format!("{frame} is outside 0..={MAX_FRAME}"),
                );
            }
            let prev = keys.last().copied().unwrap_or(CameraKey {
                frame: 0,
                eye: camera.eye,
                look_at: camera.look_at,
                up: camera.up,
                fov: camera.fov,
            });
            if let Some(p) = keys.last()
                && frame <= p.frame as i64
            {
                return self.err(
                    k.frame.span(),
                    &key("frame"),
                    format!(
                        "{frame} is not after the previous key's frame, {}: keys go in increasing frames",
                        p.frame
                    ),
                );
            }
            let v3 = |v: &Option<format::Vec3File>, name: &str, old: [f32; 3]| match v {
                Some(v) => self.finite3(v, &key(name)),
                None => Ok(old),
            };
            let this = CameraKey {
                frame: frame as u32,
                eye: v3(&k.eye, "eye", prev.eye)?,
                look_at: v3(&k.look_at, "look_at", prev.look_at)?,
                up: v3(&k.up, "up", prev.up)?,
                fov: match &k.fov {
                    Some(f) => self.check(*f.get_ref(), f.span(), &key("fov"), validate::fov)?,
                    None => prev.fov,
                },
            };
            match validate::view(this.eye, this.look_at, this.up) {
                Ok(()) => {}
                Err(validate::ViewFault::LookAt(m)) => {
                    let s = k.look_at.as_ref().map_or(span, |v| v.span());
                    return self.err(s, &key("look_at"), m);
                }
                Err(validate::ViewFault::Up(m)) => {
                    let s = k.up.as_ref().map_or(span, |v| v.span());
                    return self.err(s, &key("up"), m);
                }
            }
            keys.push(this);
        }
        Ok(keys)
    }

    fn material(
        &self,
        name: &str,
        m: &Spanned<format::MaterialFile>,
        textures: &mut texture::TextureSet,
    ) -> Result<Material, SceneError> {
        let span = m.span();
        let m = m.get_ref();
        let key = |k: &str| format!("materials.{name}.{k}");
        let model = match m.model.get_ref().as_str() {
            "ambient" => Model::Ambient,
            "diffuse" => Model::Diffuse,
            "phong" => Model::Phong,
            other => {
                return self.err(
                    m.model.span(),
                    &key("model"),
                    format!("unknown model {other:?}: expected ambient, diffuse or phong"),
                );
            }
        };
        let ka = self.colour(&m.ka, &key("ka"))?;
        let need = |v: &Option<Vec3File>, k: &str, needed: bool| -> Result<[f32; 3], SceneError> {
            match v {
                Some(v) => self.colour(v, &key(k)),
                None if needed => self.err(
                    span.clone(),
                    &key(k),
                    format!("missing: the {} model needs it", m.model.get_ref()),
                ),
                None => Ok([0.0; 3]),
            }
        };
        let kd = need(&m.kd, "kd", model != Model::Ambient)?;
        let ks = need(&m.ks, "ks", model == Model::Phong)?;
        let n = match &m.n {
            Some(n) => self.check(*n.get_ref(), n.span(), &key("n"), validate::shininess)?,
            None if model == Model::Phong => {
                return self.err(span, &key("n"), "missing: the phong model needs it".into());
            }
            None => 1.0,
        };
        let mut map = |v: &Option<Spanned<String>>, k: &str| -> Result<Option<u32>, SceneError> {
            let Some(file) = v else { return Ok(None) };
            let base = self.path.parent().unwrap_or(Path::new("."));
            let path = base.join(file.get_ref());
            textures
                .add(&path, self.read, self.stages)
                .map(Some)
                .or_else(|e| self.err(file.span(), &key(k), format!("{}: {e}", path.display())))
        };
        let map_kd = map(&m.map_kd, "map_kd")?;
        let map_ka = map(&m.map_ka, "map_ka")?;
        Ok(Material {
            name: name.to_string(),
            model,
            ka,
            kd,
            ks,
            n,
            optics: self.optics(name, m)?,
            map_kd,
            map_ka,
        })
    }

    /// A material's `kr`, `kt`, `ior` and `fresnel`: `ior` is needed with `kt`.
    fn optics(&self, name: &str, m: &format::MaterialFile) -> Result<Optics, SceneError> {
        let key = |k: &str| format!("materials.{name}.{k}");
        let d = Optics::default();
        let kr =
            m.kr.as_ref()
                .map_or(Ok(d.kr), |v| self.colour(v, &key("kr")))?;
        let kt =
            m.kt.as_ref()
                .map_or(Ok(d.kt), |v| self.colour(v, &key("kt")))?;
        let ior = match (&m.ior, &m.kt) {
            (Some(i), _) => self.check(*i.get_ref(), i.span(), &key("ior"), validate::ior)?,
            (None, Some(kt)) => {
                return self.err(
                    kt.span(),
                    &key("ior"),
                    "missing: kt (transmittance) needs an index of refraction".into(),
                );
            }
            (None, None) => d.ior,
        };
        Ok(Optics {
            kr,
            kt,
            ior,
            fresnel: m.fresnel.unwrap_or(d.fresnel),
        })
    }

    /// The scene's `max_depth`, 0..=[`MAX_DEPTH`] (default [`DEFAULT_MAX_DEPTH`]).
    fn max_depth(&self, v: &Option<Spanned<i64>>) -> Result<u32, SceneError> {
        match v {
            None => Ok(DEFAULT_MAX_DEPTH),
            Some(v) => self.check(*v.get_ref(), v.span(), "max_depth", validate::max_depth),
        }
    }

    /// The scene's `min_weight`, finite and ≥ 0 (default [`DEFAULT_MIN_WEIGHT`]).
    fn min_weight(&self, v: &Option<Spanned<f32>>) -> Result<f32, SceneError> {
        match v {
            None => Ok(DEFAULT_MIN_WEIGHT),
            Some(v) => self.check(*v.get_ref(), v.span(), "min_weight", validate::min_weight),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::{ReadError, confined_reader};

    #[test]
    fn a_confined_reader_refuses_what_is_outside_its_folder() {
        let d = std::env::temp_dir().join(format!("glint-confine-unit-{}", std::process::id()));
        let inside = d.join("in");
        std::fs::create_dir_all(&inside).unwrap();
        std::fs::write(d.join("out.obj"), "v 0 0 0\n").unwrap();
        std::fs::write(inside.join("in.obj"), "v 0 0 0\n").unwrap();
        let root = std::fs::canonicalize(&inside).unwrap();
        let read = confined_reader(root.clone());
        let e = read(&inside.join("../out.obj")).unwrap_err();
        let out = std::fs::canonicalize(d.join("out.obj")).unwrap();
        assert!(
            matches!(&e, ReadError::Outside { path, root: r } if *path == out && *r == root),
            "{e:?}"
        );
        assert_eq!(
            e.to_string(),
            format!(
                "{} is outside the scene's folder {} (--confine)",
                out.display(),
                root.display()
            )
        );
        // The twin: the file inside is read; one missing is an I/O error.
        assert_eq!(read(&inside.join("in.obj")).unwrap(), b"v 0 0 0\n");
        let e = read(&inside.join("missing.obj")).unwrap_err();
        assert!(matches!(e, ReadError::Io(_)) && e.to_string().starts_with("cannot read: "));
        let _ = std::fs::remove_dir_all(&d);
    }
}
