//! The ray-query tracer's two parts on the host: its shader module's source (trace.wgsl
//! with the driver answering for the triangles, `shaders/trace_rq.wgsl`) and the
//! acceleration structure over a scene's triangles.

use web_time::Instant;

use super::GpuError;
use crate::buffers::Triangle;

/// The ray-query part of the shader (its doc says how the module is put together).
pub const RQ_SOURCE: &str = include_str!("../../shaders/trace_rq.wgsl");

/// The binding of the acceleration structure in the ray-query module.
pub const ACCEL_BINDING: u32 = 11;

/// The whole ray-query module: `enable wgpu_ray_query;`, `trace.wgsl` with `closest_hit`
/// and `occluded` renamed `closest_hit_compute` and `occluded_compute` (their ray-query
/// twins in `trace_rq.wgsl` take the names, so every caller, `shade` and both entry points
/// included, traces through the driver), then `trace_rq.wgsl`.
pub fn shader_source() -> String {
    let mut src = super::SHADER_SOURCE.to_string();
    for name in ["closest_hit", "occluded"] {
        let from = format!("fn {name}(");
        assert_eq!(
            src.matches(&from).count(),
            1,
            "trace.wgsl must define `{name}` exactly once"
        );
        src = src.replace(&from, &format!("fn {name}_compute("));
    }
    format!("enable wgpu_ray_query;\n{src}\n{RQ_SOURCE}")
}

/// A scene's triangles in the driver's acceleration structures: one bottom level (triangle
/// k is primitive k) and one instance of it with the identity transform.
pub struct Accel {
    /// The top level, bound at [`ACCEL_BINDING`].
    pub tlas: wgpu::Tlas,
    /// The bottom level (kept alive with the top).
    pub blas: wgpu::Blas,
    /// How long the build took, to the GPU's finish.
    pub build: std::time::Duration,
}

/// Builds the acceleration structures over `triangles` and waits for the build. The
/// triangle buffer itself is the vertex buffer: its a, b and c sit 16 bytes apart, so with
/// a stride of 16 vertex 3k + i is corner i of triangle k. With no triangles, one triangle
/// of NaN vertices stands in (Vulkan makes such a triangle inactive: never hit).
pub fn build(
    device: &wgpu::Device,
    queue: &wgpu::Queue,
    triangles: &[Triangle],
) -> Result<Accel, GpuError> {
    use wgpu::util::DeviceExt;
    let t0 = Instant::now();
    let nan = [Triangle {
        a: [f32::NAN; 3],
        b: [f32::NAN; 3],
        c: [f32::NAN; 3],
        ..Triangle::default()
    }];
    let tris = if triangles.is_empty() {
        &nan[..]
    } else {
        triangles
    };
    let bytes: &[u8] = bytemuck::cast_slice(tris);
    super::sync::check_size(
        device,
        "the acceleration structure's vertices",
        bytes.len() as u64,
    )?;
    let vertices = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
        label: Some("ray-query vertices"),
        contents: bytes,
        usage: wgpu::BufferUsages::BLAS_INPUT,
    });
    let size = wgpu::BlasTriangleGeometrySizeDescriptor {
        vertex_format: wgpu::VertexFormat::Float32x3,
        vertex_count: 3 * tris.len() as u32,
        index_format: None,
        index_count: None,
        flags: wgpu::AccelerationStructureGeometryFlags::OPAQUE,
    };
    super::sync::scoped(device, "acceleration structure build", || {
        let blas = device.create_blas(
            &wgpu::CreateBlasDescriptor {
                label: Some("glint triangles"),
                flags: wgpu::AccelerationStructureFlags::PREFER_FAST_TRACE,
                update_mode: wgpu::AccelerationStructureUpdateMode::Build,
            },
            wgpu::BlasGeometrySizeDescriptors::Triangles {
                descriptors: vec![size.clone()],
            },
        );
        let mut tlas = device.create_tlas(&wgpu::CreateTlasDescriptor {
            label: Some("glint scene"),
            max_instances: 1,
            flags: wgpu::AccelerationStructureFlags::PREFER_FAST_TRACE,
            update_mode: wgpu::AccelerationStructureUpdateMode::Build,
        });
        let identity = [1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0];
        tlas[0] = Some(wgpu::TlasInstance::new(&blas, identity, 0, 0xff));
        let mut enc = device.create_command_encoder(&Default::default());
        enc.build_acceleration_structures(
            std::iter::once(&wgpu::BlasBuildEntry {
                blas: &blas,
                geometry: wgpu::BlasGeometries::TriangleGeometries(vec![
                    wgpu::BlasTriangleGeometry {
                        size: &size,
                        vertex_buffer: &vertices,
                        first_vertex: 0,
                        vertex_stride: 16,
                        index_buffer: None,
                        first_index: None,
                        transform_buffer: None,
                        transform_buffer_offset: None,
                    },
                ]),
            }),
            std::iter::once(&tlas),
        );
        queue.submit([enc.finish()]);
        (tlas, blas)
    })
    .and_then(|(tlas, blas)| {
        super::sync::wait(device, "acceleration structure build")?;
        Ok(Accel {
            tlas,
            blas,
            build: t0.elapsed(),
        })
    })
}
