//! `glint bench`: speed against error for each scene × tracer × triangle algorithm, and
//! the specialised pipeline beside the general one. Release builds only mean anything.

use std::time::{Duration, Instant};

use serde::Serialize;

use crate::buffers::{SceneBuffers, Specialisation};
use crate::compare::diff;
use crate::gpu::Gpu;
use crate::image::Image;
use crate::scene::{Scene, TriangleAlgorithm};

/// One measured configuration.
#[derive(Clone, Debug, Serialize)]
pub struct Row {
    /// Scene name.
    pub scene: String,
    /// `gpu`, `gpu-general`, `gpu-rq` (the ray-query tracer), `cpu-f32` or `cpu-f64`.
    pub tracer: String,
    /// GPU rows: the BVH traversal, `packet` (one packet per subgroup) or `per-ray`; `None`
    /// for the ray-query and CPU rows.
    pub traversal: Option<String>,
    /// Triangle algorithm.
    pub triangle: String,
    /// Width × height.
    pub size: (u32, u32),
    /// Spheres + triangles.
    pub primitives: usize,
    /// BVH build (median of the runs), ms.
    pub build_ms: f64,
    /// Median frame time (trace + readback on the GPU), ms.
    pub median_ms: f64,
    /// Fastest frame, ms.
    pub min_ms: f64,
    /// Slowest frame, ms.
    pub max_ms: f64,
    /// Primary rays per second at the median.
    pub rays_per_s: f64,
    /// GPU: pipeline compile, ms (first use of the specialisation).
    pub compile_ms: Option<f64>,
    /// GPU: buffer creation and upload, ms (median).
    pub upload_ms: Option<f64>,
    /// GPU: dispatch until done, ms (median).
    pub trace_ms: Option<f64>,
    /// GPU: copy and map back, ms (median).
    pub readback_ms: Option<f64>,
    /// Ray-query tracer: the driver's acceleration-structure build, ms (median; not in the
    /// frame time, as the BVH build is not).
    pub accel_ms: Option<f64>,
    /// Largest channel difference to the f64 image.
    pub max_err: f64,
    /// RMS channel difference to the f64 image.
    pub rms_err: f64,
    /// Pixels off by ≥ 1/255 in some channel.
    pub pixels_off: usize,
    /// Hit/miss disagreements with the f64 image.
    pub hit_miss: usize,
    /// GPU rows: whether the image equals the CPU f32 mirror's in every bit (colour,
    /// hit/miss and t); `None` for the CPU rows.
    pub equals_cpu_f32: Option<bool>,
}

/// The whole report.
#[derive(Clone, Debug, Serialize)]
pub struct Report {
    /// The GPU adapter, or why there was none.
    pub adapter: String,
    /// Device start (adapter + device creation), ms.
    pub device_start_ms: Option<f64>,
    /// CPU threads used by the CPU tracers.
    pub cpu_threads: usize,
    /// The packet tracer's build that ran (`avx512`, `avx2` or `baseline`).
    pub cpu_simd: String,
    /// Timed runs per configuration (after one warm-up).
    pub runs: usize,
    /// The rows.
    pub rows: Vec<Row>,
}

fn ms(d: Duration) -> f64 {
    d.as_secs_f64() * 1e3
}

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

