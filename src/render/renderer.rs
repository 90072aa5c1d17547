//! The library's front door: one [`Renderer`] for every backend, the `auto` policy, and a
//! constructor that takes the caller's own wgpu device.
//!
//! ```no_run
//! use glint::{Backend, RenderOptions, Renderer, scene::Scene};
//! let scene = Scene::load("scenes/bb8.toml")?;
//! let image = Renderer::new(Backend::Auto)?.render(&scene, &RenderOptions::default())?;
//! image.save("bb8.png".as_ref())?;
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

use crate::gpu::{Gpu, GpuError, GpuOptions, Kernel, is_cpu_adapter};
use crate::image::Image;
use crate::scene::{Scene, TriangleAlgorithm};

/// Which tracer renders.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Backend {
    /// A real GPU when there is one. When the only Vulkan adapters are CPU implementations
    /// (lavapipe, SwiftShader) the CPU tracer, which beat lavapipe on every whole render
    /// measured (`docs/bench/drivers.md`: device start and compile included), and no device
    /// is started; with no adapter at all, the CPU tracer too. [`Renderer::note`] says why.
    Auto,
    /// The WGSL compute shader on a Vulkan adapter (an error when there is none).
    Gpu,
    /// The ray-query tracer: the same shader with the triangles traced by the driver's
    /// acceleration structure (VK_KHR_ray_query), the spheres by glint's own test. An error
    /// where the adapter has no ray queries; `Auto` never picks it.
    GpuRq,
    /// The f32 CPU tracer: the shader's mirror, in packets (bit for bit lavapipe's image).
    Cpu,
    /// The f64 CPU tracer: the ground truth for error.
    CpuF64,
}

impl Backend {
    /// Every backend, in the order of [`Backend::NAMES`].
    pub const ALL: [Backend; 5] = [
        Backend::Auto,
        Backend::Gpu,
        Backend::GpuRq,
        Backend::Cpu,
        Backend::CpuF64,
    ];

    /// The names [`std::str::FromStr`] takes and [`std::fmt::Display`] writes, as the
    /// command line's `--backend` spells them.
    pub const NAMES: [&'static str; 5] = ["auto", "gpu", "gpu-rq", "cpu", "cpu-f64"];

    /// This backend's name.
    pub fn name(self) -> &'static str {
        Backend::NAMES[Backend::ALL.iter().position(|&b| b == self).unwrap_or(0)]
    }
}

/// The command line's `--backend` values: [`Backend::NAMES`], each with a line of help.
#[cfg(feature = "cli")]
impl clap::ValueEnum for Backend {
    fn value_variants<'a>() -> &'a [Self] {
        &Backend::ALL
    }

    fn to_possible_value(&self) -> Option<clap::builder::PossibleValue> {
        let help = match self {
            Backend::Auto => {
                "A real GPU when there is one; the CPU tracer when the only adapters are CPU \
                 Vulkan implementations (lavapipe: slower than the CPU tracer for every whole \
                 render measured) or there is none (said in one line); the CPU tracer too when \
                 the scene exceeds the GPU's buffers"
            }
            Backend::Gpu => "The WGSL compute shader through wgpu (Vulkan)",
            Backend::GpuRq => {
                "The shader with the triangles traced by the driver's ray queries \
                 (VK_KHR_ray_query: ray-tracing GPUs, Mesa >= 24.1's lavapipe); an error where \
                 there are none"
            }
            Backend::Cpu => "The f32 CPU mirror of the shader",
            Backend::CpuF64 => "The f64 CPU ground truth",
        };
        Some(clap::builder::PossibleValue::new(self.name()).help(help))
    }
}

/// A backend name that is none of [`Backend::NAMES`].
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
#[error("unknown backend {given:?}: expected one of auto, gpu, gpu-rq, cpu, cpu-f64")]
pub struct UnknownBackend {
    /// What was given.
    pub given: String,
}

impl std::str::FromStr for Backend {
    type Err = UnknownBackend;
    fn from_str(s: &str) -> Result<Backend, UnknownBackend> {
        Backend::NAMES
            .iter()
            .position(|&n| n == s)
            .map(|k| Backend::ALL[k])
            .ok_or_else(|| UnknownBackend {
                given: s.to_string(),
            })
    }
}

