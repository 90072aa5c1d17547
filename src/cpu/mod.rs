//! The CPU tracers: the f32 mirror of the shader and the f64 ground truth, both from the
//! one generic `trace.rs`, rows in parallel with rayon.

pub mod aov;
pub mod common;
pub mod count;
pub mod exact;
pub mod instance;
pub mod packet;
pub mod prims;
pub mod texture;
/// The numeric kernel ([`crate::shared::real`]), where the mirror's arithmetic lives.
pub use crate::shared::real;
pub mod trace;
pub mod whitted;

use std::sync::atomic::{AtomicU32, Ordering};

use rayon::prelude::*;

use crate::buffers::{AovOut, HitOut, RayIn, SceneBuffers, Specialisation};
use crate::image::Image;
use crate::scene::Scene;
use count::NoCount;
use real::{Real, V3};
use trace::{Camera, Globals};

pub use crate::shared::real::camera_basis;

/// Called with (rows done, rows in all) as rows finish, from any thread.
pub type Progress<'a> = dyn Fn(u32, u32) + Sync + 'a;

fn render_with<R: Real>(g: &Globals<R>, progress: &Progress<'_>) -> Image {
    let (w, h) = (g.cam.width, g.cam.height);
    Image {
        width: w,
        height: h,
        pixels: rows_with(g, 0, h, progress),
    }
}

/// Rows `y0 .. y0 + rows` of [`render_with`]'s image, row-major.
fn rows_with<R: Real>(
    g: &Globals<R>,
    y0: u32,
    rows: u32,
    progress: &Progress<'_>,
) -> Vec<[f32; 4]> {
    let w = g.cam.width;
    let mut pixels = vec![[0.0f32; 4]; w as usize * rows as usize];
    let done = AtomicU32::new(0);
    pixels
        .par_chunks_mut(w as usize)
        .enumerate()
        .for_each(|(r, row)| {
            let j = y0 + r as u32;
            for (i, px) in row.iter_mut().enumerate() {
                let c = trace::trace_pixel(g, i as u32, j);
                *px = c.map(|x| x.to_f32());
            }
            progress(done.fetch_add(1, Ordering::Relaxed) + 1, rows);
        });
    pixels
}

/// What the f32 tracers see: the camera exactly as the shader receives it.
fn globals_f32(buf: &SceneBuffers, spec: Specialisation) -> Globals<'_, f32> {
    Globals {
        cam: Camera::from_params(&buf.params),
        buf,
        spec,
        count: NoCount,
    }
}

/// Scenes with more primitives than this go through the BVH in the packet tracer, even
/// where the shader tests every primitive (`buffers::BRUTE_FORCE_MAX`, 16): sixteen rays
/// share each node's test, so the tree pays off sooner than for the shader's one ray.
/// Interleaved, 1024×768, packets through the BVH against every primitive: mitsubishi
/// 0.47 of the time, umbrella 0.55, mitsubishi with shadows 0.70, the peers' 2 triangles
/// and 10 spheres 0.81 (docs/bench/ab.md). The same change made the shader 1.5× slower
/// on those scenes on lavapipe 22.3 and left it as it was on lavapipe 25 (0.95–1.0), so
/// the shader keeps its own threshold.
pub const PACKET_BRUTE_FORCE_MAX: usize = 2;

/// `globals_f32` for the packet tracer: `spec` with the BVH on where
/// [`PACKET_BRUTE_FORCE_MAX`] says. The image is the same either way, bit for bit:
/// `closest_hit_bvh` and `occluded_bvh` give `closest_hit_all`'s and `occluded_all`'s
/// answers (tests/packets.rs renders both ways against the mirror).
fn packet_globals(buf: &SceneBuffers, spec: Specialisation) -> Globals<'_, f32> {
    let prims = buf.spheres.len() + buf.triangles.len();
    let bvh = spec.use_bvh || (buf.params.n_nodes > 0 && prims > PACKET_BRUTE_FORCE_MAX);
    if bvh || spec.instances {
        // Made here, once, on every thread (not by the first packet that asks, while the
        // other threads wait).
        buf.leaf_triangles();
    }
    globals_f32(buf, spec.with_bvh(bvh))
}

/// Renders in packets of `packet::LANES` camera rays (blocks of `PACKET_W` × `PACKET_H`
/// pixels, bands of `PACKET_H` rows in parallel): the same image as [`render_with`].
fn render_packets(g: &Globals<f32>, simd: packet::Simd, progress: &Progress<'_>) -> Image {
    let (w, h) = (g.cam.width, g.cam.height);
    Image {
        width: w,
        height: h,
        pixels: packet_rows(g, simd, 0, h, progress),
    }
}

