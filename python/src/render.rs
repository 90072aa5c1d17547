//! `glint.Renderer` and the render call: the GIL released while the frame is traced, the
//! caller's Ctrl-C turned into a cancelled job, the frame handed to numpy without a copy.

use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
use std::sync::{Arc, RwLock};
use std::time::Duration;

use numpy::{PyArray1, PyArrayMethods};
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use pyo3::types::PyDict;
use pyo3::types::PyTuple;

use crate::errors::{from_panic, from_render_error};
use crate::scene::{State, scene_arg};

/// How many `Renderer`s this process has made (the test that the module-level `render`
/// keeps one).
pub static RENDERERS_MADE: AtomicUsize = AtomicUsize::new(0);

/// A renderer: one backend, with its device and compiled pipelines kept across calls.
///
/// `backend` is one of `auto`, `gpu`, `gpu-rq`, `cpu`, `cpu-f64` (as `glint render
/// --backend`); `adapter` picks a Vulkan adapter whose name contains it; `threads` the CPU
/// threads of its CPU work (the CPU tracers, the BVH build; default one per core, as the
/// command line's `--threads`). `auto` takes a real GPU when there is one, else the CPU
/// tracer (see `note`). Renders from several threads run in parallel (the GIL is released
/// while tracing). `close()` (or leaving a `with` block) lets the device go.
#[pyclass(frozen, module = "glint", name = "Renderer")]
pub struct Renderer {
    inner: RwLock<Option<Arc<glint::Renderer>>>,
    /// The pool of `threads`, where given.
    pool: Option<Arc<rayon::ThreadPool>>,
    /// The backend asked for, still known after `close`.
    backend: glint::Backend,
}

impl Renderer {
    /// The library's renderer, or `RenderError` once closed.
    pub(crate) fn inner(&self) -> PyResult<Arc<glint::Renderer>> {
        self.inner
            .read()
            .unwrap_or_else(|e| e.into_inner())
            .clone()
            .ok_or_else(|| crate::errors::RenderError::new_err("this glint.Renderer is closed"))
    }
}

#[pymethods]
impl Renderer {
    #[new]
    #[pyo3(signature = (backend="auto", adapter=None, threads=None))]
    fn new(
        py: Python<'_>,
        backend: &str,
        adapter: Option<&str>,
        threads: Option<usize>,
    ) -> PyResult<Renderer> {
        let b: glint::Backend = backend
            .parse()
            .map_err(|e: glint::UnknownBackend| PyValueError::new_err(e.to_string()))?;
        let pool = match threads {
            None => None,
            Some(0) => return Err(PyValueError::new_err("threads: must be at least 1")),
            Some(n) => Some(Arc::new(
                rayon::ThreadPoolBuilder::new()
                    .num_threads(n)
                    .build()
                    .map_err(|e| PyValueError::new_err(format!("threads: {e}")))?,
            )),
        };
        let make = || glint::Renderer::with_adapter(b, adapter);
        let inner = py
            .detach(|| match &pool {
                Some(p) => p.install(make),
                None => make(),
            })
            .map_err(|e| from_render_error(py, &e, false))?;
        RENDERERS_MADE.fetch_add(1, Ordering::Relaxed);
        Ok(Renderer {
            inner: RwLock::new(Some(Arc::new(inner))),
            pool,
            backend: b,
        })
    }

