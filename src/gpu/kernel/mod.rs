//! The compiled kernel: the shader module, one pipeline per [`Specialisation`] and entry
//! point, the upload, the dispatch in tiles, and the readback.

use std::collections::HashMap;
use std::sync::Mutex;
use std::time::Duration;
use web_time::Instant;

use bytemuck::Pod;
use wgpu::util::DeviceExt;

use super::exact::{ExactSource, Exactness};
use super::sync::{check_size, scoped, wait};
use super::{GpuError, SHADER_SOURCE};
use crate::buffers::{HitOut, Params, RayIn, SceneBuffers, Specialisation};
use crate::image::Image;

mod bands;
mod binding;

pub use binding::RENDER_STORAGE_BUFFERS;
use binding::{SCENE_BINDINGS, scene_entries, storage_buffer, storage_entry};
pub(super) use binding::{SHADING_BINDINGS, shading_buffers};

/// The side of the square of pixels one workgroup of `render` covers (its 64 invocations
/// laid out by WGSL `pixel_of`, eight at a time in 4×2 blocks).
pub const RENDER_WORKGROUP: u32 = 8;
/// `@workgroup_size` of `query` in x.
pub const QUERY_WORKGROUP: u32 = 64;
/// Most pixels in one dispatch (16 bytes each): small enough for every device's storage
/// buffer limit and for a display driver's watchdog, large enough to keep a GPU busy.
pub const MAX_TILE_PIXELS: u64 = 1 << 22;

/// Where the GPU's time went, apart.
#[derive(Clone, Copy, Debug, Default)]
pub struct GpuTimings {
    /// Creating the compute pipeline (shader compile), zero when it was cached.
    pub compile: Duration,
    /// Creating and filling the scene buffers.
    pub upload: Duration,
    /// The dispatches, until the GPU finished.
    pub trace: Duration,
    /// Copying and mapping the output back (for `render` and `render_into`, the copy out
    /// of the mapped memory into the image too).
    pub readback: Duration,
    /// Time in the caller's band callback of `render_bands`/`render_bands_rgba8`, which
    /// reads each tile from the mapped memory (an encoder's work, say): not readback.
    /// Zero for `render` and `render_into`, whose callback is the copy into the image.
    pub band: Duration,
    /// Building the driver's acceleration structures (the ray-query tracer only).
    pub accel: Duration,
}

#[derive(Clone, Copy, PartialEq, Eq, Hash)]
pub(super) enum Entry {
    Render,
    /// `render_rgba8`: the lean frame.
    RenderRgba8,
    Query,
    /// `render_aov`: the frame's AOVs.
    Aov,
}

/// Where `render` writes (`image` in the shader).
const IMAGE_BINDING: u32 = 5;
/// Where `render_rgba8` writes (`image_rgba8` in the shader).
pub(super) const RGBA8_BINDING: u32 = 14;
/// Where `render_aov` writes (`aov_out` in the shader).
const AOV_BINDING: u32 = 16;