/// Runs the benchmark on `scenes` (name, scene) at `size` with `runs` timed runs each,
/// calling `progress(done, total, label)` as it goes.
pub fn run(
    scenes: &[(String, Scene)],
    size: Option<(u32, u32)>,
    only: Option<TriangleAlgorithm>,
    runs: usize,
    gpu: Option<&Gpu>,
    progress: &mut dyn FnMut(usize, usize, &str),
) -> Result<Report, crate::gpu::GpuError> {
    let runs = runs.max(1);
    let mut rows = Vec::new();
    let configs: Vec<(usize, TriangleAlgorithm)> = scenes
        .iter()
        .enumerate()
        .flat_map(|(k, (_, s))| {
            let algos: Vec<TriangleAlgorithm> = if let Some(a) = only {
                vec![a]
            } else if s.triangles.is_empty() {
                vec![s.triangle]
            } else {
                TriangleAlgorithm::ALL.to_vec()
            };
            algos.into_iter().map(move |a| (k, a))
        })
        .collect();
    let total = configs.len();
    for (done, (k, algo)) in configs.into_iter().enumerate() {
        let (name, scene) = &scenes[k];
        progress(done, total, &format!("{name} {algo}"));
        let (w, h) = size.unwrap_or(scene.size());
        let buf = SceneBuffers::new(scene, w, h, algo);
        let build_ms = median(
            (0..runs)
                .map(|_| {
                    let t0 = Instant::now();
                    std::hint::black_box(crate::bvh::Bvh::build(&buf.spheres, &buf.triangles));
                    ms(t0.elapsed())
                })
                .collect(),
        );
        let primitives = buf.spheres.len() + buf.triangles.len();
        let spec = Specialisation::for_scene(&buf);
        let truth = crate::cpu::render_f64(scene, &buf, spec);
        let mirror = crate::cpu::render_f32(&buf, spec);
        let mut row = |tracer: &str,
                       traversal: Option<&str>,
                       times: Vec<f64>,
                       img: &Image,
                       gpu_parts: Option<[f64; 4]>,
                       accel_ms: Option<f64>| {
            let d = diff(img, &truth);
            let equals_cpu_f32 = gpu_parts.map(|_| diff(img, &mirror).bit_exact());
            let med = median(times.clone());
            rows.push(Row {
                scene: name.clone(),
                tracer: tracer.into(),
                traversal: traversal.map(Into::into),
                triangle: algo.name().into(),
                size: (w, h),
                primitives,
                build_ms,
                median_ms: med,
                min_ms: times.iter().copied().fold(f64::INFINITY, f64::min),
                max_ms: times.iter().copied().fold(0.0, f64::max),
                rays_per_s: (w as f64 * h as f64) / (med / 1e3),
                compile_ms: gpu_parts.map(|p| p[0]),
                upload_ms: gpu_parts.map(|p| p[1]),
                trace_ms: gpu_parts.map(|p| p[2]),
                readback_ms: gpu_parts.map(|p| p[3]),
                accel_ms,
                max_err: d.max_abs,
                rms_err: d.rms,
                pixels_off: d.differing_pixels,
                hit_miss: d.hit_miss,
                equals_cpu_f32,
            });
        };
        if let Some(gpu) = gpu {
            let mut tracers = vec![
                ("gpu", gpu.compute_kernel(spec)?, spec),
                (
                    "gpu-general",
                    gpu.compute_kernel(Specialisation::general(&buf))?,
                    Specialisation::general(&buf),
                ),
            ];
            if gpu.has_ray_query() {
                let rq = gpu.ray_query_kernel()?;
                tracers.push(("gpu-rq", rq, spec));
            }
            for (tracer, kernel, sp) in tracers {
                kernel.clear_cache();
                let compile = kernel.prepare(&gpu.device, sp)?;
                let mut parts = Vec::new();
                // Every run reads back into the warm-up's image, as the CPU rows draw
                // into theirs: the frame, not the mapping of fresh memory.
                let (i, _) = kernel.render(&gpu.device, &gpu.queue, &buf, sp, &mut |_, _| {})?;
                let mut img = Some(i);
                for _ in 0..runs {
                    let image = img.as_mut().expect("rendered");
                    let t = kernel.render_into(
                        &gpu.device,
                        &gpu.queue,
                        &buf,
                        sp,
                        image,
                        &mut |_, _| {},
                    )?;
                    parts.push(t);
                }
                let times: Vec<f64> = parts.iter().map(|t| ms(t.trace + t.readback)).collect();
                let med = |f: &dyn Fn(&crate::gpu::GpuTimings) -> Duration| {
                    median(parts.iter().map(|t| ms(f(t))).collect())
                };
                let p = [
                    ms(compile),
                    med(&|t| t.upload),
                    med(&|t| t.trace),
                    med(&|t| t.readback),
                ];
                let accel = kernel.is_ray_query().then(|| med(&|t| t.accel));
                let traversal = (!kernel.is_ray_query()).then(|| kernel.traversal_name());
                row(
                    tracer,
                    traversal,
                    times,
                    img.as_ref().expect("rendered"),
                    Some(p),
                    accel,
                );
            }
        }
        let timed = |f: &dyn Fn() -> Image| {
            let mut img = f();
            let mut times = Vec::new();
            for _ in 0..runs {
                let t0 = Instant::now();
                img = f();
                times.push(ms(t0.elapsed()));
            }
            (times, img)
        };
        // The packet tracer draws into the warm-up's image at every timed run, as a
        // sequence of frames would (and as Mitsuba's frames reuse their memory through
        // Dr.Jit's allocator cache): the frame, not the mapping of fresh memory.
        let mut img = crate::cpu::render_f32(&buf, spec);
        let mut t = Vec::new();
        for _ in 0..runs {
            let t0 = Instant::now();
            crate::cpu::render_f32_into(&buf, spec, &mut img);
            t.push(ms(t0.elapsed()));
        }
        row("cpu-f32", None, t, &img, None, None);
        let (t, img) = timed(&|| crate::cpu::render_f64(scene, &buf, spec));
        row("cpu-f64", None, t, &img, None, None);
    }
    progress(total, total, "done");
    Ok(Report {
        adapter: gpu.map(|g| g.describe()).unwrap_or_else(|| "none".into()),
        device_start_ms: gpu.map(|g| ms(g.start_time)),
        cpu_threads: rayon::current_num_threads(),
        cpu_simd: crate::cpu::packet::Simd::Best.name().into(),
        runs,
        rows,
    })
}

