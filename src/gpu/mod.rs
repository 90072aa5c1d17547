//! The GPU tracer: adapter choice and device creation ([`Gpu::new`]) kept apart from the
//! work ([`Kernel::render`], [`Kernel::query`]), which takes any `wgpu::Device` so that tests
//! inject one.

pub mod exact;
mod kernel;
mod resident;
pub mod rq;
pub mod spirv;
pub mod subgroup;
mod sync;

use std::sync::OnceLock;
use std::time::Duration;
use web_time::Instant;

pub use kernel::{GpuTimings, Kernel, RENDER_STORAGE_BUFFERS, tile_rows};
pub use resident::Resident;

/// The WGSL source of the kernel: `shaders/exact.wgsl`, `common.wgsl`, `prims.wgsl`,
/// `texture.wgsl`, `trace.wgsl`, `instance.wgsl`, `whitted.wgsl` and `aov.wgsl`, joined in that order (WGSL
/// needs no declaration before use).
pub const SHADER_SOURCE: &str = concat!(
    include_str!("../../shaders/exact.wgsl"),
    include_str!("../../shaders/common.wgsl"),
    include_str!("../../shaders/prims.wgsl"),
    include_str!("../../shaders/texture.wgsl"),
    include_str!("../../shaders/trace.wgsl"),
    include_str!("../../shaders/instance.wgsl"),
    include_str!("../../shaders/whitted.wgsl"),
    include_str!("../../shaders/aov.wgsl"),
);

/// `text` (a kernel's WGSL, `exact.wgsl` first) with `div_rn` and `sqrt_rn` reduced to the
/// driver's own operations: the kernel that `--math fast` and a trusted driver's `exact`
/// run. The same function as the whole text with `EXACT_MATH` off, without the corrections'
/// dead code at every call site, which costs lavapipe seconds to compile (4.4 s against
/// 0.3 s for whitted's pipeline).
pub fn without_corrections(text: &str) -> String {
    let mut out = text.to_string();
    for (head, body) in [
        (
            "fn div_rn(a: f32, b: f32) -> f32 {\n",
            "    return approx_div(a, b);\n",
        ),
        (
            "fn sqrt_rn(x: f32) -> f32 {\n",
            "    return approx_sqrt(x);\n",
        ),
    ] {
        let start = out
            .find(head)
            .expect("exact.wgsl defines div_rn and sqrt_rn")
            + head.len();
        let end = start
            + out[start..]
                .find("\n}\n")
                .expect("a function ends with `}`")
            + 1;
        out.replace_range(start..end, body);
    }
    out
}

/// Why the GPU tracer could not run.
#[derive(Clone, Debug, thiserror::Error)]
pub enum GpuError {
    /// No Vulkan adapter at all.
    #[error(
        "no Vulkan adapter found: install a Vulkan driver (on Debian or Ubuntu: \
         `apt-get install mesa-vulkan-drivers libvulkan1` gives lavapipe, a CPU Vulkan), \
         or use --backend cpu"
    )]
    NoAdapter,
    /// `--adapter NAME` matched none.
    #[error("no Vulkan adapter matches {wanted:?}; found: {found}")]
    AdapterNotFound {
        /// What was asked for.
        wanted: String,
        /// What there is.
        found: String,
    },
    /// The device could not be created.
    #[error("cannot create a device on {adapter}: {message}")]
    Device {
        /// Adapter name.
        adapter: String,
        /// wgpu's message.
        message: String,
    },
    /// The scene needs a buffer larger than the device allows.
    #[error(
        "{what} needs {needed} bytes but this device allows at most {limit} bytes in one \
         storage buffer (max_storage_buffer_binding_size / max_buffer_size)"
    )]
    TooLarge {
        /// Which buffer.
        what: &'static str,
        /// Bytes needed.
        needed: u64,
        /// Bytes allowed.
        limit: u64,
    },
    /// The ray-query tracer was asked for on an adapter without ray queries.
    #[error(
        "{adapter} has no ray queries (VK_KHR_ray_query with acceleration structures, which \
         wgpu offers as EXPERIMENTAL_RAY_QUERY): the ray-query tracer needs Mesa ≥ 24.1's \
         lavapipe or a ray-tracing GPU (NVIDIA RTX, AMD RDNA2 or later, Intel Arc); \
         --backend gpu runs the compute tracer here"
    )]
    NoRayQuery {
        /// The adapter asked.
        adapter: String,
    },
    /// The ray-query tracer was given a scene with `[[instances]]`, which its one
    /// acceleration structure does not place.
    #[error(
        "the ray-query tracer does not take scenes with [[instances]] yet: \
         --backend gpu (the compute tracer) or cpu renders them"
    )]
    RayQueryInstances,
    /// Out of memory, a validation error, or a lost device during the work.
    #[error("GPU error during {during}: {message}")]
    Runtime {
        /// What was being done.
        during: &'static str,
        /// wgpu's message.
        message: String,
    },
    /// The GPU did not finish in time.
    #[error("the GPU did not finish {during} within {seconds} s")]
    Timeout {
        /// What was being done.
        during: &'static str,
        /// The limit.
        seconds: u64,
    },
}

