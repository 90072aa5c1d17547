//! A scene kept on the device across frames, for interactive views: its buffers, the
//! driver's acceleration structure where the kernel uses one, the 8-bit frame buffer and
//! the bind group are made once ([`Kernel::resident`]); a frame writes the parameters
//! (the camera), dispatches `render_rgba8` over the whole frame and copies the packed
//! pixels into a texture on the same device, with no readback. The pixels are
//! `render_bands_rgba8`'s (the same pipeline and parameters).

use std::time::Duration;
use web_time::Instant;

use super::GpuError;
use super::kernel::{Entry, Kernel, RENDER_WORKGROUP, shading_buffers};
use super::sync::{check_size, scoped, wait};
use crate::buffers::{Params, SceneBuffers, Specialisation};

/// A scene uploaded once, drawn into textures as often as asked (see the module's doc).
pub struct Resident {
    pipeline: wgpu::ComputePipeline,
    params: wgpu::Buffer,
    output: wgpu::Buffer,
    bind_group: wgpu::BindGroup,
    width: u32,
    height: u32,
    /// The buffers the bind group holds (kept alive with it).
    _buffers: Vec<wgpu::Buffer>,
    _accel: Option<super::rq::Accel>,
}

impl Kernel {
    /// Uploads `buf` (its frame size fixed from now on) and compiles the pipeline for
    /// `spec`; fails where the device's limits are smaller than the scene or the frame.
    pub fn resident(
        &self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        buf: &SceneBuffers,
        spec: Specialisation,
    ) -> Result<Resident, GpuError> {
        let (width, height) = (buf.params.width, buf.params.height);
        let (pipeline, _) = self.pipeline(device, spec, Entry::RenderRgba8)?;
        let bytes = width as u64 * height as u64 * 4;
        check_size(device, "the frame", bytes)?;
        let (scene, shading, output) = scoped(device, "upload", || -> Result<_, GpuError> {
            let scene = self.scene_buffers(device, buf)?;
            let shading = shading_buffers(device, buf)?;
            let output = device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("frame (rgba8)"),
                size: bytes,
                usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
                mapped_at_creation: false,
            });
            Ok((scene, shading, output))
        })??;
        let accel = self.accel(device, queue, buf)?;
        let bind_group = self.render_bind_group(
            device,
            Entry::RenderRgba8,
            &scene,
            &shading,
            accel.as_ref(),
            &output,
        );
        let [params, rest @ ..] = scene;
        Ok(Resident {
            pipeline,
            params,
            output,
            bind_group,
            width,
            height,
            _buffers: rest.into_iter().chain(shading).collect(),
            _accel: accel,
        })
    }
}

impl Resident {
    /// The frame's size.
    pub fn size(&self) -> (u32, u32) {
        (self.width, self.height)
    }

    /// Traces the frame with `params` (a camera moved by [`SceneBuffers::set_camera`]; the
    /// size must be this scene's) into `texture` (`Rgba8Unorm`, the frame's size, with
    /// `COPY_DST`), and waits for it: the time taken.
    pub fn frame(
        &self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        params: &Params,
        texture: &wgpu::Texture,
    ) -> Result<Duration, GpuError> {
        let t0 = Instant::now();
        let (w, h) = (self.width, self.height);
        let mut enc = self.trace(device, queue, params);
        // Row by row where a row's bytes are not a multiple of the copy alignment (the
        // frame buffer is packed; a texture copy's rows must be aligned).
        let row = 4 * w;
        let extent = |rows: u32| wgpu::Extent3d {
            width: w,
            height: rows,
            depth_or_array_layers: 1,
        };
        let to = |y: u32| wgpu::TexelCopyTextureInfo {
            texture,
            mip_level: 0,
            origin: wgpu::Origin3d { x: 0, y, z: 0 },
            aspect: wgpu::TextureAspect::All,
        };
        if row.is_multiple_of(wgpu::COPY_BYTES_PER_ROW_ALIGNMENT) {
            enc.copy_buffer_to_texture(
                wgpu::TexelCopyBufferInfo {
                    buffer: &self.output,
                    layout: wgpu::TexelCopyBufferLayout {
                        offset: 0,
                        bytes_per_row: Some(row),
                        rows_per_image: Some(h),
                    },
                },
                to(0),
                extent(h),
            );
        } else {
            for y in 0..h {
                enc.copy_buffer_to_texture(
                    wgpu::TexelCopyBufferInfo {
                        buffer: &self.output,
                        layout: wgpu::TexelCopyBufferLayout {
                            offset: y as u64 * row as u64,
                            bytes_per_row: None,
                            rows_per_image: None,
                        },
                    },
                    to(y),
                    extent(1),
                );
            }
        }
        scoped(device, "trace", || queue.submit([enc.finish()]))?;
        wait(device, "trace")?;
        Ok(t0.elapsed())
    }

    /// Traces the frame with `params` as [`Resident::frame`] does and copies its packed
    /// pixels (rows top to bottom, red in each word's lowest byte) into `staging`
    /// (`MAP_READ | COPY_DST`, at least `4 × width × height` bytes), without waiting: for
    /// a caller that maps the buffer itself, as a browser must (a WebGPU map completes
    /// only once control is back in the page's event loop).
    pub fn frame_to_buffer(
        &self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        params: &Params,
        staging: &wgpu::Buffer,
    ) -> Result<(), GpuError> {
        let bytes = 4 * self.width as u64 * self.height as u64;
        let mut enc = self.trace(device, queue, params);
        enc.copy_buffer_to_buffer(&self.output, 0, staging, 0, bytes);
        scoped(device, "trace", || queue.submit([enc.finish()]))?;
        Ok(())
    }

    /// Writes `params` (as a whole-frame tile) and records the dispatch of `render_rgba8`
    /// into the frame buffer.
    fn trace(
        &self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        params: &Params,
    ) -> wgpu::CommandEncoder {
        let (w, h) = (self.width, self.height);
        let params = Params {
            tile_x: 0,
            tile_y: 0,
            tile_width: w,
            tile_height: h,
            ..*params
        };
        queue.write_buffer(&self.params, 0, bytemuck::bytes_of(&params));
        let mut enc = device.create_command_encoder(&Default::default());
        {
            let mut pass = enc.begin_compute_pass(&Default::default());
            pass.set_pipeline(&self.pipeline);
            pass.set_bind_group(0, &self.bind_group, &[]);
            pass.dispatch_workgroups(
                w.div_ceil(RENDER_WORKGROUP),
                h.div_ceil(RENDER_WORKGROUP),
                1,
            );
        }
        enc
    }
}