/// Rows `y0 .. y0 + rows` of [`render_packets`]'s image, row-major. Any `y0` gives the same
/// pixels: each lane of a packet is its own pixel's ray, whatever its neighbours.
fn packet_rows(
    g: &Globals<f32>,
    simd: packet::Simd,
    y0: u32,
    rows: u32,
    progress: &Progress<'_>,
) -> Vec<[f32; 4]> {
    let mut pixels = vec![[0.0f32; 4]; g.cam.width as usize * rows as usize];
    packet_rows_into(g, simd, y0, progress, &mut pixels);
    pixels
}

/// [`packet_rows`] written over `pixels`, whose length (a whole number of rows) gives the
/// rows. Every pixel is written, whatever `pixels` held.
fn packet_rows_into(
    g: &Globals<f32>,
    simd: packet::Simd,
    y0: u32,
    progress: &Progress<'_>,
    pixels: &mut [[f32; 4]],
) {
    let w = g.cam.width;
    let rows = (pixels.len() / w as usize) as u32;
    let done = AtomicU32::new(0);
    const PW: usize = packet::PACKET_W as usize;
    let (pw, ph) = (PW, packet::PACKET_H as usize);
    let band = ph * w as usize;
    let trace: packet::PacketFn = if g.spec.light_kinds || g.spec.textures {
        packet::trace_packet_mirror
    } else {
        packet::tracer(simd, g.spec.instances)
    };
    pixels
        .par_chunks_mut(band)
        .enumerate()
        .for_each(|(b, out)| {
            let j = y0 + (b * ph) as u32;
            // The last band may have fewer rows than a packet, the last packet of a row
            // fewer columns.
            let n = out.len() / w as usize;
            for i in (0..w as usize).step_by(pw) {
                let px = trace(g, i as u32, j);
                let cols = pw.min(w as usize - i);
                if n == ph && cols == pw {
                    // A whole packet: copies of a length known here, moves rather than a
                    // `memmove` call each (which were 5 % of a frame without primitives).
                    for (y, row) in px.chunks_exact(PW).enumerate() {
                        let at = y * w as usize + i;
                        let dst: &mut [[f32; 4]; PW] = (&mut out[at..at + PW]).try_into().unwrap();
                        *dst = row.try_into().unwrap();
                    }
                    continue;
                }
                for (y, row) in px.chunks_exact(pw).take(n).enumerate() {
                    let at = y * w as usize + i;
                    out[at..at + cols].copy_from_slice(&row[..cols]);
                }
            }
            progress(done.fetch_add(n as u32, Ordering::Relaxed) + n as u32, rows);
        });
}

/// Rows `y0 .. y0 + rows` of [`render_f32`]'s image (row-major): a band of a frame too large
/// to hold whole, for streaming it to a file. `y0 + rows` must not exceed the height.
pub fn render_f32_rows(
    buf: &SceneBuffers,
    spec: Specialisation,
    y0: u32,
    rows: u32,
) -> Vec<[f32; 4]> {
    let g = packet_globals(buf, spec);
    packet_rows(&g, packet::Simd::Best, y0, rows, &|_, _| {})
}

/// Rows `y0 .. y0 + rows` of [`render_f64`]'s image (row-major).
pub fn render_f64_rows(
    scene: &Scene,
    buf: &SceneBuffers,
    spec: Specialisation,
    y0: u32,
    rows: u32,
) -> Vec<[f32; 4]> {
    let g = globals_f64(scene, buf, spec);
    rows_with(&g, y0, rows, &|_, _| {})
}

/// The start of a progressive frame for [`add_sample_f32`]: every pixel's running sum 0 and
/// its nearest hit −1 (none yet).
pub fn samples_start(width: u32, height: u32) -> Vec<[f32; 4]> {
    vec![[0.0, 0.0, 0.0, -1.0]; width as usize * height as usize]
}