    /// Renders `scene` (a `glint.Scene`, a path or a dict) and returns the frame as float32
    /// of shape (height, width, 4): linear RGB, and the hit distance t in the 4th channel
    /// (-1 for a miss). Exactly what `glint render -o x.exr` writes, in every bit.
    ///
    /// `size=(width, height)`, `samples` (N×N per pixel), `triangle` (`naive`,
    /// `moller-trumbore`, `watertight`) and `max_depth` override the scene's. `math` is the
    /// GPU kernel's division and square root: `exact` (correctly rounded on every driver,
    /// the default), `corrected` (the corrections even where the driver is exact) or
    /// `fast` (the driver's own). `progress`, a callable, is called as
    /// `progress(rows_done, rows_total)` while the frame is traced, on the calling thread;
    /// an exception it raises stops the render and is raised here. Ctrl-C stops the render
    /// (KeyboardInterrupt).
    ///
    /// With `aovs` (a list of AOV names: `t`, `depth`, `position`, `geo_normal`, `normal`,
    /// `albedo`, `prim_id`, `object_id`, `material_id`, `mask`) it returns a dict instead:
    /// `color`, the frame above, and one array per AOV, (height, width) for a scalar and
    /// (height, width, 3) for a vector, float32 except the ids (uint32); docs/aov.md.
    #[pyo3(signature = (scene, *, size=None, samples=None, triangle=None, max_depth=None, math="exact", progress=None, aovs=None))]
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
        progress: Option<Bound<'py, PyAny>>,
        aovs: Option<Vec<String>>,
    ) -> PyResult<Bound<'py, PyAny>> {
        let scene = scene_arg(py, scene)?;
        let mut options = options(size, samples, triangle, max_depth, math)?;
        let with_aovs = aovs.is_some();
        if let Some(names) = aovs {
            let mut list = names
                .iter()
                .map(|n| n.parse::<glint::render::Aov>())
                .collect::<Result<Vec<_>, _>>()
                .map_err(|e| PyValueError::new_err(format!("aovs: {e}")))?;
            list.sort();
            list.dedup();
            options.aovs = list;
        }
        let inner = self.inner()?;
        render_array(
            py,
            &inner,
            self.pool.as_deref(),
            &scene.get().state(),
            options,
            progress.as_ref(),
            with_aovs,
        )
    }

    /// Lets the device and the compiled pipelines go (once the renders running now end);
    /// a later `render` raises `glint.RenderError`. Closing twice is allowed.
    fn close(&self) {
        let taken = self.inner.write().unwrap_or_else(|e| e.into_inner()).take();
        drop(taken);
    }

    /// Whether `close()` was called.
    #[getter]
    fn closed(&self) -> bool {
        self.inner
            .read()
            .unwrap_or_else(|e| e.into_inner())
            .is_none()
    }

    fn __enter__(slf: Py<Self>) -> Py<Self> {
        slf
    }

    #[pyo3(signature = (*_args))]
    fn __exit__(&self, _args: &Bound<'_, PyTuple>) -> bool {
        self.close();
        false
    }

    /// The backend asked for (`auto`, `gpu`, ...).
    #[getter]
    fn backend(&self) -> String {
        self.backend.to_string()
    }

    /// What renders, in words: the adapter and driver, or the CPU tracer (`closed` once
    /// closed).
    fn describe(&self) -> String {
        self.inner()
            .map(|r| r.describe())
            .unwrap_or_else(|_| "closed".to_owned())
    }

    /// Why `auto` chose what it chose, where it says (None otherwise, and once closed).
    #[getter]
    fn note(&self) -> Option<String> {
        self.inner().ok()?.note().map(str::to_string)
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

/// What the render's thread tells the calling thread.
enum Message {
    /// Rows done of the total.
    Rows(u32, u32),
    /// The job's result, or its panic.
    Done(Box<std::thread::Result<Result<glint::render::RenderReport, glint::RenderError>>>),
}

/// Renders on `renderer` (in `pool` where given) with the GIL released, polling for
/// signals every 50 ms (Ctrl-C cancels the job, which the job's thread answers at its next
/// band) and calling `progress` with the rows as they come; the frame becomes a numpy
/// array that owns the renderer's buffer; with `as_dict`, a dict of it (`color`) and of
/// each AOV of `options.aovs`.
pub(crate) fn render_array<'py>(
    py: Python<'py>,
    renderer: &glint::Renderer,
    pool: Option<&rayon::ThreadPool>,
    scene: &State,
    options: glint::RenderOptions,
    progress: Option<&Bound<'py, PyAny>>,
    as_dict: bool,
) -> PyResult<Bound<'py, PyAny>> {
    let aovs = options.aovs.clone();
    let cancel = Arc::new(AtomicBool::new(false));
    let dict = scene.is_from_dict();
    let s: &glint::scene::Scene = &scene.scene;
    let progress = progress.map(|p| p.clone().unbind());
    let mut stopped: Option<PyErr> = None;
    let outcome = py.detach(|| {
        std::thread::scope(|threads| {
            let flag = cancel.clone();
            let (tx, rx) = std::sync::mpsc::channel();
            let rows = tx.clone();
            let want_rows = progress.is_some();
            threads.spawn(move || {
                let run = move || {
                    glint::render::Job::borrowed(s, glint::render::Output::Memory)
                        .options(options)
                        .cancel_on(flag)
                        .on_event(move |e| {
                            if let glint::render::Event::Rows { done, total } = e
                                && want_rows
                            {
                                let _ = rows.send(Message::Rows(done, total));
                            }
                        })
                        .run(renderer)
                };
                let r = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| match pool {
                    Some(p) => p.install(run),
                    None => run(),
                }));
                let _ = tx.send(Message::Done(Box::new(r)));
            });
            loop {
                match rx.recv_timeout(Duration::from_millis(50)) {
                    Ok(Message::Done(r)) => return *r,
                    Ok(Message::Rows(done, total)) => {
                        if stopped.is_none()
                            && let Some(f) = &progress
                            && let Err(e) = Python::attach(|py| f.call1(py, (done, total)))
                        {
                            cancel.store(true, Ordering::Relaxed);
                            stopped = Some(e);
                        }
                    }
                    Err(std::sync::mpsc::RecvTimeoutError::Timeout) => {
                        if stopped.is_none()
                            && let Err(e) = Python::attach(|py| py.check_signals())
                        {
                            cancel.store(true, Ordering::Relaxed);
                            stopped = Some(e);
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
    if let Some(e) = stopped {
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
    let array = PyArray1::from_vec(py, flat).reshape([h, w, 4])?.into_any();
    if !as_dict {
        return Ok(array);
    }
    let out = PyDict::new(py);
    out.set_item("color", array)?;
    if let Some(frame) = &report.aovs {
        for &aov in &aovs {
            out.set_item(aov.name(), aov_array(py, frame, aov)?)?;
        }
    }
    Ok(out.into_any())
}

/// One AOV of `frame` as a numpy array: (height, width) for a scalar, (height, width, 3)
/// for a vector; float32, or uint32 for an id.
fn aov_array<'py>(
    py: Python<'py>,
    frame: &glint::render::AovImage,
    aov: glint::render::Aov,
) -> PyResult<Bound<'py, PyAny>> {
    use glint::image::ChannelData;
    let (w, h) = (frame.width as usize, frame.height as usize);
    let channels = frame.channels(aov);
    let n = channels.len();
    let shape = |a: Bound<'py, PyAny>| -> PyResult<Bound<'py, PyAny>> {
        match n {
            1 => a.call_method1("reshape", ((h, w),)),
            _ => a.call_method1("reshape", ((h, w, n),)),
        }
    };
    match &channels[0].1 {
        ChannelData::U32(_) => {
            let mut v = Vec::with_capacity(w * h * n);
            for k in 0..w * h {
                for (_, c) in &channels {
                    if let ChannelData::U32(c) = c {
                        v.push(c[k]);
                    }
                }
            }
            shape(PyArray1::from_vec(py, v).into_any())
        }
        ChannelData::F32(_) => {
            let mut v = Vec::with_capacity(w * h * n);
            for k in 0..w * h {
                for (_, c) in &channels {
                    if let ChannelData::F32(c) = c {
                        v.push(c[k]);
                    }
                }
            }
            shape(PyArray1::from_vec(py, v).into_any())
        }
    }
}
