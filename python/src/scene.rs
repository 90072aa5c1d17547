//! `glint.Scene`: a validated scene, kept with the TOML text it was made from, so that it
//! converts back to a dict and pickles (by its text and path: mesh files are read again,
//! at the same paths, where it is unpickled).

use std::path::PathBuf;
use std::sync::{Arc, RwLock};

use pyo3::PyTypeInfo;
use pyo3::exceptions::{PyKeyError, PyTypeError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::{PyBool, PyDict, PyFloat, PyInt, PyList, PyString, PyTuple};

use crate::errors::{from_scene_error, scene_error};

/// The name a scene made from a dict or from text has, in its folder.
const DICT_NAME: &str = "<dict>";
const TEXT_NAME: &str = "<toml>";

/// How a scene was made: what pickling sends to make it again.
#[derive(Clone)]
enum Origin {
    /// A file: loaded again from its path (with the cache folder it had, if any), then
    /// the settings (`key=value`, as `--set`) that `with_camera` made.
    File(PathBuf, Option<PathBuf>, Vec<String>),
    /// TOML text, its meshes relative to the folder.
    Text(PathBuf),
    /// A dict, its meshes relative to the folder.
    Dict(PathBuf),
}

/// A validated scene (spheres, triangles, meshes, lights, materials, camera).
///
/// Make one with `Scene.load(path)`, `Scene.from_toml(text)` or `Scene.from_dict(d)`;
/// every way checks it as the command line checks a scene file, with the same errors
/// (`glint.SceneError`). Its camera can be read and set (`camera`, `with_camera`); for
/// anything else edit `scene.to_dict()` and make a new one.
/// It pickles by its text and folder, so mesh files must be readable at the same paths
/// where it is unpickled (on a cluster: a shared file system).
#[pyclass(frozen, module = "glint", name = "Scene")]
pub struct Scene {
    /// What the scene is now: replaced whole when `camera` is set, so a render that took
    /// it keeps the scene it started with.
    state: RwLock<Arc<State>>,
}

/// A scene's content: the library's scene, the text it was made from, and how.
pub(crate) struct State {
    pub(crate) scene: Arc<glint::scene::Scene>,
    text: String,
    origin: Origin,
}

impl State {
    /// Whether errors should name `<dict>` rather than lines of the generated TOML.
    pub(crate) fn is_from_dict(&self) -> bool {
        matches!(self.origin, Origin::Dict(_))
    }
}

impl Scene {
    fn new(state: State) -> Scene {
        Scene {
            state: RwLock::new(Arc::new(state)),
        }
    }

    /// The scene as it is now.
    pub(crate) fn state(&self) -> Arc<State> {
        self.state.read().unwrap_or_else(|e| e.into_inner()).clone()
    }

    fn parse(py: Python<'_>, text: String, origin: Origin) -> PyResult<Scene> {
        let (path, dict) = match &origin {
            Origin::File(p, ..) => (p.clone(), false),
            Origin::Text(d) => (d.join(TEXT_NAME), false),
            Origin::Dict(d) => (d.join(DICT_NAME), true),
        };
        let result = py.detach(|| match &origin {
            Origin::File(p, cache, settings) => {
                let settings = settings
                    .iter()
                    .map(|s| s.parse())
                    .collect::<Result<Vec<_>, _>>()
                    .map_err(|error| glint::scene::SceneError::Set {
                        file: p.clone(),
                        error,
                    })?;
                let options = glint::scene::LoadOptions {
                    cache: cache.as_ref().map(|dir| {
                        Arc::new(glint::cache::Cache::new(glint::cache::Settings::new(
                            dir.clone(),
                        )))
                    }),
                    settings,
                    ..glint::scene::LoadOptions::default()
                };
                let scene = glint::scene::Scene::parse_options(&text, p, &options)?;
                // The text with the settings made, for `to_toml`, `to_dict` and pickling.
                let text = match options.settings.is_empty() {
                    true => None,
                    false => glint::scene::set::apply(&text, &options.settings)
                        .ok()
                        .map(|a| a.text),
                };
                Ok((scene, text))
            }
            _ => glint::scene::Scene::parse(&text, &path).map(|s| (s, None)),
        });
        let (scene, made) = result.map_err(|e| from_scene_error(py, &e, dict))?;
        let text = made.unwrap_or(text);
        Ok(Scene::new(State {
            scene: Arc::new(scene),
            text,
            origin,
        }))
    }
}

#[pymethods]
impl Scene {
    /// Loads and validates the scene file at `path` (a str or os.PathLike); its meshes
    /// resolve against the file's folder. `cache`: `True` (the default, as `glint render`)
    /// for the cache of large meshes and their BVHs in the command line's folder
    /// (`GLINT_CACHE_DIR`, else `$XDG_CACHE_HOME/glint`, else `~/.cache/glint`; none when
    /// none of them is set), a folder of its own, or `False`/`None` for none. Raises
    /// `glint.SceneError` or `OSError`.
    #[staticmethod]
    #[pyo3(signature = (path, *, cache=Some(CacheArg::Flag(true))))]
    fn load(py: Python<'_>, path: PathBuf, cache: Option<CacheArg>) -> PyResult<Scene> {
        let cache = match cache {
            Some(CacheArg::Flag(true)) => glint::cache::default_dir(),
            None | Some(CacheArg::Flag(false)) => None,
            Some(CacheArg::Folder(dir)) => Some(dir),
        };
        let text =
            std::fs::read_to_string(&path).map_err(|e| crate::errors::os_error(&path, &e))?;
        Scene::parse(py, text, Origin::File(path, cache, Vec::new()))
    }

    /// A scene from TOML text in the scene file's format; mesh paths resolve against
    /// `base_dir`. Errors name the file `<toml>` in `base_dir`, with the line.
    #[staticmethod]
    #[pyo3(signature = (text, base_dir=PathBuf::from(".")))]
    fn from_toml(py: Python<'_>, text: String, base_dir: PathBuf) -> PyResult<Scene> {
        Scene::parse(py, text, Origin::Text(base_dir))
    }

    /// A scene from a dict with the scene file's keys (`camera`, `lights`, `materials`,
    /// `spheres`, `triangles`, `meshes`, ...), as `to_dict` gives; mesh paths resolve
    /// against `base_dir`. Values may be Python or numpy numbers, lists, tuples or numpy
    /// arrays, strings and os.PathLike. Errors name `<dict>` and the key.
    #[staticmethod]
    #[pyo3(signature = (d, base_dir=PathBuf::from(".")))]
    fn from_dict(py: Python<'_>, d: &Bound<'_, PyDict>, base_dir: PathBuf) -> PyResult<Scene> {
        let table = to_table(py, d, "", 0)?;
        let text = toml::to_string(&table).map_err(|e| {
            scene_error(
                py,
                format!("<dict>: {e}"),
                Some(DICT_NAME.into()),
                None,
                None,
            )
        })?;
        Scene::parse(py, text, Origin::Dict(base_dir))
    }

    /// The scene as a dict with the scene file's keys (what it was made from, not the
    /// meshes' triangles): `Scene.from_dict(s.to_dict())` is the same scene.
    fn to_dict<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        let table: toml::Table = toml::from_str(&self.state().text)
            .map_err(|e| PyTypeError::new_err(format!("the scene's own text: {e}")))?;
        from_value(py, &toml::Value::Table(table))
    }

    /// The scene as TOML text in the scene file's format.
    fn to_toml(&self) -> String {
        self.state().text.clone()
    }

    /// The scene file's path (or `<dict>` / `<toml>` in the base folder).
    #[getter]
    fn path(&self) -> PathBuf {
        self.state().scene.path.clone()
    }

    /// The camera's (width, height).
    #[getter]
    fn size(&self) -> (u32, u32) {
        self.state().scene.size()
    }

    /// How many triangles, meshes' included.
    #[getter]
    fn triangles(&self) -> usize {
        self.state().scene.triangles.len()
    }

    /// How many spheres.
    #[getter]
    fn spheres(&self) -> usize {
        self.state().scene.spheres.len()
    }

    /// The warnings loading gave (a scene without lights, a zero-area triangle, ...).
    #[getter]
    fn warnings(&self) -> Vec<String> {
        self.state().scene.warnings.clone()
    }

    /// The camera, as a dict: `eye`, `look_at`, `up` (3-tuples), `fov` (degrees, vertical),
    /// `size` ((width, height)) and `samples` (N×N rays a pixel). Setting it to a dict of
    /// some of these keys changes those parts, as `with_camera` does, in this scene (a
    /// render already running keeps the camera it started with); an unknown key is a
    /// `KeyError`.
    #[getter]
    fn camera<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        camera_dict(py, &self.state().scene.camera)
    }

    /// The camera at `frame` (fractional frames allowed) on the scene's camera path
    /// (`[[camera.keys]]`: linear between keys, held before the first and after the last),
    /// as a dict with `camera`'s keys; `[camera]` itself where there are no keys. The same
    /// in every bit as `glint render --frames` uses. `scene.with_camera(**scene.camera_at(f))`
    /// is the scene at frame `f`. A frame that is not finite, or where the path has no view,
    /// is a `ValueError`.
    fn camera_at<'py>(&self, py: Python<'py>, frame: f64) -> PyResult<Bound<'py, PyDict>> {
        let c = self
            .state()
            .scene
            .camera_at(frame)
            .map_err(|e| pyo3::exceptions::PyValueError::new_err(e.to_string()))?;
        camera_dict(py, &c)
    }

    /// A copy of this scene with the camera's given parts changed (the others kept): `eye`,
    /// `look_at`, `up` (3 numbers each), `fov` (degrees), `size` ((width, height)),
    /// `samples`. Meshes, textures and BVH inputs are not read again: the geometry is
    /// copied in memory. The new camera is checked as a scene file's is (`SceneError`
    /// naming `camera.KEY`); `to_dict`, `to_toml` and pickling carry it.
    #[pyo3(signature = (*, eye=None, look_at=None, up=None, fov=None, size=None, samples=None))]
    #[allow(clippy::too_many_arguments)] // Python's keyword arguments
    fn with_camera(
        &self,
        py: Python<'_>,
        eye: Option<[f32; 3]>,
        look_at: Option<[f32; 3]>,
        up: Option<[f32; 3]>,
        fov: Option<f32>,
        size: Option<(u32, u32)>,
        samples: Option<u32>,
    ) -> PyResult<Scene> {
        let change = CameraChange {
            eye,
            look_at,
            up,
            fov,
            size,
            samples,
        };
        Ok(Scene::new(self.state().with_camera(py, change)?))
    }

    /// A copy of this scene with the named mesh `mesh` (a `[[meshes]]` entry's `name`)
    /// placed once more for each map of `transforms`: an (N, 3, 4) or (N, 4, 4) array
    /// (anything numpy makes one of) of object-to-world maps, rows `[m0, m1, m2, t]` (a
    /// 4×4's last row must be 0, 0, 0, 1), with `material` replacing the mesh's own where
    /// given. `[[instances]]` in bulk, without writing N tables: the meshes are not read
    /// again. A refused map raises `ValueError` naming its index, and nothing is added.
    /// `to_dict`, `to_toml` and pickling carry the instances (as `matrix` tables); a
    /// scene from a file then pickles by its text, no longer following the file.
    #[pyo3(signature = (mesh, transforms, material=None))]
    fn with_instances(
        &self,
        py: Python<'_>,
        mesh: String,
        transforms: &Bound<'_, PyAny>,
        material: Option<String>,
    ) -> PyResult<Scene> {
        let maps = affine_rows(py, transforms)?;
        Ok(Scene::new(self.state().with_instances(
            &mesh,
            &maps,
            material.as_deref(),
        )?))
    }

    #[setter]
    fn set_camera(&self, py: Python<'_>, value: &Bound<'_, PyDict>) -> PyResult<()> {
        let mut change = CameraChange::default();
        for (k, v) in value.iter() {
            let key: String = k.extract()?;
            match key.as_str() {
                "eye" => change.eye = Some(v.extract()?),
                "look_at" => change.look_at = Some(v.extract()?),
                "up" => change.up = Some(v.extract()?),
                "fov" => change.fov = Some(v.extract()?),
                "size" => change.size = Some(v.extract()?),
                "samples" => change.samples = Some(v.extract()?),
                _ => {
                    return Err(PyKeyError::new_err(format!(
                        "camera: unknown key {key:?} (eye, look_at, up, fov, size, samples)"
                    )));
                }
            }
        }
        let new = self.state().with_camera(py, change)?;
        *self.state.write().unwrap_or_else(|e| e.into_inner()) = Arc::new(new);
        Ok(())
    }

    /// Pickling: the text and how to resolve it, not the triangles.
    fn __reduce__<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyTuple>> {
        let make = py.import("glint")?.getattr("Scene")?.getattr("_remake")?;
        let st = self.state();
        let (kind, a, b, settings) = match &st.origin {
            Origin::File(p, c, s) => ("file", p.clone(), c.clone(), s.clone()),
            Origin::Text(d) => ("text", d.clone(), None, Vec::new()),
            Origin::Dict(d) => ("dict", d.clone(), None, Vec::new()),
        };
        (make, (kind, st.text.clone(), a, b, settings)).into_pyobject(py)
    }

    /// Makes a scene again from what `__reduce__` sent (a file is read again from its
    /// path, so a scene pickled from a file follows that file, with the camera changes
    /// made since).
    #[staticmethod]
    #[pyo3(signature = (kind, text, a, b, settings=Vec::new()))]
    fn _remake(
        py: Python<'_>,
        kind: &str,
        text: String,
        a: PathBuf,
        b: Option<PathBuf>,
        settings: Vec<String>,
    ) -> PyResult<Scene> {
        match kind {
            "file" => {
                let text =
                    std::fs::read_to_string(&a).map_err(|e| crate::errors::os_error(&a, &e))?;
                Scene::parse(py, text, Origin::File(a, b, settings))
            }
            "text" => Scene::parse(py, text, Origin::Text(a)),
            "dict" => Scene::parse(py, text, Origin::Dict(a)),
            _ => Err(PyTypeError::new_err(format!(
                "unknown scene origin {kind:?}"
            ))),
        }
    }

    fn __repr__(&self) -> String {
        let st = self.state();
        let (w, h) = st.scene.size();
        format!(
            "glint.Scene({:?}, {w}x{h}, {} triangles, {} spheres)",
            st.scene.path.display().to_string(),
            st.scene.triangles.len(),
            st.scene.spheres.len()
        )
    }
}