/// A device, its queue and the compiled kernel: one per process is enough.
pub struct Gpu {
    /// What the adapter says of itself.
    pub info: wgpu::AdapterInfo,
    /// The device.
    pub device: wgpu::Device,
    /// Its queue.
    pub queue: wgpu::Queue,
    /// The shader module and pipelines, with the per-ray traversal.
    pub kernel: Kernel,
    /// The per-ray traversal only ([`GpuOptions::per_ray_traversal`]).
    per_ray_traversal: bool,
    /// Shadow rays in packets, where not the adapter's choice ([`GpuOptions::packet_shadows`]).
    packet_shadows: Option<bool>,
    /// The packet traversal's kernel, made on first use ([`Gpu::packet_kernel`]).
    packet: OnceLock<Result<Option<Kernel>, GpuError>>,
    /// The ray-query tracer's kernel, made on first use ([`Gpu::ray_query_kernel`]).
    ray_query: OnceLock<Result<Kernel, GpuError>>,
    /// Time to find the adapter and create the device.
    pub start_time: Duration,
}

/// Whether the adapter's own `/` and `sqrt` are IEEE 754's, correctly rounded, so that
/// [`crate::buffers::Math::Exact`] needs no corrections there: Mesa's lavapipe, which
/// compiles them to LLVM's `fdiv` and `sqrt` without fast-math flags (x86's `divps` and
/// `sqrtps`). Checked on 22.3, 25.0 and 26.1 by `tests/exact_math.rs` (normal operands and
/// quotients; 26.1 flushes subnormals in compute, which glint's own flush covers:
/// docs/exactness.md). Every other driver gets the corrections.
pub fn rounds_correctly(info: &wgpu::AdapterInfo) -> bool {
    info.device_type == wgpu::DeviceType::Cpu
        && (info.driver.to_lowercase().contains("llvmpipe")
            || info.name.to_lowercase().contains("llvmpipe"))
}

/// Whether shadow rays should go in packets on this adapter: yes, except on lavapipe
/// before Mesa 24.3, which runs both sides of every branch, even where no lane takes one
/// (24.3 skips an inactive branch), so packets of shadow rays are slower there
/// (`docs/bench/ab.md`). A driver whose version cannot be read gets packets.
pub fn packet_shadows_pay(info: &wgpu::AdapterInfo) -> bool {
    if info.device_type != wgpu::DeviceType::Cpu {
        return true;
    }
    match mesa_version(&info.driver_info) {
        Some(v) => v >= (24, 3),
        None => true,
    }
}

