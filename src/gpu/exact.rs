//! Shader modules that a Vulkan driver must compute as written: the WGSL parsed and
//! validated by naga once, then, for each pipeline, specialised (the override constants),
//! written to SPIR-V with the options wgpu itself would use, every floating-point result
//! marked `NoContraction` ([`super::spirv::forbid_contraction`]), and handed to the driver
//! through wgpu's SPIR-V passthrough.
//!
//! Why: Mesa 25.3 and later rewrite inexact arithmetic in NIR ("a + b + a → b + 2a",
//! constants moved through products, `dot` summed in reverse order); every such rewrite is
//! skipped for a `NoContraction` instruction, and the Vulkan specification forbids fusing
//! one. Without the decoration the shader's image equals the CPU mirror's only on drivers
//! that happen not to rewrite (Mesa 22.3 and 25.0 do not; 26.1 does).
//!
//! Where the device cannot take SPIR-V (no `Features::PASSTHROUGH_SHADERS`, or not the
//! Vulkan backend), [`Exactness::NotGuaranteed`] says so and wgpu compiles the WGSL as
//! usual: the same operations, but the driver may rewrite them.

use super::GpuError;

/// Whether a kernel's arithmetic reaches the driver with every rewrite forbidden.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Exactness {
    /// SPIR-V with every floating-point result decorated `NoContraction`.
    NoContraction,
    /// WGSL compiled by wgpu: the driver may fuse or reassociate; the reason is given.
    NotGuaranteed(&'static str),
}

impl Exactness {
    /// A short phrase for reports: "NoContraction SPIR-V" or "not guaranteed (reason)".
    pub fn describe(&self) -> String {
        match self {
            Exactness::NoContraction => "exact arithmetic (NoContraction SPIR-V)".to_string(),
            Exactness::NotGuaranteed(why) => format!("exactness not guaranteed: {why}"),
        }
    }
}

/// The features a device needs for exact kernels; [`super::Gpu::new`] asks for them.
pub const FEATURES: wgpu::Features = wgpu::Features::PASSTHROUGH_SHADERS;

/// What a device made by [`super::Gpu::new`] on `adapter` would give (`glint adapters`).
pub fn adapter_exactness(adapter: &wgpu::Adapter) -> Exactness {
    if adapter.get_info().backend != wgpu::Backend::Vulkan {
        Exactness::NotGuaranteed("not the Vulkan backend")
    } else if !adapter.features().contains(FEATURES) {
        Exactness::NotGuaranteed("the adapter offers no Features::PASSTHROUGH_SHADERS")
    } else {
        Exactness::NoContraction
    }
}

/// A validated naga module and the SPIR-V options of the device it is compiled for.
pub struct ExactSource {
    module: naga::Module,
    info: naga::valid::ModuleInfo,
    options: naga::back::spv::Options<'static>,
    target: SpirvTarget,
}

/// What the SPIR-V depends on of the device it is written for.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct SpirvTarget {
    /// The physical device's Vulkan version (`ash::vk::make_api_version`): the SPIR-V
    /// version follows it as wgpu's does (1.0 → 1.0, 1.1 → 1.3, 1.2 → 1.5, 1.3 → 1.6).
    pub api_version: u32,
    /// `robustBufferAccess2` enabled on the device: buffer accesses need no clamping in the
    /// shader.
    pub robust_buffer_access2: bool,
}

impl SpirvTarget {
    /// The device's facts, read through wgpu's Vulkan device as wgpu reads them for its
    /// own SPIR-V; `None` on another backend.
    pub fn of(device: &wgpu::Device) -> Option<SpirvTarget> {
        device_facts(device)
    }
}

/// In the browser there is no SPIR-V: WebGPU takes WGSL only.
#[cfg(target_arch = "wasm32")]
fn device_facts(_device: &wgpu::Device) -> Option<SpirvTarget> {
    None
}