/// A camera as `Scene.camera` gives it.
fn camera_dict<'py>(py: Python<'py>, c: &glint::scene::Camera) -> PyResult<Bound<'py, PyDict>> {
    let d = PyDict::new(py);
    d.set_item("eye", (c.eye[0], c.eye[1], c.eye[2]))?;
    d.set_item("look_at", (c.look_at[0], c.look_at[1], c.look_at[2]))?;
    d.set_item("up", (c.up[0], c.up[1], c.up[2]))?;
    d.set_item("fov", c.fov)?;
    d.set_item("size", (c.width, c.height))?;
    d.set_item("samples", c.samples)?;
    Ok(d)
}

/// Parts of a camera to change (`None`: kept).
#[derive(Default)]
struct CameraChange {
    eye: Option<[f32; 3]>,
    look_at: Option<[f32; 3]>,
    up: Option<[f32; 3]>,
    fov: Option<f32>,
    size: Option<(u32, u32)>,
    samples: Option<u32>,
}

impl State {
    /// This scene with `change` made to its camera, checked as a file's camera is; the
    /// text and the origin carry the change (as `--set` settings).
    fn with_camera(&self, py: Python<'_>, change: CameraChange) -> PyResult<State> {
        let mut scene = (*self.scene).clone();
        let c = &mut scene.camera;
        let v3 = |v: [f32; 3]| format!("[{:?}, {:?}, {:?}]", v[0], v[1], v[2]);
        let mut settings = Vec::new();
        if let Some(v) = change.eye {
            c.eye = v;
            settings.push(format!("camera.eye={}", v3(v)));
        }
        if let Some(v) = change.look_at {
            c.look_at = v;
            settings.push(format!("camera.look_at={}", v3(v)));
        }
        if let Some(v) = change.up {
            c.up = v;
            settings.push(format!("camera.up={}", v3(v)));
        }
        if let Some(v) = change.fov {
            c.fov = v;
            settings.push(format!("camera.fov={v:?}"));
        }
        if let Some((w, h)) = change.size {
            (c.width, c.height) = (w, h);
            settings.push(format!("camera.width={w}"));
            settings.push(format!("camera.height={h}"));
        }
        if let Some(n) = change.samples {
            c.samples = n;
            settings.push(format!("camera.samples={n}"));
        }
        let dict = self.is_from_dict();
        scene
            .validate()
            .map_err(|e| from_scene_error(py, &e, dict))?;
        let parsed = settings
            .iter()
            .map(|s| s.parse::<glint::scene::set::Setting>())
            .collect::<Result<Vec<_>, _>>()
            .and_then(|list| glint::scene::set::apply(&self.text, &list))
            .map_err(|e| PyTypeError::new_err(e.to_string()))?;
        let origin = match &self.origin {
            Origin::File(p, cache, old) => {
                let mut all = old.clone();
                all.extend(settings);
                Origin::File(p.clone(), cache.clone(), all)
            }
            other => other.clone(),
        };
        Ok(State {
            scene: Arc::new(scene),
            text: parsed.text,
            origin,
        })
    }
}