/// Where a kernel's pipelines get their shader module.
enum ModuleSource {
    /// Per pipeline, SPIR-V with every rewrite forbidden ([`super::exact`]).
    Exact(Box<ExactSource>),
    /// One WGSL module compiled by wgpu, specialised by override constants; the reason
    /// the exact path was not taken.
    Wgsl(wgpu::ShaderModule, &'static str),
}

/// The shader module with its layouts and a cache of specialised pipelines.
pub struct Kernel {
    flavour: Flavour,
    source: ModuleSource,
    /// The kernel's WGSL, for [`Kernel::fast_source`].
    text: String,
    /// The exact path's module without the corrections ([`super::without_corrections`]),
    /// parsed on the first pipeline that runs the driver's own division.
    fast: std::sync::OnceLock<Result<ExactSource, GpuError>>,
    render_layout: wgpu::BindGroupLayout,
    pub(super) rgba8_layout: wgpu::BindGroupLayout,
    query_layout: wgpu::BindGroupLayout,
    aov_layout: wgpu::BindGroupLayout,
    render_pipeline_layout: wgpu::PipelineLayout,
    rgba8_pipeline_layout: wgpu::PipelineLayout,
    query_pipeline_layout: wgpu::PipelineLayout,
    aov_pipeline_layout: wgpu::PipelineLayout,
    /// The WGSL binding numbers of the render, render_rgba8, query and render_aov layouts,
    /// for the exact path's binding map ([`super::exact::binding_map`]).
    bindings: [Vec<u32>; 4],
    pipelines: Mutex<HashMap<(Specialisation, Entry), wgpu::ComputePipeline>>,
    /// The device's `/` and `sqrt` are correctly rounded ([`super::rounds_correctly`]):
    /// [`crate::buffers::Math::Exact`] compiles no corrections here.
    native_rounding: bool,
}

/// The rows of each tile of a `width`×`height` frame, within the device's limits.
pub fn tile_rows(device: &wgpu::Device, width: u32, height: u32) -> u32 {
    let l = device.limits();
    let bytes = l.max_storage_buffer_binding_size.min(l.max_buffer_size);
    let max_pixels = (bytes / 16).min(MAX_TILE_PIXELS);
    let by_pixels = (max_pixels / width as u64).max(1);
    let by_dispatch = l.max_compute_workgroups_per_dimension as u64 * RENDER_WORKGROUP as u64;
    by_pixels.min(by_dispatch).min(height as u64) as u32
}

/// Which traversal a kernel's module holds.
#[derive(Clone, Copy, PartialEq, Eq)]
enum Flavour {
    /// `trace.wgsl`: one ray per invocation.
    PerRay,
    /// `trace_subgroup.wgsl`: one packet per subgroup, shadow rays in packets too
    /// (`trace_subgroup_shadows.wgsl`) or each on its own.
    Packet { shadows: bool },
    /// `trace_rq.wgsl`: the driver's acceleration structure.
    RayQuery,
}

/// The scene a render reads: kept as it is, or freed of its geometry once uploaded.
enum Source<'a> {
    Kept(&'a SceneBuffers),
    Released(&'a mut SceneBuffers),
}

impl Source<'_> {
    fn get(&self) -> &SceneBuffers {
        match self {
            Source::Kept(b) => b,
            Source::Released(b) => b,
        }
    }

    /// Frees the geometry where the caller gave it up (see `render_bands_rgba8_releasing`).
    fn release(&mut self) {
        if let Source::Released(b) = self {
            b.release_geometry();
        }
    }
}

impl Kernel {
    /// Compiles the shader module on `device` (pipelines are made on first use).
    pub fn new(device: &wgpu::Device) -> Result<Kernel, GpuError> {
        Kernel::with_flavour(device, Flavour::PerRay)
    }

    /// The compute tracer with packet traversal (`shaders/trace_subgroup.wgsl`): one packet
    /// per subgroup, the same image, shadow rays in packets too. The device must have
    /// `Features::SUBGROUP`.
    pub fn new_packet(device: &wgpu::Device) -> Result<Kernel, GpuError> {
        Kernel::new_packet_with(device, true)
    }

    /// [`Kernel::new_packet`], with shadow rays in packets or each on its own (the shader
    /// module made with or without `trace_subgroup_shadows.wgsl`; the same image either
    /// way). See [`super::packet_shadows_pay`] for which to choose.
    pub fn new_packet_with(
        device: &wgpu::Device,
        shadows_in_packets: bool,
    ) -> Result<Kernel, GpuError> {
        Kernel::with_flavour(
            device,
            Flavour::Packet {
                shadows: shadows_in_packets,
            },
        )
    }

    /// Whether this kernel traverses in packets (one per subgroup).
    pub fn is_packet(&self) -> bool {
        matches!(self.flavour, Flavour::Packet { .. })
    }

    /// The traversal, as bench rows and `glint render` name it: "packet", "packet, shadow
    /// rays per ray", "per-ray", or "ray query".
    pub fn traversal_name(&self) -> &'static str {
        match self.flavour {
            Flavour::RayQuery => "ray query",
            Flavour::Packet { shadows: true } => "packet",
            Flavour::Packet { shadows: false } => "packet, shadow rays per ray",
            Flavour::PerRay => "per-ray",
        }
    }