impl std::fmt::Display for Backend {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

/// Options of one render; `None` takes the scene's own value.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct RenderOptions {
    /// Image size in pixels (default: the scene camera's).
    pub size: Option<(u32, u32)>,
    /// Triangle algorithm (default: the scene's).
    pub triangle: Option<TriangleAlgorithm>,
    /// Antialiasing, N×N samples a pixel, clamped to 1..=[`crate::scene::MAX_SAMPLES`]
    /// (default: the scene camera's `samples`).
    pub samples: Option<u32>,
    /// The most reflections plus refractions along a path, clamped to
    /// 0..=[`crate::scene::MAX_DEPTH`] (default: the scene's `max_depth`).
    pub max_depth: Option<u32>,
    /// The GPU kernel's division and square root (default: exact, correctly rounded on
    /// every driver); the CPU tracers always divide as IEEE 754 does.
    pub math: crate::buffers::Math,
    /// Make the GPU driver's first approximations of `/` and `sqrt` deliberately inexact
    /// (up to ±2 ULP): with exact math the image must not change (`glint compare
    /// --inexact-driver`).
    pub inexact_driver: bool,
    /// The AOVs to write beside the colour (docs/aov.md), in [`super::Aov::ALL`]'s order;
    /// empty (the default) renders colour alone and compiles none of their code.
    pub aovs: Vec<super::Aov>,
}

impl RenderOptions {
    /// The frame's size: [`RenderOptions::size`], else the scene camera's; each side in
    /// 1..=[`crate::scene::MAX_IMAGE_SIDE`], as the scene file's are.
    pub fn checked_size(&self, scene: &Scene) -> Result<(u32, u32), RenderError> {
        let (w, h) = self.size.unwrap_or(scene.size());
        let ok = |x: u32| (1..=crate::scene::MAX_IMAGE_SIDE).contains(&(x as i64));
        if !(ok(w) && ok(h)) {
            return Err(RenderError::Size(w, h));
        }
        Ok((w, h))
    }

    /// The kernel's arithmetic these options ask for.
    pub fn math_mode(&self) -> crate::buffers::MathMode {
        crate::buffers::MathMode {
            math: self.math,
            inexact_driver: self.inexact_driver,
        }
    }

    /// Sets `buf`'s frame values that these options override (samples, depth).
    pub(crate) fn apply(&self, buf: &mut crate::buffers::SceneBuffers) {
        if let Some(n) = self.samples {
            buf.params.samples = n.clamp(1, crate::scene::MAX_SAMPLES);
        }
        if let Some(d) = self.max_depth {
            buf.params.max_depth = d.min(crate::scene::MAX_DEPTH);
        }
    }
}

