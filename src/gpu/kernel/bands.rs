//! The dispatch in tiles of whole rows, each tile read back as it is done, and the
//! query entry point.

use super::*;

impl Kernel {
    /// Renders `buf` with the pipeline specialised as `spec`, in tiles of whole rows, and
    /// calls `progress(rows_done, rows_total)` after each tile.
    pub fn render(
        &self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        buf: &SceneBuffers,
        spec: Specialisation,
        progress: &mut dyn FnMut(u32, u32),
    ) -> Result<(Image, GpuTimings), GpuError> {
        let (width, height) = (buf.params.width, buf.params.height);
        let mut image = Image::new(width, height, [0.0; 4]);
        let timings = self.render_into(device, queue, buf, spec, &mut image, progress)?;
        Ok((image, timings))
    }

    /// [`Kernel::render`] written over `image`, whose pixel buffer is kept when it has the
    /// frame's size (else replaced): each tile is copied from the mapped readback buffer
    /// straight into it. A sequence of frames (the bench's timed runs) then maps and zeroes
    /// the frame's memory once, as the CPU's `render_f32_into` does.
    pub fn render_into(
        &self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        buf: &SceneBuffers,
        spec: Specialisation,
        image: &mut Image,
        progress: &mut dyn FnMut(u32, u32),
    ) -> Result<GpuTimings, GpuError> {
        let (width, height) = (buf.params.width, buf.params.height);
        image.reshape(width, height);
        let t = self.render_bands(device, queue, buf, spec, u32::MAX, &mut |y, data| {
            let start = y as usize * width as usize;
            image.pixels[start..start + data.len()].copy_from_slice(data);
            progress(y + (data.len() / width as usize) as u32, height);
        })?;
        Ok(GpuTimings {
            readback: t.readback + t.band,
            band: Duration::ZERO,
            ..t
        })
    }

    /// [`Kernel::render`] without the whole frame: tiles of at most `max_rows` rows (and the
    /// device's limit), each handed to `band(first_row, pixels)` as it is read back, top to
    /// bottom, so a frame larger than memory can be streamed to a file.
    pub fn render_bands(
        &self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        buf: &SceneBuffers,
        spec: Specialisation,
        max_rows: u32,
        band: &mut dyn FnMut(u32, &[[f32; 4]]),
    ) -> Result<GpuTimings, GpuError> {
        self.bands(
            device,
            queue,
            Source::Kept(buf),
            spec,
            Entry::Render,
            max_rows,
            band,
        )
    }

    /// [`Kernel::render_bands`] for an 8-bit image, the lean frame: each pixel is
    /// `pack_rgba8` of its colour (red in the lowest byte), packed by the shader, so a
    /// quarter of the bytes are written and read back. The bytes are the mirror's
    /// `pack_rgba8` of the f32 frame's pixels (`tests/gpu_vs_cpu.rs`).
    pub fn render_bands_rgba8(
        &self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        buf: &SceneBuffers,
        spec: Specialisation,
        max_rows: u32,
        band: &mut dyn FnMut(u32, &[u32]),
    ) -> Result<GpuTimings, GpuError> {
        let src = Source::Kept(buf);
        self.bands(device, queue, src, spec, Entry::RenderRgba8, max_rows, band)
    }

    /// [`Kernel::render_bands_rgba8`] for a caller that has no use for `buf`'s geometry once
    /// the device holds it: the triangles, BVH, primitive ids and vertex normals are freed
    /// as soon as they are uploaded ([`SceneBuffers::release_geometry`]), so the host's copy
    /// and the device's are not both held while the frame is traced (on a CPU Vulkan such
    /// as lavapipe, device memory is the host's). An error before the upload is done (a
    /// scene too large for the device, say) frees nothing, so the caller can still trace
    /// `buf` on the CPU.
    pub fn render_bands_rgba8_releasing(
        &self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        buf: &mut SceneBuffers,
        spec: Specialisation,
        max_rows: u32,
        band: &mut dyn FnMut(u32, &[u32]),
    ) -> Result<GpuTimings, GpuError> {
        let src = Source::Released(buf);
        self.bands(device, queue, src, spec, Entry::RenderRgba8, max_rows, band)
    }

