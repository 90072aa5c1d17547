//! `glint.Scene`: a validated scene, kept with the TOML text it was made from, so that it
//! converts back to a dict and pickles (by its text and path: mesh files are read again,
//! at the same paths, where it is unpickled).

use std::path::PathBuf;
use std::sync::Arc;

use pyo3::PyTypeInfo;
use pyo3::exceptions::PyTypeError;
use pyo3::prelude::*;
use pyo3::types::{PyBool, PyDict, PyFloat, PyInt, PyList, PyString, PyTuple};

use crate::errors::{from_scene_error, scene_error};

/// The name a scene made from a dict or from text has, in its folder.
const DICT_NAME: &str = "<dict>";
const TEXT_NAME: &str = "<toml>";

/// How a scene was made: what pickling sends to make it again.
#[derive(Clone)]
enum Origin {
    /// A file: loaded again from its path (with the cache folder it had, if any).
    File(PathBuf, Option<PathBuf>),
    /// TOML text, its meshes relative to the folder.
    Text(PathBuf),
    /// A dict, its meshes relative to the folder.
    Dict(PathBuf),
}

/// A validated scene (spheres, triangles, meshes, lights, materials, camera).
///
/// Make one with `Scene.load(path)`, `Scene.from_toml(text)` or `Scene.from_dict(d)`;
/// every way checks it as the command line checks a scene file, with the same errors
/// (`glint.SceneError`). A scene is immutable: edit `scene.to_dict()` and make a new one.
/// It pickles by its text and folder, so mesh files must be readable at the same paths
/// where it is unpickled (on a cluster: a shared file system).
#[pyclass(frozen, module = "glint", name = "Scene")]
pub struct Scene {
    pub(crate) scene: Arc<glint::scene::Scene>,
    text: String,
    origin: Origin,
}

impl Scene {
    /// Whether errors should name `<dict>` rather than lines of the generated TOML.
    pub(crate) fn is_from_dict(&self) -> bool {
        matches!(self.origin, Origin::Dict(_))
    }

    fn parse(py: Python<'_>, text: String, origin: Origin) -> PyResult<Scene> {
        let (path, dict) = match &origin {
            Origin::File(p, _) => (p.clone(), false),
            Origin::Text(d) => (d.join(TEXT_NAME), false),
            Origin::Dict(d) => (d.join(DICT_NAME), true),
        };
        let result = py.detach(|| match &origin {
            Origin::File(p, cache) => {
                let options = glint::scene::LoadOptions {
                    cache: cache.as_ref().map(|dir| {
                        Arc::new(glint::cache::Cache::new(glint::cache::Settings::new(
                            dir.clone(),
                        )))
                    }),
                    ..glint::scene::LoadOptions::default()
                };
                glint::scene::Scene::load_with(p, &options)
            }
            _ => glint::scene::Scene::parse(&text, &path),
        });
        let scene = result.map_err(|e| from_scene_error(py, &e, dict))?;
        Ok(Scene {
            scene: Arc::new(scene),
            text,
            origin,
        })
    }
}

#[pymethods]
impl Scene {
    /// Loads and validates the scene file at `path` (a str or os.PathLike); its meshes
    /// resolve against the file's folder. `cache`: a folder for the cache of large meshes
    /// and their BVHs (as `glint render` keeps in `~/.cache/glint`), `True` for that
    /// default folder, or `None`/`False` for none. Raises `glint.SceneError` or `OSError`.
    #[staticmethod]
    #[pyo3(signature = (path, *, cache=None))]
    fn load(py: Python<'_>, path: PathBuf, cache: Option<&Bound<'_, PyAny>>) -> PyResult<Scene> {
        let cache = match cache {
            None => None,
            Some(c) if c.is_instance_of::<PyBool>() => match c.extract::<bool>()? {
                true => Some(glint::cache::default_dir().ok_or_else(|| {
                    PyTypeError::new_err("cache=True: no default cache folder (HOME is unset)")
                })?),
                false => None,
            },
            Some(c) => Some(c.extract::<PathBuf>()?),
        };
        let text =
            std::fs::read_to_string(&path).map_err(|e| crate::errors::os_error(&path, &e))?;
        Scene::parse(py, text, Origin::File(path, cache))
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
        let table = to_table(py, d, "")?;
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
        let table: toml::Table = toml::from_str(&self.text)
            .map_err(|e| PyTypeError::new_err(format!("the scene's own text: {e}")))?;
        from_value(py, &toml::Value::Table(table))
    }