/// Why a render failed.
#[derive(Debug, thiserror::Error)]
pub enum RenderError {
    /// The GPU path failed (no adapter, a buffer too large, a device error).
    #[error(transparent)]
    Gpu(#[from] GpuError),
    /// The image could not be written.
    #[error(transparent)]
    Image(#[from] crate::image::ImageError),
    /// The frame cannot fit in this process's memory (checked before any work).
    #[error(transparent)]
    Memory(#[from] super::memory::MemoryError),
    /// The scene's values are out of their domain ([`Scene::validate`]).
    #[error(transparent)]
    Scene(#[from] crate::scene::SceneError),
    /// The frame size asked for has a side outside 1..=[`crate::scene::MAX_IMAGE_SIDE`].
    #[error("size {0}x{1}: each side must be in 1..={max}", max = crate::scene::MAX_IMAGE_SIDE)]
    Size(u32, u32),
    /// The job was cancelled ([`super::Job::cancel_on`]).
    #[error("cancelled")]
    Cancelled,
    /// The AOVs cannot be written as asked.
    #[error(transparent)]
    Aov(#[from] super::AovError),
    /// The output is the scene file itself.
    #[error("{}: the output would overwrite the scene file", .0.display())]
    OverwritesScene(std::path::PathBuf),
}

/// A tracer by name: what made an image, in reports and the bench.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, serde::Serialize)]
pub enum TracerKind {
    /// The shader, specialised for the scene.
    #[serde(rename = "gpu")]
    Gpu,
    /// The shader with no specialisation (the bench's comparison).
    #[serde(rename = "gpu-general")]
    GpuGeneral,
    /// The ray-query shader.
    #[serde(rename = "gpu-rq")]
    GpuRq,
    /// The f32 CPU mirror, in packets.
    #[serde(rename = "cpu-f32")]
    CpuF32,
    /// The f64 CPU ground truth.
    #[serde(rename = "cpu-f64")]
    CpuF64,
}

impl TracerKind {
    /// The name reports print: `gpu`, `gpu-general`, `gpu-rq`, `cpu-f32`, `cpu-f64`.
    pub fn name(self) -> &'static str {
        match self {
            TracerKind::Gpu => "gpu",
            TracerKind::GpuGeneral => "gpu-general",
            TracerKind::GpuRq => "gpu-rq",
            TracerKind::CpuF32 => "cpu-f32",
            TracerKind::CpuF64 => "cpu-f64",
        }
    }

    /// Whether the GPU made the image.
    pub fn is_gpu(self) -> bool {
        matches!(
            self,
            TracerKind::Gpu | TracerKind::GpuGeneral | TracerKind::GpuRq
        )
    }
}

impl std::fmt::Display for TracerKind {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

/// The tracer a [`Renderer`] runs: what [`Backend`] resolved to.
pub enum Tracer {
    /// The f32 CPU tracer.
    Cpu,
    /// The f64 CPU tracer.
    CpuF64,
    /// The shader on this device.
    Gpu(Box<Gpu>),
    /// The ray-query shader on this device (which has ray queries).
    GpuRq(Box<Gpu>),
}

impl Tracer {
    /// What reports call this tracer.
    pub fn kind(&self) -> TracerKind {
        match self {
            Tracer::Cpu => TracerKind::CpuF32,
            Tracer::CpuF64 => TracerKind::CpuF64,
            Tracer::Gpu(_) => TracerKind::Gpu,
            Tracer::GpuRq(_) => TracerKind::GpuRq,
        }
    }

    /// The device a GPU tracer traces on; `None` for the CPU tracers.
    pub fn gpu(&self) -> Option<&Gpu> {
        match self {
            Tracer::Gpu(g) | Tracer::GpuRq(g) => Some(g),
            Tracer::Cpu | Tracer::CpuF64 => None,
        }
    }

    /// A GPU tracer's device and the kernel it runs for `spec` (the ray-query kernel for
    /// [`Tracer::GpuRq`], compiled once a device); `None` for the CPU tracers.
    pub fn kernel(
        &self,
        spec: crate::buffers::Specialisation,
    ) -> Result<Option<(&Gpu, &Kernel)>, GpuError> {
        Ok(match self {
            Tracer::Gpu(g) => Some((g, g.compute_kernel(spec)?)),
            Tracer::GpuRq(g) => Some((g, g.ray_query_kernel()?)),
            Tracer::Cpu | Tracer::CpuF64 => None,
        })
    }
}

/// Renders scenes on one backend; holds the device (if any) across renders.
pub struct Renderer {
    backend: Backend,
    tracer: Tracer,
    note: Option<String>,
}

impl Renderer {
    /// A renderer on `backend`, on the best adapter.
    pub fn new(backend: Backend) -> Result<Renderer, RenderError> {
        Renderer::with_adapter(backend, None)
    }

    /// A renderer on `backend`; for the GPU, the first adapter whose name contains
    /// `adapter` (case-insensitive). Naming an adapter makes `Auto` use it, CPU or not.
    pub fn with_adapter(backend: Backend, adapter: Option<&str>) -> Result<Renderer, RenderError> {
        Renderer::with_options(backend, &GpuOptions::adapter(adapter))
    }

    /// A renderer on `backend`, its device (if any) made as `options` say; naming an
    /// adapter there makes `Auto` use it, CPU or not.
    pub fn with_options(backend: Backend, options: &GpuOptions) -> Result<Renderer, RenderError> {
        let adapter = options.adapter.as_deref();
        let (tracer, note) = match backend {
            Backend::Cpu => (Tracer::Cpu, None),
            Backend::CpuF64 => (Tracer::CpuF64, None),
            Backend::Gpu => (Tracer::Gpu(Box::new(Gpu::with_options(options)?)), None),
            Backend::GpuRq => {
                let g = Gpu::with_options(options)?;
                g.ray_query_kernel()?;
                (Tracer::GpuRq(Box::new(g)), None)
            }
            Backend::Auto => {
                let t0 = web_time::Instant::now();
                let list = crate::gpu::adapters();
                let infos: Vec<wgpu::AdapterInfo> = list.iter().map(|a| a.get_info()).collect();
                if infos.is_empty() {
                    (
                        Tracer::Cpu,
                        Some(
                            "CPU tracer: no Vulkan adapter (apt-get install \
                             mesa-vulkan-drivers libvulkan1 for one)"
                                .to_string(),
                        ),
                    )
                } else if adapter.is_none() && infos.iter().all(is_cpu_adapter) {
                    (
                        Tracer::Cpu,
                        Some(format!(
                            "CPU tracer: the only Vulkan adapter, {}, is a CPU Vulkan (--backend gpu to use it)",
                            infos[0].name
                        )),
                    )
                } else {
                    // The list already enumerated: no second instance.
                    let g = Gpu::from_adapters(list, options, t0)?;
                    (Tracer::Gpu(Box::new(g)), None)
                }
            }
        };
        Ok(Renderer {
            backend,
            tracer,
            note,
        })
    }

    /// A GPU renderer on the caller's own device and queue (made with whatever adapter,
    /// features and limits the caller chose); `info` names the adapter in reports.
    pub fn with_device(
        info: wgpu::AdapterInfo,
        device: wgpu::Device,
        queue: wgpu::Queue,
    ) -> Result<Renderer, RenderError> {
        Ok(Renderer {
            backend: Backend::Gpu,
            tracer: Tracer::Gpu(Box::new(Gpu::from_device(info, device, queue)?)),
            note: None,
        })
    }

    /// A renderer on a [`Gpu`] the caller opened (for instance on an adapter that can also
    /// present to a window): `Gpu` and `GpuRq` trace on it, `Auto` too unless it is a CPU
    /// implementation (then the CPU tracer, as `Auto` decides everywhere), `Cpu` and
    /// `CpuF64` leave it unused.
    pub fn from_gpu(backend: Backend, gpu: Gpu) -> Result<Renderer, RenderError> {
        let (tracer, note) = match backend {
            Backend::Cpu => (Tracer::Cpu, None),
            Backend::CpuF64 => (Tracer::CpuF64, None),
            Backend::Gpu => (Tracer::Gpu(Box::new(gpu)), None),
            Backend::GpuRq => {
                gpu.ray_query_kernel()?;
                (Tracer::GpuRq(Box::new(gpu)), None)
            }
            Backend::Auto if is_cpu_adapter(&gpu.info) => (
                Tracer::Cpu,
                Some(format!(
                    "CPU tracer: the adapter, {}, is a CPU Vulkan (--backend gpu to use it)",
                    gpu.info.name
                )),
            ),
            Backend::Auto => (Tracer::Gpu(Box::new(gpu)), None),
        };
        Ok(Renderer {
            backend,
            tracer,
            note,
        })
    }

    /// What `Auto` chose and why, when it did not choose the GPU.
    pub fn note(&self) -> Option<&str> {
        self.note.as_deref()
    }

    /// The backend this renderer was asked for (`Auto` falls back to the CPU in a
    /// [`super::Job`] where the GPU cannot hold a scene).
    pub fn backend(&self) -> Backend {
        self.backend
    }

    /// The tracer this renderer runs.
    pub fn tracer(&self) -> &Tracer {
        &self.tracer
    }

    /// One line: the tracer, and for the GPU the adapter and driver.
    pub fn describe(&self) -> String {
        match &self.tracer {
            Tracer::Cpu => crate::cpu::describe_f32(),
            Tracer::CpuF64 => "cpu-f64".into(),
            Tracer::Gpu(g) => format!("gpu: {}", g.describe()),
            Tracer::GpuRq(g) => format!("gpu-rq: {}", g.describe()),
        }
    }

    /// Renders `scene` with `options`: the whole frame in memory, colours linear, t per
    /// pixel (see [`Image`]); a [`super::Job`] to [`super::Output::Memory`], whose report
    /// (warnings, timings) this drops. For files and frames larger than memory, run a
    /// [`super::Job`].
    pub fn render(&self, scene: &Scene, options: &RenderOptions) -> Result<Image, RenderError> {
        let report = super::Job::borrowed(scene, super::Output::Memory)
            .options(options.clone())
            .run(self)?;
        Ok(report.image.expect("a memory output returns its image"))
    }
}

#[cfg(test)]
mod tests {
    use super::{Backend, UnknownBackend};

    /// Every name parses to its backend and back; an unknown one is an error naming it.
    #[test]
    fn backend_names_round_trip() {
        for (b, n) in Backend::ALL.iter().zip(Backend::NAMES) {
            assert_eq!(n.parse::<Backend>(), Ok(*b));
            assert_eq!(b.to_string(), n);
        }
        // The twin: a near miss is refused, with the name in the error.
        let e = "GPU".parse::<Backend>().unwrap_err();
        assert_eq!(
            e,
            UnknownBackend {
                given: "GPU".into()
            }
        );
        assert!(e.to_string().contains("\"GPU\""));
    }
}