    /// The frame's AOVs (WGSL `render_aov`: what the ray through each pixel's centre hit),
    /// in tiles of at most `max_rows` rows handed to `band(first_row, pixels)` as they are
    /// read back, top to bottom. The same values as the mirror's
    /// [`crate::cpu::render_aov_rows`], in every bit, wherever the colour image is.
    pub fn render_aov_bands(
        &self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        buf: &SceneBuffers,
        spec: Specialisation,
        max_rows: u32,
        band: &mut dyn FnMut(u32, &[crate::buffers::AovOut]),
    ) -> Result<GpuTimings, GpuError> {
        let src = Source::Kept(buf);
        self.bands(device, queue, src, spec, Entry::Aov, max_rows, band)
    }

    /// The render entry point `entry` in tiles, each tile's pixels (of type `T`, as that
    /// entry point writes them) handed to `band`.
    #[allow(clippy::too_many_arguments)]
    fn bands<T: Pod>(
        &self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        mut src: Source<'_>,
        spec: Specialisation,
        entry: Entry,
        max_rows: u32,
        band: &mut dyn FnMut(u32, &[T]),
    ) -> Result<GpuTimings, GpuError> {
        let buf = src.get();
        let (width, height) = (buf.params.width, buf.params.height);
        let mut timings = GpuTimings::default();
        let (pipeline, compile) = self.pipeline(device, spec, entry)?;
        let px_bytes = size_of::<T>() as u64;
        timings.compile = compile;

        let t0 = Instant::now();
        // With N×N samples a pixel, a tile holds N² times fewer pixels, so that one dispatch
        // stays about as long as without antialiasing and progress still moves.
        let per_pixel = if spec.antialias {
            (buf.params.samples as u64).pow(2).max(1)
        } else {
            1
        };
        let by_work = ((MAX_TILE_PIXELS / per_pixel) / width as u64).max(1) as u32;
        // A tile's pixels in one storage buffer: `tile_rows` counts 16 bytes a pixel, and
        // an AOV pixel is 64.
        let l = device.limits();
        let limit = l.max_storage_buffer_binding_size.min(l.max_buffer_size);
        let by_bytes = (limit / (width as u64 * px_bytes)).max(1) as u32;
        let rows = tile_rows(device, width, height)
            .min(by_work)
            .min(by_bytes)
            .min(max_rows.max(1));
        let tile_bytes = rows as u64 * width as u64 * px_bytes;
        check_size(device, "one tile of the image", tile_bytes)?;
        let (scene, shading, output, staging) =
            scoped(device, "upload", || -> Result<_, GpuError> {
                let scene = self.scene_buffers(device, buf)?;
                let shading = shading_buffers(device, buf)?;
                let output = device.create_buffer(&wgpu::BufferDescriptor {
                    label: Some("image"),
                    size: tile_bytes,
                    usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
                    mapped_at_creation: false,
                });
                let staging = device.create_buffer(&wgpu::BufferDescriptor {
                    label: Some("readback"),
                    size: tile_bytes,
                    usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
                    mapped_at_creation: false,
                });
                Ok((scene, shading, output, staging))
            })??;
        let accel = self.accel(device, queue, buf)?;
        timings.accel = accel.as_ref().map_or(Duration::ZERO, |a| a.build);
        let bind_group =
            self.render_bind_group(device, entry, &scene, &shading, accel.as_ref(), &output);
        timings.upload = t0.elapsed().saturating_sub(timings.accel);
        // From here on only the parameters are read from the host.
        let frame_params = buf.params;
        src.release();

        let mut y = 0;
        while y < height {
            let h = rows.min(height - y);
            let params = Params {
                tile_x: 0,
                tile_y: y,
                tile_width: width,
                tile_height: h,
                ..frame_params
            };
            let t1 = Instant::now();
            queue.write_buffer(&scene[0], 0, bytemuck::bytes_of(&params));
            let mut enc = device.create_command_encoder(&Default::default());
            {
                let mut pass = enc.begin_compute_pass(&Default::default());
                pass.set_pipeline(&pipeline);
                pass.set_bind_group(0, &bind_group, &[]);
                pass.dispatch_workgroups(
                    width.div_ceil(RENDER_WORKGROUP),
                    h.div_ceil(RENDER_WORKGROUP),
                    1,
                );
            }
            let bytes = h as u64 * width as u64 * px_bytes;
            enc.copy_buffer_to_buffer(&output, 0, &staging, 0, bytes);
            scoped(device, "trace", || queue.submit([enc.finish()]))?;
            wait(device, "trace")?;
            timings.trace += t1.elapsed();

            // The tile goes from the mapped memory straight to `band` (no copy of its own
            // in between); the time `band` takes is counted apart.
            let t2 = Instant::now();
            let mut in_band = Duration::ZERO;
            read_back(device, &staging, bytes, &mut |data: &[T]| {
                let t3 = Instant::now();
                band(y, data);
                in_band += t3.elapsed();
            })?;
            timings.readback += t2.elapsed().saturating_sub(in_band);
            timings.band += in_band;
            y += h;
        }
        Ok(timings)
    }