/// Whether the packet traversal (one packet per subgroup) pays on this adapter: on CPU
/// Vulkan implementations yes (`docs/bench/ab.md`); on GPUs no, where the one measured
/// (an NVIDIA H200) ran the per-ray traversal faster or level on every scene
/// (`docs/bench/gpu-h200.md`).
pub fn packet_traversal_pays(info: &wgpu::AdapterInfo) -> bool {
    info.device_type == wgpu::DeviceType::Cpu
}

/// (major, minor) of the first "Mesa X.Y" in a driver string, as lavapipe reports it
/// ("Mesa 22.3.6 (LLVM 15.0.6)", "Mesa 25.0.7-2~bpo12+1 (LLVM 15.0.6)").
pub fn mesa_version(driver_info: &str) -> Option<(u32, u32)> {
    let rest = &driver_info[driver_info.find("Mesa ")? + 5..];
    let mut parts = rest.split(|c: char| !c.is_ascii_digit());
    let major = parts.next()?.parse().ok()?;
    let minor = parts.next()?.parse().ok()?;
    Some((major, minor))
}

/// The Vulkan adapters on this machine, best first: discrete GPU, integrated, virtual,
/// then CPU implementations such as lavapipe.
pub fn adapters() -> Vec<wgpu::Adapter> {
    let instance = wgpu::Instance::new(wgpu::InstanceDescriptor {
        backends: wgpu::Backends::VULKAN,
        ..wgpu::InstanceDescriptor::new_without_display_handle()
    });
    let mut list = pollster::block_on(instance.enumerate_adapters(wgpu::Backends::VULKAN));
    rank_adapters(&mut list);
    list
}

/// Sorts adapters best first: discrete GPUs, then integrated, virtual, CPU (lavapipe),
/// other; the driver's order kept within a kind.
pub fn rank_adapters(list: &mut [wgpu::Adapter]) {
    list.sort_by_key(|a| match a.get_info().device_type {
        wgpu::DeviceType::DiscreteGpu => 0,
        wgpu::DeviceType::IntegratedGpu => 1,
        wgpu::DeviceType::VirtualGpu => 2,
        wgpu::DeviceType::Cpu => 3,
        wgpu::DeviceType::Other => 4,
    });
}

/// How [`Gpu::with_options`] makes its device: settings as values (the command line reads
/// them from the environment, once, in `main`).
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct GpuOptions {
    /// The first adapter whose name contains this (case-insensitive); `None`: the best.
    pub adapter: Option<String>,
    /// The largest buffer the device may have, below the adapter's own limit: a smaller
    /// GPU's limits on this one, so that the too-large path (the error naming the buffer,
    /// and `auto`'s fall-back to the CPU) can be tried on any machine
    /// (`GLINT_MAX_BUFFER_BYTES` on the command line).
    pub max_buffer_bytes: Option<u64>,
    /// The per-ray BVH traversal even where the device has subgroups for the packet one
    /// (`GLINT_TRAVERSAL=ray` on the command line). The same image either way.
    pub per_ray_traversal: bool,
    /// In the packet traversal, whether shadow rays go in packets too: `None` for the
    /// adapter's measured choice ([`packet_shadows_pay`]), else as given
    /// (`GLINT_PACKET_SHADOWS=0|1` on the command line). The same image either way.
    pub packet_shadows: Option<bool>,
}

impl GpuOptions {
    /// The defaults with `adapter` picked by name.
    pub fn adapter(name: Option<&str>) -> GpuOptions {
        GpuOptions {
            adapter: name.map(str::to_string),
            ..GpuOptions::default()
        }
    }
}

/// The adapter's limits, with the largest buffer capped at `cap` when given.
fn capped_limits(mut l: wgpu::Limits, cap: Option<u64>) -> wgpu::Limits {
    if let Some(cap) = cap {
        l.max_buffer_size = l.max_buffer_size.min(cap);
        l.max_storage_buffer_binding_size = l.max_storage_buffer_binding_size.min(cap);
    }
    l
}