#[cfg(not(target_arch = "wasm32"))]
fn device_facts(device: &wgpu::Device) -> Option<SpirvTarget> {
    // SAFETY: the hal device is only read (its instance, physical device and the
    // extensions wgpu enabled), while the wgpu device it belongs to is borrowed.
    let hal = unsafe { device.as_hal::<wgpu::hal::api::Vulkan>() }?;
    let shared = hal.shared_instance();
    let instance = shared.raw_instance();
    let phd = hal.raw_physical_device();
    // SAFETY: `phd` is the device's own physical device, from the same instance.
    let api_version = unsafe { instance.get_physical_device_properties(phd) }.api_version;
    let has_ext = hal
        .enabled_device_extensions()
        .contains(&ash::ext::robustness2::NAME);
    let robust_buffer_access2 =
        has_ext && shared.instance_api_version() >= ash::vk::API_VERSION_1_1 && {
            let mut r2 = ash::vk::PhysicalDeviceRobustness2FeaturesEXT::default();
            let mut f2 = ash::vk::PhysicalDeviceFeatures2::default().push_next(&mut r2);
            // SAFETY: as above; the chain lives on this stack frame.
            unsafe { instance.get_physical_device_features2(phd, &mut f2) };
            r2.robust_buffer_access2 == ash::vk::TRUE
        };
    Some(SpirvTarget {
        api_version,
        robust_buffer_access2,
    })
}

/// wgpu's own SPIR-V options for this device (wgpu-hal's Vulkan adapter: the language
/// version from the Vulkan version, index accesses clamped, buffer accesses clamped unless
/// `robustBufferAccess2` does it), so that an exact kernel's SPIR-V differs from the one
/// wgpu would write only by its decorations. Capabilities are left for naga to declare
/// as used.
fn spv_options(facts: &SpirvTarget) -> naga::back::spv::Options<'static> {
    use naga::proc::BoundsCheckPolicy as P;
    // `VK_MAKE_API_VERSION(0, 1, minor, 0)`, as ash's `API_VERSION_1_x` constants.
    let vk_1 = |minor: u32| (1 << 22) | (minor << 12);
    let lang_version = match facts.api_version {
        v if v >= vk_1(3) => (1, 6),
        v if v >= vk_1(2) => (1, 5),
        v if v >= vk_1(1) => (1, 3),
        _ => (1, 0),
    };
    naga::back::spv::Options {
        lang_version,
        flags: naga::back::spv::WriterFlags::empty(),
        capabilities: None,
        bounds_check_policies: naga::proc::BoundsCheckPolicies {
            index: P::Restrict,
            buffer: if facts.robust_buffer_access2 {
                P::Unchecked
            } else {
                P::Restrict
            },
            image_load: P::Restrict,
            binding_array: P::Unchecked,
        },
        zero_initialize_workgroup_memory: naga::back::spv::ZeroInitializeWorkgroupMemoryMode::None,
        force_loop_bounding: true,
        ..Default::default()
    }
}

/// Where wgpu puts each binding of a bind group layout in Vulkan: wgpu-hal 30 numbers a
/// layout's Vulkan bindings 0, 1, 2, ... in the order of the WGSL binding numbers (wgpu-core
/// sorts a layout's entries by binding), and rewrites the SPIR-V it writes itself to
/// match. SPIR-V handed through must be written with the same map: a WGSL binding past a
/// gap in the numbers would otherwise read another buffer. `bindings` are group 0's WGSL
/// binding numbers; empty gives the empty map (the WGSL's numbers).
pub fn binding_map(bindings: &[u32]) -> naga::back::spv::BindingMap {
    let mut sorted = bindings.to_vec();
    sorted.sort_unstable();
    sorted.dedup();
    sorted
        .iter()
        .enumerate()
        .map(|(k, &b)| {
            (
                naga::ResourceBinding {
                    group: 0,
                    binding: b,
                },
                naga::back::spv::BindingInfo {
                    descriptor_set: 0,
                    binding: k as u32,
                    binding_array_size: None,
                },
            )
        })
        .collect()
}

/// A failure of the exact path's compilation, as [`GpuError`] reports one.
fn compile_error(message: String) -> GpuError {
    GpuError::Runtime {
        during: "shader compilation",
        message,
    }
}

