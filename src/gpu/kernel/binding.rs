//! The kernel's bindings: the bind group layout entries of the scene and shading buffers,
//! and the buffers made for them.

use super::*;

pub(super) fn storage_entry(binding: u32, read_only: bool) -> wgpu::BindGroupLayoutEntry {
    wgpu::BindGroupLayoutEntry {
        binding,
        visibility: wgpu::ShaderStages::COMPUTE,
        ty: wgpu::BindingType::Buffer {
            ty: wgpu::BufferBindingType::Storage { read_only },
            has_dynamic_offset: false,
            min_binding_size: None,
        },
        count: None,
    }
}

/// The scene's read-only storage bindings: spheres, triangles, materials, lights, BVH
/// nodes, primitive ids (binding 0 is `params`).
pub(super) const SCENE_STORAGE: [u32; 6] = [1, 2, 3, 4, 8, 9];
/// What `shade` alone reads, so bound for `render` only (the `query` entry point stays
/// within eight storage buffers): the smooth triangles' vertex normals, the textured
/// triangles' coordinates, the textures (places and texels, one buffer).
pub(in crate::gpu) const SHADING_BINDINGS: [u32; 3] = [10, 15, 17];
/// The storage buffers `render` and `render_rgba8` bind: the scene's, the shading's and
/// the output. A device must offer that many per shader stage
/// (`maxStorageBuffersPerShaderStage`; WebGPU's default is 8, most adapters offer 10).
pub const RENDER_STORAGE_BUFFERS: u32 = (SCENE_STORAGE.len() + SHADING_BINDINGS.len() + 1) as u32;
/// Every scene binding, in the order of `Kernel::scene_buffers`.
pub(super) const SCENE_BINDINGS: [u32; 7] = [0, 1, 2, 3, 4, 8, 9];

pub(super) fn scene_entries() -> Vec<wgpu::BindGroupLayoutEntry> {
    let mut v = vec![wgpu::BindGroupLayoutEntry {
        binding: 0,
        visibility: wgpu::ShaderStages::COMPUTE,
        ty: wgpu::BindingType::Buffer {
            ty: wgpu::BufferBindingType::Uniform,
            has_dynamic_offset: false,
            min_binding_size: wgpu::BufferSize::new(size_of::<Params>() as u64),
        },
        count: None,
    }];
    v.extend(SCENE_STORAGE.iter().map(|&b| storage_entry(b, true)));
    v
}

/// The shading buffers in the order of `SHADING_BINDINGS`: vertex normals, texture
/// coordinates, texels.
pub(in crate::gpu) fn shading_buffers(
    device: &wgpu::Device,
    buf: &SceneBuffers,
) -> Result<[wgpu::Buffer; 3], GpuError> {
    let none = wgpu::BufferUsages::empty();
    Ok([
        storage_buffer(device, "vertex normals", &buf.normals, none)?,
        storage_buffer(device, "texture coordinates", &buf.uvs, none)?,
        storage_buffer(device, "texels", &buf.texels, none)?,
    ])
}

/// A storage buffer holding `data`, or one zeroed element when `data` is empty (WGSL has
/// no empty bindings). Fails when the device's limits are smaller than the data.
pub(super) fn storage_buffer<T: Pod + Default>(
    device: &wgpu::Device,
    what: &'static str,
    data: &[T],
    usage: wgpu::BufferUsages,
) -> Result<wgpu::Buffer, GpuError> {
    let one = [T::default()];
    let data = if data.is_empty() { &one[..] } else { data };
    let bytes: &[u8] = bytemuck::cast_slice(data);
    check_size(device, what, bytes.len() as u64)?;
    Ok(
        device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some(what),
            contents: bytes,
            usage: wgpu::BufferUsages::STORAGE | usage,
        }),
    )
}
