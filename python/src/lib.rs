//! The `glint._glint` extension module: glint's library from Python. The `glint` package
//! (`python/glint/__init__.py`) re-exports it with the module-level conveniences.
//!
//! The library does the work; this module only converts: paths and dicts to scenes, the
//! frame to a numpy array, glint's errors to Python exceptions.

mod errors;
mod render;
mod scene;

use std::path::PathBuf;

use numpy::{PyArray1, PyArrayMethods, PyReadonlyArray3, PyUntypedArrayMethods};
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use pyo3::types::PyDict;

use errors::{from_render_error, image_error};
use render::Renderer;
use scene::{Scene, scene_arg};

/// Renders `scene` on the GPU's shader, on its f32 CPU mirror and in f64 on `renderer`'s
/// device, as `glint compare` does, and returns the metrics as a dict: `gpu_vs_cpu`,
/// `cpu_vs_f64`, `gpu_vs_f64` (each with `bit_exact`, `differing_bits`, `hit_miss`,
/// `differing_t`, `max_abs`, `rms`, `mean_abs`, `max_u8`, ...), `adapter`, `exactness`,
/// `traversal`, `algorithm`, `width`, `height`, `warnings`, `ray_query`.
#[pyfunction]
#[pyo3(signature = (renderer, scene, *, size=None, samples=None, triangle=None, max_depth=None, math="exact"))]
#[allow(clippy::too_many_arguments)] // Python's keyword arguments
fn _compare_on<'py>(
    py: Python<'py>,
    renderer: &Renderer,
    scene: &Bound<'py, PyAny>,
    size: Option<(u32, u32)>,
    samples: Option<u32>,
    triangle: Option<&str>,
    max_depth: Option<u32>,
    math: &str,
) -> PyResult<Bound<'py, PyDict>> {
    let scene = scene_arg(py, scene)?;
    let options = render::options(size, samples, triangle, max_depth, math)?;
    let inner = renderer.inner()?;
    let Some(gpu) = inner.tracer().gpu() else {
        return Err(PyValueError::new_err(format!(
            "compare needs a GPU renderer; this one is {:?}",
            inner.backend().name()
        )));
    };
    let s = scene.get().state();
    let dict_source = s.is_from_dict();
    let report = py
        .detach(|| glint::render::compare(&s.scene, &options, gpu))
        .map_err(|e| from_render_error(py, &e, dict_source))?;
    let diff = |d: &glint::compare::Diff| -> PyResult<Bound<'py, PyDict>> {
        let x = PyDict::new(py);
        x.set_item("bit_exact", d.bit_exact())?;
        x.set_item("pixels", d.pixels)?;
        x.set_item("differing_pixels", d.differing_pixels)?;
        x.set_item("differing_bits", d.differing_bits)?;
        x.set_item("hit_miss", d.hit_miss)?;
        x.set_item("differing_t", d.differing_t)?;
        x.set_item("max_abs", d.max_abs)?;
        x.set_item("rms", d.rms)?;
        x.set_item("mean_abs", d.mean_abs)?;
        x.set_item("max_u8", d.max_u8)?;
        Ok(x)
    };
    let out = PyDict::new(py);
    out.set_item("scene", report.scene.display().to_string())?;
    out.set_item("width", report.width)?;
    out.set_item("height", report.height)?;
    out.set_item("algorithm", report.algorithm.name())?;
    out.set_item("adapter", &report.adapter)?;
    out.set_item("traversal", report.traversal)?;
    out.set_item("exactness", &report.exactness)?;
    let warnings: Vec<String> = report.warnings.iter().map(|w| w.to_string()).collect();
    out.set_item("warnings", warnings)?;
    out.set_item("gpu_vs_cpu", diff(&report.gpu_vs_cpu)?)?;
    out.set_item("cpu_vs_f64", diff(&report.cpu_vs_f64)?)?;
    out.set_item("gpu_vs_f64", diff(&report.gpu_vs_f64)?)?;
    match &report.ray_query {
        glint::render::RayQueryResult::Measured { vs_f64, .. } => {
            out.set_item("ray_query", diff(vs_f64)?)?
        }
        glint::render::RayQueryResult::NotMeasured(e) => {
            out.set_item("ray_query", e.to_string())?
        }
    }
    Ok(out)
}