impl State {
    /// `Scene.with_instances`: the maps added to a copy of the scene, and to its text as
    /// `[[instances]]` tables with `matrix`, so that the text makes the same scene.
    fn with_instances(
        &self,
        mesh: &str,
        maps: &[[[f64; 4]; 3]],
        material: Option<&str>,
    ) -> PyResult<State> {
        let mut scene = (*self.scene).clone();
        scene
            .add_instances(mesh, maps, material)
            .map_err(|e| PyValueError::new_err(format!("with_instances: {e}")))?;
        let mut text = self.text.clone();
        let quoted = |s: &str| toml::Value::String(s.to_string()).to_string();
        let row = |r: &[f64; 4]| format!("[{:?}, {:?}, {:?}, {:?}]", r[0], r[1], r[2], r[3]);
        for m in maps {
            text.push_str(&format!(
                "\n[[instances]]\nmesh = {}\nmatrix = [{}, {}, {}]\n",
                quoted(mesh),
                row(&m[0]),
                row(&m[1]),
                row(&m[2])
            ));
            if let Some(name) = material {
                text.push_str(&format!("material = {}\n", quoted(name)));
            }
        }
        let origin = match &self.origin {
            Origin::File(p, ..) => Origin::Text(p.parent().map(PathBuf::from).unwrap_or_default()),
            other => other.clone(),
        };
        Ok(State {
            scene: Arc::new(scene),
            text,
            origin,
        })
    }
}