    /// Runs the `query` entry point: the nearest hit of each ray, as `closest_hit` gives it.
    pub fn query(
        &self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        buf: &SceneBuffers,
        spec: Specialisation,
        rays: &[RayIn],
    ) -> Result<Vec<HitOut>, GpuError> {
        if rays.is_empty() {
            return Ok(Vec::new());
        }
        let (pipeline, _) = self.pipeline(device, spec, Entry::Query)?;
        let max_rays = device.limits().max_compute_workgroups_per_dimension as usize
            * QUERY_WORKGROUP as usize;
        let mut out = Vec::with_capacity(rays.len());
        let scene = self.scene_buffers(device, buf)?;
        let accel = self.accel(device, queue, buf)?;
        for chunk in rays.chunks(max_rays.min(1 << 20)) {
            let bytes = (chunk.len() * size_of::<HitOut>()) as u64;
            let ray_buf = storage_buffer(device, "rays", chunk, wgpu::BufferUsages::empty())?;
            let hits = device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("hits"),
                size: bytes,
                usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
                mapped_at_creation: false,
            });
            let staging = device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("hits readback"),
                size: bytes,
                usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            });
            let mut entries = self.scene_bindings(&scene, accel.as_ref());
            entries.push(wgpu::BindGroupEntry {
                binding: 6,
                resource: ray_buf.as_entire_binding(),
            });
            entries.push(wgpu::BindGroupEntry {
                binding: 7,
                resource: hits.as_entire_binding(),
            });
            let bind_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
                label: Some("query"),
                layout: &self.query_layout,
                entries: &entries,
            });
            let mut enc = device.create_command_encoder(&Default::default());
            {
                let mut pass = enc.begin_compute_pass(&Default::default());
                pass.set_pipeline(&pipeline);
                pass.set_bind_group(0, &bind_group, &[]);
                pass.dispatch_workgroups((chunk.len() as u32).div_ceil(QUERY_WORKGROUP), 1, 1);
            }
            enc.copy_buffer_to_buffer(&hits, 0, &staging, 0, bytes);
            scoped(device, "query", || queue.submit([enc.finish()]))?;
            wait(device, "query")?;
            read_back(device, &staging, bytes, &mut |h: &[HitOut]| {
                out.extend_from_slice(h)
            })?;
        }
        Ok(out)
    }
}

/// Maps the first `bytes` of `staging` and hands them to `take` as `T`s, in the mapped
/// memory itself.
fn read_back<T: Pod>(
    device: &wgpu::Device,
    staging: &wgpu::Buffer,
    bytes: u64,
    take: &mut dyn FnMut(&[T]),
) -> Result<(), GpuError> {
    let slice = staging.slice(..bytes);
    let (tx, rx) = std::sync::mpsc::channel();
    slice.map_async(wgpu::MapMode::Read, move |r| {
        let _ = tx.send(r);
    });
    wait(device, "readback")?;
    match rx.recv() {
        Ok(Ok(())) => {}
        Ok(Err(e)) => {
            return Err(GpuError::Runtime {
                during: "readback",
                message: e.to_string(),
            });
        }
        Err(_) => {
            return Err(GpuError::Runtime {
                during: "readback",
                message: "map callback dropped".into(),
            });
        }
    }
    {
        let view = slice.get_mapped_range().map_err(|e| GpuError::Runtime {
            during: "readback",
            message: e.to_string(),
        })?;
        take(bytemuck::cast_slice::<u8, T>(&view));
    }
    staging.unmap();
    Ok(())
}