/// Adds sample position `k` of the n×n that `trace_pixel` takes (n = `buf.params.samples`;
/// row `k / n`, column `k % n`) of every pixel to `acc` (row-major, `[Σr, Σg, Σb,
/// t_near]`, from [`samples_start`]), in `trace_pixel`'s order of additions. After the
/// n² samples 0, 1, …, n² − 1, [`samples_finish`] gives [`render_f32`]'s antialiased image in
/// every bit: what a viewer shows while the camera is still, refining one sample position
/// a frame. The mirror's tracer, one ray at a time, rows in parallel.
pub fn add_sample_f32(buf: &SceneBuffers, spec: Specialisation, k: u32, acc: &mut [[f32; 4]]) {
    let g = globals_f32(buf, spec);
    let n = g.cam.samples.max(1);
    let (dx, dy) = (
        trace::sample_offset::<f32>(k % n, n),
        trace::sample_offset::<f32>(k / n, n),
    );
    let w = g.cam.width as usize;
    acc.par_chunks_mut(w).enumerate().for_each(|(j, row)| {
        for (i, a) in row.iter_mut().enumerate() {
            let s = trace::trace_sample(&g, i as u32, j as u32, dx, dy);
            let sum = V3::new(a[0], a[1], a[2]) + V3::new(s[0], s[1], s[2]);
            let mut t_near = a[3];
            if s[3] >= 0.0 && (t_near < 0.0 || s[3] < t_near) {
                t_near = s[3];
            }
            *a = [sum.x, sum.y, sum.z, t_near];
        }
    });
}

/// The picture after `k` ≥ 1 of the `n2` sample positions were added by [`add_sample_f32`]:
/// each sum divided by `k` (after all `n2`, `trace_pixel`'s flushed quotient, so the
/// image is [`render_f32`]'s in every bit), the nearest hit as it stands.
pub fn samples_finish(acc: &[[f32; 4]], k: u32, n2: u32) -> Vec<[f32; 4]> {
    acc.par_iter()
        .map(|a| {
            let c = V3::new(a[0], a[1], a[2]) / V3::splat(k as f32);
            let c = if k == n2 { common::flush3(c) } else { c };
            [c.x, c.y, c.z, a[3]]
        })
        .collect()
}

/// What `glint render` and [`crate::Renderer::describe`] call the f32 CPU tracer: "cpu
/// (f32, avx512)", with the packet build this CPU runs.
pub fn describe_f32() -> String {
    format!("cpu (f32, {})", packet::Simd::Best.name())
}

/// Renders in f32 as the shader does, specialised as the GPU would be, in packets of
/// `packet::LANES` camera rays (`packet/`). The image is [`render_f32_mirror`]'s, bit for bit
/// (`tests/packets.rs`).
pub fn render_f32(buf: &SceneBuffers, spec: Specialisation) -> Image {
    render_f32_progress(buf, spec, &|_, _| {})
}

/// [`render_f32`] written over `image`, whose pixel buffer is kept when it has the frame's
/// size (else it is replaced): the same pixels, bit for bit, whatever `image` held. A
/// sequence of frames (an animation, an interactive view, a benchmark's timed runs) then
/// maps and zeroes its 16 bytes a pixel once, not every frame: for a frame without
/// primitives at 1024×768 that was about a third of the frame's time on this project's
/// dev box (docs/bench/ab.md).
pub fn render_f32_into(buf: &SceneBuffers, spec: Specialisation, image: &mut Image) {
    let g = packet_globals(buf, spec);
    image.reshape(g.cam.width, g.cam.height);
    packet_rows_into(&g, packet::Simd::Best, 0, &|_, _| {}, &mut image.pixels);
}

/// [`render_f32`], reporting rows done to `progress`.
pub fn render_f32_progress(
    buf: &SceneBuffers,
    spec: Specialisation,
    progress: &Progress<'_>,
) -> Image {
    let g = packet_globals(buf, spec);
    render_packets(&g, packet::Simd::Best, progress)
}

/// [`render_f32`] with the packet tracer's build `simd` (the AVX2 or the baseline build on
/// a CPU with AVX-512, say), for tests: every build gives the same image. `spec.use_bvh`
/// is taken as given (not raised by [`PACKET_BRUTE_FORCE_MAX`]), so that tests reach the
/// packet tracer's search over every primitive on scenes of any size.
pub fn render_f32_simd(buf: &SceneBuffers, spec: Specialisation, simd: packet::Simd) -> Image {
    if spec.use_bvh || spec.instances {
        buf.leaf_triangles(); // as in `packet_globals`
    }
    let g = globals_f32(buf, spec);
    render_packets(&g, simd, &|_, _| {})
}

/// Renders with the f32 mirror of `trace.wgsl` itself, one `trace_pixel` per pixel: the
/// slower twin that [`render_f32`] is checked against.
pub fn render_f32_mirror(buf: &SceneBuffers, spec: Specialisation) -> Image {
    let g = globals_f32(buf, spec);
    render_with(&g, &|_, _| {})
}