/// Whether an adapter is a CPU implementation (lavapipe, SwiftShader).
pub fn is_cpu_adapter(info: &wgpu::AdapterInfo) -> bool {
    info.device_type == wgpu::DeviceType::Cpu
}

impl Gpu {
    /// Opens the best adapter, or the first whose name contains `name` (case-insensitive),
    /// with the default [`GpuOptions`].
    pub fn new(name: Option<&str>) -> Result<Gpu, GpuError> {
        Gpu::with_options(&GpuOptions::adapter(name))
    }

    /// Opens the adapter `options` names (or the best) as `options` say.
    pub fn with_options(options: &GpuOptions) -> Result<Gpu, GpuError> {
        let t0 = Instant::now();
        Gpu::from_adapters(adapters(), options, t0)
    }

    /// [`Gpu::with_options`] from an adapter list already enumerated ([`adapters`], best
    /// first), so a caller that looked at the list does not enumerate twice; `since` starts
    /// the clock of `start_time`.
    pub fn from_adapters(
        list: Vec<wgpu::Adapter>,
        options: &GpuOptions,
        since: Instant,
    ) -> Result<Gpu, GpuError> {
        let name = options.adapter.as_deref();
        let t0 = since;
        if list.is_empty() {
            return Err(GpuError::NoAdapter);
        }
        let adapter = match name {
            None => list.into_iter().next().ok_or(GpuError::NoAdapter)?,
            Some(want) => {
                let found: Vec<String> = list.iter().map(|a| a.get_info().name).collect();
                let low = want.to_lowercase();
                list.into_iter()
                    .find(|a| a.get_info().name.to_lowercase().contains(&low))
                    .ok_or_else(|| GpuError::AdapterNotFound {
                        wanted: want.to_string(),
                        found: found.join(", "),
                    })?
            }
        };
        let info = adapter.get_info();
        // Ray queries where the adapter has them, for the ray-query tracer; the compute
        // tracer does not use them (and is bit-exact with them on: tests on Mesa 25).
        let rq = adapter
            .features()
            .contains(wgpu::Features::EXPERIMENTAL_RAY_QUERY);
        // Subgroups where the adapter has them, for the packet traversal.
        let subgroups = adapter.features() & wgpu::Features::SUBGROUP;
        let (device, queue) = pollster::block_on(adapter.request_device(&wgpu::DeviceDescriptor {
            label: Some("glint"),
            required_features: subgroups
                | (adapter.features() & exact::FEATURES)
                | if rq {
                    wgpu::Features::EXPERIMENTAL_RAY_QUERY
                } else {
                    wgpu::Features::empty()
                },
            // SAFETY: wgpu's experimental features are enabled only for its ray-query API,
            // which the ray-query tracer uses as documented; the acknowledgement is wgpu's.
            experimental_features: if rq {
                unsafe { wgpu::ExperimentalFeatures::enabled() }
            } else {
                wgpu::ExperimentalFeatures::disabled()
            },
            // Everything the adapter offers: large scenes need its largest storage buffers.
            required_limits: capped_limits(adapter.limits(), options.max_buffer_bytes),
            ..Default::default()
        }))
        .map_err(|e| GpuError::Device {
            adapter: info.name.clone(),
            message: e.to_string(),
        })?;
        let start_time = t0.elapsed();
        Ok(Gpu {
            start_time,
            per_ray_traversal: options.per_ray_traversal,
            packet_shadows: options.packet_shadows,
            ..Gpu::from_device(info, device, queue)?
        })
    }