    /// The scene as TOML text in the scene file's format.
    fn to_toml(&self) -> String {
        self.text.clone()
    }

    /// The scene file's path (or `<dict>` / `<toml>` in the base folder).
    #[getter]
    fn path(&self) -> PathBuf {
        self.scene.path.clone()
    }

    /// The camera's (width, height).
    #[getter]
    fn size(&self) -> (u32, u32) {
        self.scene.size()
    }

    /// How many triangles, meshes' included.
    #[getter]
    fn triangles(&self) -> usize {
        self.scene.triangles.len()
    }

    /// How many spheres.
    #[getter]
    fn spheres(&self) -> usize {
        self.scene.spheres.len()
    }

    /// The warnings loading gave (a scene without lights, a zero-area triangle, ...).
    #[getter]
    fn warnings(&self) -> Vec<String> {
        self.scene.warnings.clone()
    }

    /// Pickling: the text and how to resolve it, not the triangles.
    fn __reduce__<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyTuple>> {
        let make = py.import("glint")?.getattr("Scene")?.getattr("_remake")?;
        let (kind, a, b) = match &self.origin {
            Origin::File(p, c) => ("file", p.clone(), c.clone()),
            Origin::Text(d) => ("text", d.clone(), None),
            Origin::Dict(d) => ("dict", d.clone(), None),
        };
        (make, (kind, self.text.clone(), a, b)).into_pyobject(py)
    }

    /// Makes a scene again from what `__reduce__` sent (a file is read again from its
    /// path, so a scene pickled from a file follows that file).
    #[staticmethod]
    fn _remake(
        py: Python<'_>,
        kind: &str,
        text: String,
        a: PathBuf,
        b: Option<PathBuf>,
    ) -> PyResult<Scene> {
        match kind {
            "file" => {
                let text =
                    std::fs::read_to_string(&a).map_err(|e| crate::errors::os_error(&a, &e))?;
                Scene::parse(py, text, Origin::File(a, b))
            }
            "text" => Scene::parse(py, text, Origin::Text(a)),
            "dict" => Scene::parse(py, text, Origin::Dict(a)),
            _ => Err(PyTypeError::new_err(format!(
                "unknown scene origin {kind:?}"
            ))),
        }
    }

    fn __repr__(&self) -> String {
        let (w, h) = self.scene.size();
        format!(
            "glint.Scene({:?}, {w}x{h}, {} triangles, {} spheres)",
            self.scene.path.display().to_string(),
            self.scene.triangles.len(),
            self.scene.spheres.len()
        )
    }
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
        Ok(p) => Py::new(py, Scene::load(py, p, None)?),
        Err(_) => Err(PyTypeError::new_err(format!(
            "scene: expected a glint.Scene, a path or a dict, got {}",
            scene.get_type().name()?
        ))),
    }
}

/// A dict as a TOML table; `at` is the key path so far, for errors.
fn to_table(py: Python<'_>, d: &Bound<'_, PyDict>, at: &str) -> PyResult<toml::Table> {
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
        t.insert(k, to_value(py, &v, &key)?);
    }
    Ok(t)
}

/// A Python value as a TOML value.
fn to_value(py: Python<'_>, v: &Bound<'_, PyAny>, key: &str) -> PyResult<toml::Value> {
    use toml::Value as V;
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
        return Ok(V::Table(to_table(py, d, key)?));
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
            out.push(to_value(py, &x, &format!("{key}[{i}]"))?);
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