/// Renders the f64 ground truth: the same algorithms with the camera basis, every
/// intersection and the shading in f64 (inputs widened exactly from the f32 scene).
pub fn render_f64(scene: &Scene, buf: &SceneBuffers, spec: Specialisation) -> Image {
    render_with(&globals_f64(scene, buf, spec), &|_, _| {})
}

/// The f64 camera and scene: the basis and `tan` computed in f64 from the file's values.
fn globals_f64<'a>(scene: &Scene, buf: &'a SceneBuffers, spec: Specialisation) -> Globals<'a, f64> {
    let c = &scene.camera;
    let [forward, right, up] = camera_basis::<f64>(
        V3::from_f32(c.eye),
        V3::from_f32(c.look_at),
        V3::from_f32(c.up),
    );
    let (w, h) = (buf.params.width, buf.params.height);
    let cam = Camera {
        eye: V3::from_f32(c.eye),
        forward,
        right,
        up,
        tan_half: ((c.fov as f64).to_radians() / 2.0).tan(),
        aspect: w as f64 / h as f64,
        width: w,
        height: h,
        samples: buf.params.samples,
    };
    Globals {
        cam,
        buf,
        spec,
        count: NoCount,
    }
}

/// Rows `y0 .. y0 + rows` of the frame's AOVs (row-major): WGSL `render_aov`'s records.
/// In f32 the centre rays go in packets (`packet::aov_tracer`, the same records as the
/// mirror's `aov_pixel` in every bit: [`render_aov_rows_mirror`] is the twin); the f64
/// ground truth's where `f64_scene` is given (its values rounded to f32 at the end).
pub fn render_aov_rows(
    f64_scene: Option<&Scene>,
    buf: &SceneBuffers,
    spec: Specialisation,
    y0: u32,
    rows: u32,
) -> Vec<AovOut> {
    if let Some(s) = f64_scene {
        return aov_rows_with(&globals_f64(s, buf, spec), y0, rows);
    }
    let g = packet_globals(buf, spec);
    let trace = packet::aov_tracer(packet::Simd::Best, g.spec.instances);
    let w = g.cam.width as usize;
    let (pw, ph) = (packet::PACKET_W as usize, packet::PACKET_H as usize);
    let mut out: Vec<AovOut> = bytemuck::zeroed_vec(w * rows as usize);
    out.par_chunks_mut((w * ph).max(1))
        .enumerate()
        .for_each(|(b, band)| {
            let j = y0 + (b * ph) as u32;
            let n = band.len() / w.max(1);
            for i in (0..w).step_by(pw) {
                let px = trace(&g, i as u32, j);
                let cols = pw.min(w - i);
                for (y, lanes) in px.chunks_exact(pw).take(n).enumerate() {
                    band[y * w + i..y * w + i + cols].copy_from_slice(&lanes[..cols]);
                }
            }
        });
    out
}

/// Where the CPU tracer puts a band's AOV records: a block of whole rows that one thread
/// writes, [`packet::PACKET_H`] rows of it at a time (`render_f32_rows_aov`'s blocks).
/// What it keeps of a record (the AOVs asked for, as planes) is its own choice.
pub trait RecordRows: Send {
    /// Takes `records`, the pixels `x ..` of row `row` of the block (0 its first row).
    fn put(&mut self, row: usize, x: usize, records: &[AovOut]);

    /// Takes a packet's records: pixels `x .. x + cols` of the block's rows `0 .. rows`,
    /// pixel (x + dx, dy) in lane `dy * PACKET_W + dx` of `lanes`. By default each row
    /// through [`RecordRows::put`].
    fn put_lanes(&mut self, x: usize, rows: usize, cols: usize, lanes: &packet::AovLanes) {
        const PW: usize = packet::PACKET_W as usize;
        for y in 0..rows {
            let row: [AovOut; PW] = std::array::from_fn(|c| lanes.record(y * PW + c));
            self.put(y, x, &row[..cols]);
        }
    }
}