    /// Wraps a device the caller made (its own adapter, limits and features) and compiles
    /// the kernel on it. `info` is the adapter's, for reports.
    pub fn from_device(
        info: wgpu::AdapterInfo,
        device: wgpu::Device,
        queue: wgpu::Queue,
    ) -> Result<Gpu, GpuError> {
        let kernel = Kernel::new(&device)?;
        Ok(Gpu {
            info,
            device,
            queue,
            kernel,
            per_ray_traversal: false,
            packet_shadows: None,
            packet: OnceLock::new(),
            ray_query: OnceLock::new(),
            start_time: Duration::ZERO,
        })
    }

    /// The compute tracer's kernel for a scene specialised as `spec`: the packet traversal
    /// where the device has it and the scene is traced through the BVH (a scene tested
    /// primitive by primitive has no traversal to share), else the per-ray one. Both give
    /// the same image, bit for bit on lavapipe.
    pub fn compute_kernel(
        &self,
        spec: crate::buffers::Specialisation,
    ) -> Result<&Kernel, GpuError> {
        // The two-level search of an instanced scene is per ray in every kernel: the
        // per-ray one is the smaller.
        if spec.instances {
            return Ok(&self.kernel);
        }
        Ok(match self.packet_kernel()? {
            Some(p) if spec.use_bvh => p,
            _ => &self.kernel,
        })
    }

    /// The packet traversal's kernel where the device has subgroups, the traversal pays on
    /// it ([`packet_traversal_pays`]) and the options did not ask for the per-ray traversal,
    /// else `None`; its shader module is made on the first call, so a process that never
    /// traverses a BVH on the GPU does not pay for it.
    pub fn packet_kernel(&self) -> Result<Option<&Kernel>, GpuError> {
        self.packet
            .get_or_init(|| {
                if self.device.features().contains(wgpu::Features::SUBGROUP)
                    && packet_traversal_pays(&self.info)
                    && !self.per_ray_traversal
                {
                    let shadows = self
                        .packet_shadows
                        .unwrap_or_else(|| packet_shadows_pay(&self.info));
                    Kernel::new_packet_with(&self.device, shadows).map(Some)
                } else {
                    Ok(None)
                }
            })
            .as_ref()
            .map(Option::as_ref)
            .map_err(Clone::clone)
    }

    /// Whether the device has ray queries (`Features::EXPERIMENTAL_RAY_QUERY`:
    /// VK_KHR_ray_query and acceleration structures).
    pub fn has_ray_query(&self) -> bool {
        self.device
            .features()
            .contains(wgpu::Features::EXPERIMENTAL_RAY_QUERY)
    }

    /// The ray-query tracer's kernel (its shader module made on the first call), or the
    /// error that this device has no ray queries.
    pub fn ray_query_kernel(&self) -> Result<&Kernel, GpuError> {
        self.ray_query
            .get_or_init(|| {
                if self.has_ray_query() {
                    Kernel::new_ray_query(&self.device)
                } else {
                    Err(GpuError::NoRayQuery {
                        adapter: format!(
                            "{} ({} {})",
                            self.info.name, self.info.driver, self.info.driver_info
                        ),
                    })
                }
            })
            .as_ref()
            .map_err(Clone::clone)
    }

    /// A one-line description: name, type, driver.
    pub fn describe(&self) -> String {
        format!(
            "{} ({:?}, {} {})",
            self.info.name, self.info.device_type, self.info.driver, self.info.driver_info
        )
    }
}

#[cfg(test)]
mod tests {
    use super::mesa_version;

    #[test]
    fn mesa_versions_are_read_from_lavapipe_driver_strings() {
        assert_eq!(mesa_version("Mesa 22.3.6 (LLVM 15.0.6)"), Some((22, 3)));
        assert_eq!(
            mesa_version("Mesa 25.0.7-2~bpo12+1 (LLVM 15.0.6)"),
            Some((25, 0))
        );
        assert_eq!(mesa_version("Mesa 24.3"), Some((24, 3)));
        assert_eq!(mesa_version("560.35.03"), None);
        assert_eq!(mesa_version("Mesa x"), None);
        assert_eq!(mesa_version(""), None);
    }
}