impl ExactSource {
    /// Parses and validates `wgsl` for `device`; `Ok(Err(reason))` where the device cannot
    /// take SPIR-V, so the caller compiles the WGSL through wgpu instead.
    pub fn new(
        device: &wgpu::Device,
        wgsl: &str,
    ) -> Result<Result<ExactSource, &'static str>, GpuError> {
        if !device.features().contains(FEATURES) {
            return Ok(Err(
                "the device was made without Features::PASSTHROUGH_SHADERS",
            ));
        }
        let Some(target) = SpirvTarget::of(device) else {
            return Ok(Err("not the Vulkan backend"));
        };
        ExactSource::compile(wgsl, target).map(Ok)
    }

    /// Parses and validates `wgsl` for SPIR-V written for `target`, with no device (the
    /// tests read the words of every kernel this way).
    pub fn compile(wgsl: &str, target: SpirvTarget) -> Result<ExactSource, GpuError> {
        let module = naga::front::wgsl::parse_str(wgsl)
            .map_err(|e| compile_error(e.emit_to_string(wgsl)))?;
        let info = naga::valid::Validator::new(
            naga::valid::ValidationFlags::all(),
            naga::valid::Capabilities::all(),
        )
        .validate(&module)
        .map_err(|e| compile_error(e.emit_to_string(wgsl)))?;
        Ok(ExactSource {
            module,
            info,
            options: spv_options(&target),
            target,
        })
    }

    /// The device facts the SPIR-V is written for.
    pub fn target(&self) -> SpirvTarget {
        self.target
    }

    /// The SPIR-V words of entry point `entry` with the override `constants` applied, as
    /// naga writes them, before the decorations (the tests' twin). `bindings` are the
    /// group-0 binding numbers of the pipeline layout the module will run under (see
    /// [`binding_map`]); empty keeps the WGSL's numbers.
    pub fn plain_spirv(
        &self,
        entry: &str,
        constants: &[(&str, f64)],
        bindings: &[u32],
    ) -> Result<Vec<u32>, GpuError> {
        let constants: naga::back::PipelineConstants =
            constants.iter().map(|&(k, v)| (k.to_string(), v)).collect();
        let (module, info) = naga::back::pipeline_constants::process_overrides(
            &self.module,
            &self.info,
            Some((naga::ShaderStage::Compute, entry)),
            &constants,
        )
        .map_err(|e| compile_error(e.to_string()))?;
        let mut options = self.options.clone();
        options.binding_map = binding_map(bindings);
        naga::back::spv::write_vec(
            &module,
            &info,
            &options,
            Some(&naga::back::spv::PipelineOptions {
                shader_stage: naga::ShaderStage::Compute,
                entry_point: entry.to_string(),
            }),
        )
        .map_err(|e| compile_error(e.to_string()))
    }

    /// The SPIR-V words of entry point `entry` with the override `constants` applied,
    /// every floating-point result decorated `NoContraction`.
    pub fn spirv(
        &self,
        entry: &str,
        constants: &[(&str, f64)],
        bindings: &[u32],
    ) -> Result<Vec<u32>, GpuError> {
        let words = self.plain_spirv(entry, constants, bindings)?;
        super::spirv::forbid_contraction(&words)
            .map(|(words, _)| words)
            .map_err(|e| compile_error(e.to_string()))
    }

    /// The driver's module for entry point `entry` specialised by `constants`, for a
    /// pipeline whose one bind group layout has the (WGSL) binding numbers `bindings`.
    pub fn module(
        &self,
        device: &wgpu::Device,
        entry: &str,
        constants: &[(&str, f64)],
        bindings: &[u32],
    ) -> Result<wgpu::ShaderModule, GpuError> {
        let words = self.spirv(entry, constants, bindings)?;
        let workgroup_size = self
            .module
            .entry_points
            .iter()
            .find(|e| e.name == entry)
            .map_or((1, 1, 1), |e| {
                (
                    e.workgroup_size[0],
                    e.workgroup_size[1],
                    e.workgroup_size[2],
                )
            });
        let entry_points = [wgpu::PassthroughShaderEntryPoint {
            name: entry.into(),
            workgroup_size,
        }];
        // SAFETY: the words are naga's SPIR-V of a module naga validated, for this device's
        // Vulkan version, with decorations added that change no meaning but the driver's
        // freedom to rewrite; bounds are checked as wgpu would check them.
        Ok(unsafe {
            device.create_shader_module_passthrough(wgpu::ShaderModuleDescriptorPassthrough {
                label: Some(entry),
                entry_points: entry_points[..].into(),
                spirv: Some(words.into()),
                ..Default::default()
            })
        })
    }
}
