//! Scenes: the TOML format, its validation (every error names file, line and key), and
//! OBJ meshes.

pub mod camera_path;
mod error;
mod format;
mod gltf;
mod instance;
pub use instance::{InstancesError, MAX_INSTANCES, maps_of_matrix};
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

mod model;
mod read;
mod validator;

pub use model::*;
pub use read::{
    DEFAULT_MAX_INPUT_MIB, ReadError, ReadFile, confined_reader, confined_reader_limited,
    read_from_disk, read_from_disk_limited, read_limited,
};
use read::{read_scene_text, syntax_error};
use validator::Validator;

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
    /// The meshes with a name, in file order.
    pub named: Vec<NamedMesh>,
    /// `[[instances]]`, in file order: with none, the scene is traced as one BVH.
    pub instances: Vec<Instance>,
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