/// The Vulkan adapters on this machine, best first, as dicts: `name`, `device_type`,
/// `driver`, `driver_info`, `exactness` (whether the GPU's arithmetic is the CPU mirror's).
#[pyfunction]
fn adapters(py: Python<'_>) -> PyResult<Vec<Bound<'_, PyDict>>> {
    let list = py.detach(glint::gpu::adapters);
    let mut out = Vec::new();
    for a in &list {
        let i = a.get_info();
        let d = PyDict::new(py);
        d.set_item("name", &i.name)?;
        d.set_item("device_type", format!("{:?}", i.device_type))?;
        d.set_item("driver", &i.driver)?;
        d.set_item("driver_info", &i.driver_info)?;
        d.set_item(
            "exactness",
            glint::gpu::exact::adapter_exactness(a).describe(),
        )?;
        out.push(d);
    }
    Ok(out)
}

/// `glint.save`'s core: a C-contiguous float32 (height, width, 4) array to a PNG (its
/// bytes encoded as `encoding` says) or an EXR. The Python wrapper takes the other shapes
/// and types.
#[pyfunction]
fn _save(
    py: Python<'_>,
    array: PyReadonlyArray3<'_, f32>,
    path: PathBuf,
    encoding: &str,
) -> PyResult<()> {
    let encoding: glint::image::Encoding = encoding
        .parse()
        .map_err(|e: glint::image::UnknownEncoding| PyValueError::new_err(e.to_string()))?;
    let shape = array.shape();
    if shape[2] != 4 {
        return Err(PyValueError::new_err(format!(
            "save: expected shape (height, width, 4), got {shape:?}"
        )));
    }
    let (h, w) = (shape[0], shape[1]);
    let data = array.as_array();
    let mut pixels = Vec::with_capacity(h * w);
    for y in 0..h {
        for x in 0..w {
            pixels.push([
                data[[y, x, 0]],
                data[[y, x, 1]],
                data[[y, x, 2]],
                data[[y, x, 3]],
            ]);
        }
    }
    let image = glint::image::Image {
        width: w as u32,
        height: h as u32,
        pixels,
    };
    py.detach(|| match glint::image::format_of(&path)? {
        glint::image::Format::Png => image.save_png_encoded(&path, encoding),
        glint::image::Format::Exr => image.save(&path),
    })
    .map_err(|e| image_error(&e))
}

#[pyfunction]
fn load(py: Python<'_>, path: PathBuf) -> PyResult<Bound<'_, PyAny>> {
    // The library names a missing file in a decode error; Python wants an OSError.
    std::fs::metadata(&path).map_err(|e| errors::os_error(&path, &e))?;
    let image = py
        .detach(|| glint::image::Image::load(&path))
        .map_err(|e| image_error(&e))?;
    let (w, h) = (image.width as usize, image.height as usize);
    let array = PyArray1::from_vec(py, image.pixels.into_flattened());
    Ok(array.reshape([h, w, 4])?.into_any())
}

/// How many `Renderer`s this process has made (for the tests).
#[pyfunction]
fn _renderers_made() -> usize {
    render::RENDERERS_MADE.load(std::sync::atomic::Ordering::Relaxed)
}

/// The backend names the library takes, in order.
#[pyfunction]
fn backends() -> Vec<&'static str> {
    glint::Backend::NAMES.to_vec()
}

/// The AOV names `render(..., aovs=[...])` takes, in order (docs/aov.md).
#[pyfunction]
fn aovs() -> Vec<&'static str> {
    glint::render::Aov::ALL
        .map(glint::render::Aov::name)
        .to_vec()
}

/// The extension module.
#[pymodule]
fn _glint(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<Scene>()?;
    m.add_class::<Renderer>()?;
    m.add("SceneError", m.py().get_type::<errors::SceneError>())?;
    m.add("RenderError", m.py().get_type::<errors::RenderError>())?;
    m.add_function(wrap_pyfunction!(_compare_on, m)?)?;
    m.add_function(wrap_pyfunction!(adapters, m)?)?;
    m.add_function(wrap_pyfunction!(_save, m)?)?;
    m.add_function(wrap_pyfunction!(load, m)?)?;
    m.add_function(wrap_pyfunction!(_renderers_made, m)?)?;
    m.add_function(wrap_pyfunction!(backends, m)?)?;
    m.add_function(wrap_pyfunction!(aovs, m)?)?;
    Ok(())
}