/// `transforms` as rows `[m0, m1, m2, t]`: an (N, 3, 4) array, or an (N, 4, 4) one whose
/// last rows are 0, 0, 0, 1.
fn affine_rows(py: Python<'_>, transforms: &Bound<'_, PyAny>) -> PyResult<Vec<[[f64; 4]; 3]>> {
    let np = py.import("numpy")?;
    let kwargs = PyDict::new(py);
    kwargs.set_item("dtype", np.getattr("float64")?)?;
    let a = np.call_method("ascontiguousarray", (transforms,), Some(&kwargs))?;
    let shape: Vec<usize> = a.getattr("shape")?.extract()?;
    let (n, rows) = match shape[..] {
        [n, 3, 4] => (n, 3),
        [n, 4, 4] => (n, 4),
        _ => {
            return Err(PyValueError::new_err(format!(
                "with_instances: transforms must be an (N, 3, 4) or (N, 4, 4) array of maps, not of shape {shape:?}"
            )));
        }
    };
    let flat: Vec<f64> = a.call_method0("ravel")?.call_method0("tolist")?.extract()?;
    let mut out = Vec::with_capacity(n);
    for (k, m) in flat.chunks_exact(rows * 4).enumerate() {
        if rows == 4 && m[12..16] != [0.0, 0.0, 0.0, 1.0] {
            return Err(PyValueError::new_err(format!(
                "with_instances: map {k}: a 4x4 map's last row must be 0, 0, 0, 1, not {:?}",
                &m[12..16]
            )));
        }
        out.push([
            [m[0], m[1], m[2], m[3]],
            [m[4], m[5], m[6], m[7]],
            [m[8], m[9], m[10], m[11]],
        ]);
    }
    Ok(out)
}