    /// The ray-query tracer's kernel (`shaders/trace_rq.wgsl`): the same entry points and
    /// buffers, the triangles traced through the driver's acceleration structure. The
    /// device must have `Features::EXPERIMENTAL_RAY_QUERY`.
    pub fn new_ray_query(device: &wgpu::Device) -> Result<Kernel, GpuError> {
        Kernel::with_flavour(device, Flavour::RayQuery)
    }

    /// Whether this is the ray-query kernel.
    pub fn is_ray_query(&self) -> bool {
        self.flavour == Flavour::RayQuery
    }

    /// Whether [`crate::buffers::Math::Exact`] runs the device's own `/` and `sqrt` (they
    /// are correctly rounded: [`super::rounds_correctly`]) rather than the corrections.
    pub fn native_rounding(&self) -> bool {
        self.native_rounding
    }

    /// Whether this kernel's arithmetic reaches the driver with every rewrite forbidden.
    pub fn exactness(&self) -> Exactness {
        match self.source {
            ModuleSource::Exact(_) => Exactness::NoContraction,
            ModuleSource::Wgsl(_, why) => Exactness::NotGuaranteed(why),
        }
    }

    fn with_flavour(device: &wgpu::Device, flavour: Flavour) -> Result<Kernel, GpuError> {
        let (label, text): (&str, std::borrow::Cow<str>) = match flavour {
            Flavour::RayQuery => ("trace_rq.wgsl", super::rq::shader_source().into()),
            Flavour::Packet { shadows } => (
                "trace_subgroup.wgsl",
                super::subgroup::shader_source(shadows).into(),
            ),
            Flavour::PerRay => ("trace.wgsl", SHADER_SOURCE.into()),
        };
        let kernel_text = text.to_string();
        let exact = ExactSource::new(device, &text)?;
        scoped(device, "shader compilation", || {
            let source = match exact {
                Ok(e) => ModuleSource::Exact(Box::new(e)),
                Err(why) => ModuleSource::Wgsl(
                    device.create_shader_module(wgpu::ShaderModuleDescriptor {
                        label: Some(label),
                        source: wgpu::ShaderSource::Wgsl(text),
                    }),
                    why,
                ),
            };
            let mut render = scene_entries();
            render.extend(SHADING_BINDINGS.map(|b| storage_entry(b, true)));
            let mut query = scene_entries();
            query.push(storage_entry(6, true));
            query.push(storage_entry(7, false));
            if flavour == Flavour::RayQuery {
                let accel = wgpu::BindGroupLayoutEntry {
                    binding: super::rq::ACCEL_BINDING,
                    visibility: wgpu::ShaderStages::COMPUTE,
                    ty: wgpu::BindingType::AccelerationStructure {
                        vertex_return: false,
                    },
                    count: None,
                };
                render.push(accel);
                query.push(accel);
            }
            if matches!(flavour, Flavour::Packet { .. }) {
                for b in [
                    super::subgroup::NODE_WORDS_BINDING,
                    super::subgroup::TRIANGLE_WORDS_BINDING,
                ] {
                    render.push(storage_entry(b, true));
                    query.push(storage_entry(b, true));
                }
            }
            let layout = |label, entries: &[wgpu::BindGroupLayoutEntry]| {
                device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
                    label: Some(label),
                    entries,
                })
            };
            let with = |binding| [render.clone(), vec![storage_entry(binding, false)]].concat();
            let numbers = |e: &[wgpu::BindGroupLayoutEntry]| e.iter().map(|e| e.binding).collect();
            let (render, rgba8) = (with(IMAGE_BINDING), with(RGBA8_BINDING));
            let aov = with(AOV_BINDING);
            let bindings = [
                numbers(&render),
                numbers(&rgba8),
                numbers(&query),
                numbers(&aov),
            ];
            let render_layout = layout("render", &render);
            let rgba8_layout = layout("render_rgba8", &rgba8);
            let query_layout = layout("query", &query);
            let aov_layout = layout("render_aov", &aov);
            let pl = |bgl: &wgpu::BindGroupLayout| {
                device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
                    label: None,
                    bind_group_layouts: &[Some(bgl)],
                    immediate_size: 0,
                })
            };
            Kernel {
                flavour,
                render_pipeline_layout: pl(&render_layout),
                rgba8_pipeline_layout: pl(&rgba8_layout),
                query_pipeline_layout: pl(&query_layout),
                aov_pipeline_layout: pl(&aov_layout),
                bindings,
                source,
                text: kernel_text,
                fast: std::sync::OnceLock::new(),
                render_layout,
                rgba8_layout,
                query_layout,
                aov_layout,
                pipelines: Mutex::new(HashMap::new()),
                native_rounding: super::rounds_correctly(&device.adapter_info()),
            }
        })
    }

    /// The exact path's module without the corrections, parsed once on first use.
    fn fast_source(&self, full: &ExactSource) -> Result<&ExactSource, GpuError> {
        self.fast
            .get_or_init(|| {
                ExactSource::compile(&super::without_corrections(&self.text), full.target())
            })
            .as_ref()
            .map_err(Clone::clone)
    }

    /// The pipeline for `spec` and `entry`, compiled now (the time returned) or cached.
    pub(super) fn pipeline(
        &self,
        device: &wgpu::Device,
        spec: Specialisation,
        entry: Entry,
    ) -> Result<(wgpu::ComputePipeline, Duration), GpuError> {
        if let Some(p) = self
            .pipelines
            .lock()
            .unwrap_or_else(|e| e.into_inner())
            .get(&(spec, entry))
        {
            return Ok((p.clone(), Duration::ZERO));
        }
        let t0 = Instant::now();
        let effective = spec.math.on_driver(self.native_rounding);
        let uncorrected = effective.math == crate::buffers::Math::Fast && !effective.inexact_driver;
        let constants = spec.with_math(effective).constants();
        let (entry_point, k) = match entry {
            Entry::Render => ("render", 0),
            Entry::RenderRgba8 => ("render_rgba8", 1),
            Entry::Query => ("query", 2),
            Entry::Aov => ("render_aov", 3),
        };
        // The exact path specialises while writing the SPIR-V, so its pipeline gets no
        // constants; the WGSL path hands them to wgpu.
        let exact_module;
        let (module, constants): (&wgpu::ShaderModule, &[(&str, f64)]) = match &self.source {
            ModuleSource::Exact(full) => {
                let e = if uncorrected {
                    self.fast_source(full)?
                } else {
                    full
                };
                exact_module = scoped(device, "shader compilation", || {
                    e.module(device, entry_point, &constants, &self.bindings[k])
                })??;
                (&exact_module, &[])
            }
            ModuleSource::Wgsl(m, _) => (m, &constants),
        };
        let p = scoped(device, "pipeline creation", || {
            device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
                label: Some("trace"),
                layout: Some(match entry {
                    Entry::Render => &self.render_pipeline_layout,
                    Entry::RenderRgba8 => &self.rgba8_pipeline_layout,
                    Entry::Query => &self.query_pipeline_layout,
                    Entry::Aov => &self.aov_pipeline_layout,
                }),
                module,
                entry_point: Some(entry_point),
                compilation_options: wgpu::PipelineCompilationOptions {
                    constants,
                    zero_initialize_workgroup_memory: false,
                },
                cache: None,
            })
        })?;
        let dt = t0.elapsed();
        self.pipelines
            .lock()
            .unwrap_or_else(|e| e.into_inner())
            .insert((spec, entry), p.clone());
        Ok((p, dt))
    }

    /// Compiles (or finds cached) the pipeline for `spec` and returns the compile time.
    pub fn prepare(
        &self,
        device: &wgpu::Device,
        spec: Specialisation,
    ) -> Result<Duration, GpuError> {
        Ok(self.pipeline(device, spec, Entry::Render)?.1)
    }

    /// Forgets every compiled pipeline (so that the next render measures a compile).
    pub fn clear_cache(&self) {
        self.pipelines
            .lock()
            .unwrap_or_else(|e| e.into_inner())
            .clear();
    }

    /// The scene's bind-group entries: its buffers at `SCENE_BINDINGS`, then what this
    /// kernel's flavour adds: the acceleration structure (ray queries; `accel` must then be
    /// given), or the BVH nodes and triangles again as dword views (packet traversal).
    pub(super) fn scene_bindings<'a>(
        &self,
        scene: &'a [wgpu::Buffer; 7],
        accel: Option<&'a super::rq::Accel>,
    ) -> Vec<wgpu::BindGroupEntry<'a>> {
        let mut entries: Vec<wgpu::BindGroupEntry> = scene
            .iter()
            .enumerate()
            .map(|(k, b)| wgpu::BindGroupEntry {
                binding: SCENE_BINDINGS[k],
                resource: b.as_entire_binding(),
            })
            .collect();
        if let Some(a) = accel {
            entries.push(wgpu::BindGroupEntry {
                binding: super::rq::ACCEL_BINDING,
                resource: wgpu::BindingResource::AccelerationStructure(&a.tlas),
            });
        }
        if self.is_packet() {
            entries.push(wgpu::BindGroupEntry {
                binding: super::subgroup::NODE_WORDS_BINDING,
                resource: scene[5].as_entire_binding(),
            });
            entries.push(wgpu::BindGroupEntry {
                binding: super::subgroup::TRIANGLE_WORDS_BINDING,
                resource: scene[2].as_entire_binding(),
            });
        }
        entries
    }

    /// Where `entry`'s image goes and the bind-group layout of that entry point (`render`
    /// and `render_rgba8`).
    fn output_binding(&self, entry: Entry) -> (u32, &wgpu::BindGroupLayout) {
        match entry {
            Entry::RenderRgba8 => (RGBA8_BINDING, &self.rgba8_layout),
            Entry::Aov => (AOV_BINDING, &self.aov_layout),
            _ => (IMAGE_BINDING, &self.render_layout),
        }
    }

    /// The bind group of a render entry point (`render` or `render_rgba8`): the scene's
    /// entries ([`Kernel::scene_bindings`]), `output` where `entry` writes, and the shading
    /// buffers ([`shading_buffers`]) at `SHADING_BINDINGS`.
    pub(super) fn render_bind_group(
        &self,
        device: &wgpu::Device,
        entry: Entry,
        scene: &[wgpu::Buffer; 7],
        shading: &[wgpu::Buffer; 3],
        accel: Option<&super::rq::Accel>,
        output: &wgpu::Buffer,
    ) -> wgpu::BindGroup {
        let (out_binding, layout) = self.output_binding(entry);
        let mut entries = self.scene_bindings(scene, accel);
        entries.push(wgpu::BindGroupEntry {
            binding: out_binding,
            resource: output.as_entire_binding(),
        });
        for (binding, b) in SHADING_BINDINGS.into_iter().zip(shading) {
            entries.push(wgpu::BindGroupEntry {
                binding,
                resource: b.as_entire_binding(),
            });
        }
        device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("render"),
            layout,
            entries: &entries,
        })
    }

    /// The driver's acceleration structure over `buf`'s triangles for the ray-query
    /// kernel (built and waited for); `None` for the others.
    pub(super) fn accel(
        &self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        buf: &SceneBuffers,
    ) -> Result<Option<super::rq::Accel>, GpuError> {
        if !self.is_ray_query() {
            return Ok(None);
        }
        if !buf.instances.is_empty() {
            return Err(GpuError::RayQueryInstances);
        }
        super::rq::build(device, queue, &buf.triangles).map(Some)
    }

    pub(super) fn scene_buffers(
        &self,
        device: &wgpu::Device,
        buf: &SceneBuffers,
    ) -> Result<[wgpu::Buffer; 7], GpuError> {
        let params = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("params"),
            contents: bytemuck::bytes_of(&buf.params),
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
        });
        let none = wgpu::BufferUsages::empty();
        Ok([
            params,
            storage_buffer(device, "spheres", &buf.spheres, none)?,
            storage_buffer(device, "triangles", &buf.triangles, none)?,
            storage_buffer(device, "materials", &buf.materials, none)?,
            storage_buffer(device, "lights", &buf.lights, none)?,
            if buf.instances.is_empty() {
                storage_buffer(device, "BVH nodes", &buf.nodes, none)?
            } else {
                storage_buffer(device, "BVH nodes", &buf.node_words(), none)?
            },
            storage_buffer(device, "BVH primitive ids", &buf.prim_ids, none)?,
        ])
    }
}