impl Report {
    /// The report as a markdown table.
    pub fn markdown(&self) -> String {
        let mut s = format!(
            "Adapter: {}; device start {}; CPU tracers on {} threads ({} build); median of {} runs after a warm-up.\n\n",
            self.adapter,
            self.device_start_ms
                .map(|m| format!("{m:.0} ms"))
                .unwrap_or_else(|| "n/a".into()),
            self.cpu_threads,
            self.cpu_simd,
            self.runs
        );
        s += "| scene | tracer | triangles | primitives | BVH build ms | size | median ms (min–max) | Mrays/s | compile ms | upload ms | AS build ms | trace ms | readback ms | max err | RMS err | px ≥1/255 | hit/miss | = CPU f32 |\n";
        s += "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|\n";
        let o = |x: Option<f64>| x.map(|v| format!("{v:.1}")).unwrap_or_else(|| "–".into());
        for r in &self.rows {
            s += &format!(
                "| {} | {} | {} | {} | {:.1} | {}×{} | {:.1} ({:.1}–{:.1}) | {:.2} | {} | {} | {} | {} | {} | {:.2e} | {:.2e} | {} | {} | {} |\n",
                r.scene,
                match &r.traversal {
                    Some(t) => format!("{} ({t})", r.tracer),
                    None => r.tracer.clone(),
                },
                r.triangle,
                r.primitives,
                r.build_ms,
                r.size.0,
                r.size.1,
                r.median_ms,
                r.min_ms,
                r.max_ms,
                r.rays_per_s / 1e6,
                o(r.compile_ms),
                o(r.upload_ms),
                o(r.accel_ms),
                o(r.trace_ms),
                o(r.readback_ms),
                r.max_err,
                r.rms_err,
                r.pixels_off,
                r.hit_miss,
                match r.equals_cpu_f32 {
                    Some(true) => "every bit",
                    Some(false) => "**no**",
                    None => "–",
                }
            );
        }
        s
    }

    /// A scatter plot of speed (x: rays/s, log) against error (y: max channel error, log;
    /// exact f64 rows sit on the bottom edge). Colours: GPU red, general GPU orange,
    /// ray-query GPU purple (a square: its error is the driver's triangle test), CPU f32
    /// blue, CPU f64 green. Grid lines at every decade.
    pub fn plot(&self) -> image::RgbImage {
        let (w, h, m) = (800u32, 500u32, 40u32);
        let mut img = image::RgbImage::from_pixel(w, h, image::Rgb([255, 255, 255]));
        let (x0, x1) = (4.0f64, 9.0f64); // 1e4 .. 1e9 rays/s
        let (y0, y1) = (-12.0f64, -1.0f64); // 1e-12 .. 1e-1
        let px = |lx: f64| m as f64 + (lx - x0) / (x1 - x0) * (w - 2 * m) as f64;
        let py = |ly: f64| (h - m) as f64 - (ly - y0) / (y1 - y0) * (h - 2 * m) as f64;
        for d in x0 as i32..=x1 as i32 {
            let x = px(d as f64) as u32;
            for y in m..h - m {
                img.put_pixel(x.min(w - 1), y, image::Rgb([220, 220, 220]));
            }
        }
        for d in y0 as i32..=y1 as i32 {
            let y = py(d as f64) as u32;
            for x in m..w - m {
                img.put_pixel(x, y.min(h - 1), image::Rgb([220, 220, 220]));
            }
        }
        for r in &self.rows {
            let c = match r.tracer.as_str() {
                "gpu" => [220, 30, 30],
                "gpu-general" => [240, 150, 20],
                "gpu-rq" => [150, 40, 200],
                "cpu-f32" => [30, 60, 220],
                _ => [30, 160, 60],
            };
            let lx = r.rays_per_s.max(1.0).log10().clamp(x0, x1);
            let ly = if r.max_err > 0.0 {
                r.max_err.log10().clamp(y0, y1)
            } else {
                y0
            };
            let (cx, cy) = (px(lx) as i64, py(ly) as i64);
            for dy in -4i64..=4 {
                for dx in -4i64..=4 {
                    if dx * dx + dy * dy <= 16 || r.tracer == "gpu-rq" {
                        let (x, y) = (cx + dx, cy + dy);
                        if x >= 0 && y >= 0 && (x as u32) < w && (y as u32) < h {
                            img.put_pixel(x as u32, y as u32, image::Rgb(c));
                        }
                    }
                }
            }
        }
        img
    }
}