/// `Scene.load`'s `cache`: a flag or a folder.
#[derive(FromPyObject)]
pub(crate) enum CacheArg {
    /// `True`: the command line's folder; `False`: none.
    Flag(bool),
    /// A folder of the caller's.
    Folder(PathBuf),
}

/// A scene argument: a `Scene`, a path, or a dict.
pub(crate) fn scene_arg(py: Python<'_>, scene: &Bound<'_, PyAny>) -> PyResult<Py<Scene>> {
    if let Ok(s) = scene.cast::<Scene>() {
        return Ok(s.clone().unbind());
    }
    if let Ok(d) = scene.cast::<PyDict>() {
        return Py::new(py, Scene::from_dict(py, d, PathBuf::from("."))?);
    }
    match scene.extract::<PathBuf>() {
        Ok(p) => Py::new(py, Scene::load(py, p, Some(CacheArg::Flag(true)))?),
        Err(_) => Err(PyTypeError::new_err(format!(
            "scene: expected a glint.Scene, a path or a dict, got {}",
            scene.get_type().name()?
        ))),
    }
}

/// A dict as a TOML table; `at` is the key path so far, for errors.
fn to_table(
    py: Python<'_>,
    d: &Bound<'_, PyDict>,
    at: &str,
    depth: usize,
) -> PyResult<toml::Table> {
    too_deep(py, at, depth)?;
    let mut t = toml::Table::new();
    for (k, v) in d.iter() {
        let k: String = k.extract().map_err(|_| {
            scene_error(
                py,
                format!("<dict>: {at}: a key is not a string"),
                Some(DICT_NAME.into()),
                None,
                Some(at.to_string()),
            )
        })?;
        let key = if at.is_empty() {
            k.clone()
        } else {
            format!("{at}.{k}")
        };
        if v.is_none() {
            continue; // None: the key's default, as if it were absent.
        }
        t.insert(k, to_value(py, &v, &key, depth + 1)?);
    }
    Ok(t)
}

