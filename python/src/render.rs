//! `glint.Renderer` and the render call: the GIL released while the frame is traced, the
//! caller's Ctrl-C turned into a cancelled job, the frame handed to numpy without a copy.

use std::sync::Arc;
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
use std::time::Duration;

use numpy::{PyArray1, PyArrayMethods};
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;

use crate::errors::{from_panic, from_render_error};
use crate::scene::{Scene, scene_arg};

/// How many `Renderer`s this process has made (the test that the module-level `render`
/// keeps one).
pub static RENDERERS_MADE: AtomicUsize = AtomicUsize::new(0);

/// A renderer: one backend, with its device and compiled pipelines kept across calls.
///
/// `backend` is one of `auto`, `gpu`, `gpu-rq`, `cpu`, `cpu-f64` (as `glint render
/// --backend`); `adapter` picks a Vulkan adapter whose name contains it. `auto` takes a real
/// GPU when there is one, else the CPU tracer (see `note`). Renders from several threads
/// run in parallel (the GIL is released while tracing).
#[pyclass(frozen, module = "glint", name = "Renderer")]
pub struct Renderer {
    pub(crate) inner: glint::Renderer,
}

#[pymethods]
impl Renderer {
    #[new]
    #[pyo3(signature = (backend="auto", adapter=None))]
    fn new(py: Python<'_>, backend: &str, adapter: Option<&str>) -> PyResult<Renderer> {
        let b: glint::Backend = backend
            .parse()
            .map_err(|e: glint::UnknownBackend| PyValueError::new_err(e.to_string()))?;
        let inner = py
            .detach(|| glint::Renderer::with_adapter(b, adapter))
            .map_err(|e| from_render_error(py, &e, false))?;
        RENDERERS_MADE.fetch_add(1, Ordering::Relaxed);
        Ok(Renderer { inner })
    }

    /// Renders `scene` (a `glint.Scene`, a path or a dict) and returns the frame as float32
    /// of shape (height, width, 4): linear RGB, and the hit distance t in the 4th channel
    /// (-1 for a miss). Exactly what `glint render -o x.exr` writes, in every bit.
    ///
    /// `size=(width, height)`, `samples` (N×N per pixel), `triangle` (`moller-trumbore`,
    /// `watertight`, `baldwin-weber`) and `max_depth` override the scene's. `math` is the
    /// GPU kernel's division and square root: `exact` (correctly rounded on every driver,
    /// the default), `corrected` (the corrections even where the driver is exact) or
    /// `fast` (the driver's own). Ctrl-C stops the render (KeyboardInterrupt).
    #[pyo3(signature = (scene, *, size=None, samples=None, triangle=None, max_depth=None, math="exact"))]
    #[allow(clippy::too_many_arguments)] // Python's keyword arguments
    fn render<'py>(
        &self,
        py: Python<'py>,
        scene: &Bound<'py, PyAny>,
        size: Option<(u32, u32)>,
        samples: Option<u32>,
        triangle: Option<&str>,
        max_depth: Option<u32>,
        math: &str,
    ) -> PyResult<Bound<'py, PyAny>> {
        let scene = scene_arg(py, scene)?;
        let options = options(size, samples, triangle, max_depth, math)?;
        render_array(py, &self.inner, scene.get(), options)
    }

    /// The backend asked for (`auto`, `gpu`, ...).
    #[getter]
    fn backend(&self) -> String {
        self.inner.backend().to_string()
    }

    /// What renders, in words: the adapter and driver, or the CPU tracer.
    fn describe(&self) -> String {
        self.inner.describe()
    }

    /// Why `auto` chose what it chose, where it says (None otherwise).
    #[getter]
    fn note(&self) -> Option<String> {
        self.inner.note().map(str::to_string)
    }

    fn __repr__(&self) -> String {
        format!("glint.Renderer({:?}: {})", self.backend(), self.describe())
    }
}

/// The render's options from the Python arguments (the triangle name parsed by the
/// library).
pub(crate) fn options(
    size: Option<(u32, u32)>,
    samples: Option<u32>,
    triangle: Option<&str>,
    max_depth: Option<u32>,
    math: &str,
) -> PyResult<glint::RenderOptions> {
    let math = math
        .parse::<glint::buffers::Math>()
        .map_err(PyValueError::new_err)?;
    let triangle = triangle
        .map(|t| t.parse::<glint::scene::TriangleAlgorithm>())
        .transpose()
        .map_err(PyValueError::new_err)?;
    Ok(glint::RenderOptions {
        size,
        triangle,
        samples,
        max_depth,
        math,
        ..glint::RenderOptions::default()
    })
}

/// Renders on `renderer` with the GIL released, polling for signals every 50 ms (Ctrl-C
/// cancels the job, which the job's thread answers at its next band); the frame becomes a numpy array that owns the renderer's buffer.
pub(crate) fn render_array<'py>(
    py: Python<'py>,
    renderer: &glint::Renderer,
    scene: &Scene,
    options: glint::RenderOptions,
) -> PyResult<Bound<'py, PyAny>> {
    let cancel = Arc::new(AtomicBool::new(false));
    let dict = scene.is_from_dict();
    let s: &glint::scene::Scene = &scene.scene;
    let mut interrupted: Option<PyErr> = None;
    let outcome = py.detach(|| {
        std::thread::scope(|threads| {
            let flag = cancel.clone();
            let (tx, rx) = std::sync::mpsc::channel();
            threads.spawn(move || {
                let r = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
                    glint::render::Job::borrowed(s, glint::render::Output::Memory)
                        .options(options)
                        .cancel_on(flag)
                        .run(renderer)
                }));
                let _ = tx.send(r);
            });
            loop {
                match rx.recv_timeout(Duration::from_millis(50)) {
                    Ok(r) => return r,
                    Err(std::sync::mpsc::RecvTimeoutError::Timeout) => {
                        if interrupted.is_none()
                            && let Err(e) = Python::attach(|py| py.check_signals())
                        {
                            cancel.store(true, Ordering::Relaxed);
                            interrupted = Some(e);
                        }
                    }
                    // The sender went without sending: the thread died outside the job.
                    Err(std::sync::mpsc::RecvTimeoutError::Disconnected) => {
                        return Err(Box::new("the render thread ended without a result")
                            as Box<dyn std::any::Any + Send>);
                    }
                }
            }
        })
    });
    if let Some(e) = interrupted {
        return Err(e);
    }
    let report = match outcome {
        Ok(r) => r.map_err(|e| from_render_error(py, &e, dict))?,
        Err(p) => return Err(from_panic(p)),
    };
    let image = report
        .image
        .ok_or_else(|| crate::errors::RenderError::new_err("the job gave no image"))?;
    let (w, h) = (image.width as usize, image.height as usize);
    let flat: Vec<f32> = image.pixels.into_flattened();
    let array = PyArray1::from_vec(py, flat);
    Ok(array.reshape([h, w, 4])?.into_any())
}