/// Rows `y0 .. y0 + rows` of [`render_f32_rows`]'s colours, returned, and of
/// [`render_aov_rows`]'s records, given to `blocks` (block `b` takes rows
/// `y0 + b·PACKET_H ..`, [`packet::PACKET_H`] rows, fewer in the last), each the same in
/// every bit as from its own pass. Where the packets shade the scene themselves (no
/// antialiasing, textures or directional and spot lights), the camera rays are traced
/// once for both ([`packet::colour_aov_tracer`]); elsewhere the two passes run one after
/// the other.
pub fn render_f32_rows_aov<S: RecordRows>(
    buf: &SceneBuffers,
    spec: Specialisation,
    y0: u32,
    rows: u32,
    blocks: Vec<S>,
) -> Vec<[f32; 4]> {
    let w = buf.params.width as usize;
    let ph = packet::PACKET_H as usize;
    debug_assert_eq!(blocks.len(), (rows as usize).div_ceil(ph));
    if spec.antialias || spec.textures || spec.light_kinds {
        let records = render_aov_rows(None, buf, spec, y0, rows);
        for (b, mut block) in blocks.into_iter().enumerate() {
            for (r, row) in records[b * ph * w..].chunks(w.max(1)).take(ph).enumerate() {
                block.put(r, 0, row);
            }
        }
        return render_f32_rows(buf, spec, y0, rows);
    }
    let g = packet_globals(buf, spec);
    let trace = packet::colour_aov_tracer(packet::Simd::Best, g.spec.instances);
    const PW: usize = packet::PACKET_W as usize;
    let mut colours = vec![[0.0f32; 4]; w * rows as usize];
    colours
        .par_chunks_mut((w * ph).max(1))
        .zip(blocks.into_par_iter())
        .enumerate()
        .for_each(|(b, (colour_band, mut block))| {
            let j = y0 + (b * ph) as u32;
            let n = colour_band.len() / w.max(1);
            for i in (0..w).step_by(PW) {
                let (px, rec) = trace(&g, i as u32, j);
                let cols = PW.min(w - i);
                for y in 0..n {
                    let (at, lane) = (y * w + i, y * PW);
                    if cols == PW {
                        // A copy of a length known here: a move, not a `memmove` call.
                        colour_band[at..at + PW].copy_from_slice(&px[lane..lane + PW]);
                    } else {
                        colour_band[at..at + cols].copy_from_slice(&px[lane..lane + cols]);
                    }
                }
                block.put_lanes(i, n, cols, &rec);
            }
        });
    colours
}

/// [`render_aov_rows`] in f32 with the mirror's own `aov_pixel`, one pixel at a time: the
/// slower twin that the packets are checked against.
pub fn render_aov_rows_mirror(
    buf: &SceneBuffers,
    spec: Specialisation,
    y0: u32,
    rows: u32,
) -> Vec<AovOut> {
    aov_rows_with(&globals_f32(buf, spec), y0, rows)
}

/// `aov_pixel` of every pixel of rows `y0 .. y0 + rows`, rows in parallel.
fn aov_rows_with<R: Real>(g: &Globals<R>, y0: u32, rows: u32) -> Vec<AovOut> {
    let w = g.cam.width as usize;
    let mut out: Vec<AovOut> = bytemuck::zeroed_vec(w * rows as usize);
    out.par_chunks_mut(w.max(1))
        .enumerate()
        .for_each(|(r, row)| {
            let j = y0 + r as u32;
            for (i, px) in row.iter_mut().enumerate() {
                *px = aov::aov_pixel(g, i as u32, j);
            }
        });
    out
}

/// The `query` entry point on the CPU, in f32 (the shader's twin) over many rays.
pub fn query_f32(buf: &SceneBuffers, spec: Specialisation, rays: &[RayIn]) -> Vec<HitOut> {
    let g = globals_f32(buf, spec);
    rays.par_iter().map(|r| trace::query(&g, r)).collect()
}

/// The secondary rays that leave the first hit of the ray from `origin` along `dir`, as
/// the f32 mirror's `push_children` makes them for a primary hit (the transmitted ray
/// first): each one's origin and direction. Empty on a miss, where the material neither
/// reflects nor transmits, or where `min_weight` cuts both. For tests of ray spawning.
pub fn secondary_rays_f32(
    buf: &SceneBuffers,
    spec: Specialisation,
    origin: [f32; 3],
    dir: [f32; 3],
) -> Vec<([f32; 3], [f32; 3])> {
    let g = globals_f32(buf, spec);
    let ray = trace::Ray {
        origin: V3::from_f32(origin),
        dir: V3::from_f32(dir),
    };
    let hit = trace::closest_hit(&g, ray, 0.0, f32::INFINITY);
    if hit.prim == crate::buffers::PRIM_NONE {
        return Vec::new();
    }
    let zero = whitted::Pending {
        origin: V3::splat(0.0),
        depth: 0,
        dir: V3::splat(0.0),
        weight: V3::splat(0.0),
    };
    let mut stack = [zero; whitted::WHITTED_STACK];
    let n = whitted::push_children(&g, &mut stack, 0, ray, &hit, V3::splat(1.0), 0);
    stack[..n]
        .iter()
        .map(|p| (p.origin.to_f32(), p.dir.to_f32()))
        .collect()
}