/// How deep a scene dict may nest: a scene file's deepest key (`camera.keys[0].eye[0]`) is
/// four levels down; a dict or list that contains itself would nest without end.
const MAX_DEPTH: usize = 32;

/// A `SceneError` naming `key` where `depth` is past [`MAX_DEPTH`].
fn too_deep(py: Python<'_>, key: &str, depth: usize) -> PyResult<()> {
    if depth <= MAX_DEPTH {
        return Ok(());
    }
    Err(scene_error(
        py,
        format!(
            "<dict>: {key}: nested deeper than {MAX_DEPTH} levels (a dict or list that \
             contains itself?)"
        ),
        Some(DICT_NAME.into()),
        None,
        Some(key.to_string()),
    ))
}

/// A Python value as a TOML value, `depth` levels down the dict.
fn to_value(
    py: Python<'_>,
    v: &Bound<'_, PyAny>,
    key: &str,
    depth: usize,
) -> PyResult<toml::Value> {
    use toml::Value as V;
    too_deep(py, key, depth)?;
    if v.is_instance_of::<PyBool>() {
        return Ok(V::Boolean(v.extract()?));
    }
    if v.is_instance_of::<PyInt>()
        && let Ok(i) = v.extract::<i64>()
    {
        return Ok(V::Integer(i));
    }
    if v.is_instance_of::<PyFloat>() {
        return Ok(V::Float(v.extract()?));
    }
    if v.is_instance_of::<PyString>() {
        return Ok(V::String(v.extract()?));
    }
    if let Ok(d) = v.cast::<PyDict>() {
        return Ok(V::Table(to_table(py, d, key, depth + 1)?));
    }
    // numpy scalars and arrays, tuples, other sequences; paths.
    let np_kind = v
        .getattr("dtype")
        .and_then(|d| d.getattr("kind"))
        .and_then(|k| k.extract::<String>())
        .ok();
    if v.hasattr("ndim")? && v.getattr("ndim")?.extract::<usize>()? == 0 {
        return match np_kind.as_deref() {
            Some("b") => Ok(V::Boolean(v.call_method0("item")?.extract()?)),
            Some("i" | "u") => Ok(V::Integer(v.call_method0("item")?.extract()?)),
            _ => Ok(V::Float(v.call_method0("item")?.extract()?)),
        };
    }
    if v.hasattr("__fspath__")? {
        let p: PathBuf = v.extract()?;
        return Ok(V::String(p.display().to_string()));
    }
    if let Ok(list) = v
        .call_method0("tolist")
        .or_else(|_| PyList::type_object(py).call1((v,)).map(|l| l.into_any()))
        && let Ok(list) = list.cast::<PyList>()
    {
        let mut out = Vec::new();
        for (i, x) in list.iter().enumerate() {
            out.push(to_value(py, &x, &format!("{key}[{i}]"), depth + 1)?);
        }
        return Ok(V::Array(out));
    }
    Err(scene_error(
        py,
        format!(
            "<dict>: {key}: a {} is not a scene value (numbers, strings, lists, dicts)",
            v.get_type().name()?
        ),
        Some(DICT_NAME.into()),
        None,
        Some(key.to_string()),
    ))
}

/// A TOML value as a Python value.
fn from_value<'py>(py: Python<'py>, v: &toml::Value) -> PyResult<Bound<'py, PyAny>> {
    use toml::Value as V;
    Ok(match v {
        V::String(s) => s.into_pyobject(py)?.into_any(),
        V::Integer(i) => i.into_pyobject(py)?.into_any(),
        V::Float(f) => f.into_pyobject(py)?.into_any(),
        V::Boolean(b) => b.into_pyobject(py)?.to_owned().into_any(),
        V::Datetime(d) => d.to_string().into_pyobject(py)?.into_any(),
        V::Array(a) => {
            let l = PyList::empty(py);
            for x in a {
                l.append(from_value(py, x)?)?;
            }
            l.into_any()
        }
        V::Table(t) => {
            let d = PyDict::new(py);
            for (k, x) in t {
                d.set_item(k, from_value(py, x)?)?;
            }
            d.into_any()
        }
    })
}
