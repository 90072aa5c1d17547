//! `glint bench`: speed against error for each scene × tracer × triangle algorithm, and
//! the specialised pipeline beside the general one. Release builds only mean anything.

use std::time::Duration;
use web_time::Instant;

use serde::Serialize;

use crate::buffers::{SceneBuffers, Specialisation};
use crate::compare::diff;
use crate::gpu::{Gpu, GpuOptions, GpuTimings, Kernel};
use crate::image::Image;
use crate::render::{Backend, RenderError, TracerKind};
use crate::scene::{Scene, TriangleAlgorithm};

/// The five seed scenes (`scenes/*.toml` of the original assignment) as shipped in the
/// library, by name: what `glint bench` measures when given no scene. They read no file.
pub const SEED_SCENES: [(&str, &str); 5] = [
    ("sphere", include_str!("../scenes/sphere.toml")),
    ("triangle", include_str!("../scenes/triangle.toml")),
    ("umbrella", include_str!("../scenes/umbrella.toml")),
    ("bb8", include_str!("../scenes/bb8.toml")),
    ("mitsubishi", include_str!("../scenes/mitsubishi.toml")),
];

/// One measured configuration.
#[derive(Clone, Debug, Serialize)]
pub struct Row {
    /// Scene name.
    pub scene: String,
    /// The tracer (in JSON: `gpu`, `gpu-general`, `gpu-rq`, `cpu-f32` or `cpu-f64`).
    pub tracer: TracerKind,
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

/// What to measure.
#[derive(Clone, Debug)]
pub struct Options {
    /// Image size (default: each scene camera's).
    pub size: Option<(u32, u32)>,
    /// Only this triangle algorithm (default: all three where a scene has triangles).
    pub triangle: Option<TriangleAlgorithm>,
    /// Timed runs per configuration, after one warm-up (at least 1).
    pub runs: usize,
    /// The tracers: [`Backend::Gpu`] gives the specialised shader and the general one
    /// beside it, [`Backend::GpuRq`] the ray-query shader where the device has ray queries
    /// (skipped where not), [`Backend::Cpu`] the f32 mirror, [`Backend::CpuF64`] the ground
    /// truth (which every row's error is measured against, whether or not it is listed).
    /// [`Backend::Auto`] is taken as `Gpu`.
    pub backends: Vec<Backend>,
    /// The device, for the GPU rows.
    pub gpu: GpuOptions,
    /// The GPU kernel's division and square root.
    pub math: crate::buffers::Math,
}

impl Default for Options {
    /// Every tracer, each scene's size, all algorithms, 5 runs, the best adapter.
    fn default() -> Options {
        Options {
            size: None,
            triangle: None,
            runs: 5,
            backends: vec![Backend::Gpu, Backend::GpuRq, Backend::Cpu, Backend::CpuF64],
            gpu: GpuOptions::default(),
            math: crate::buffers::Math::Exact,
        }
    }
}

impl Options {
    fn wants(&self, b: Backend) -> bool {
        self.backends
            .iter()
            .any(|&x| x == b || (b == Backend::Gpu && x == Backend::Auto))
    }
}

fn ms(d: Duration) -> f64 {
    d.as_secs_f64() * 1e3
}

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

/// The configurations of `scenes`: each scene with each algorithm asked for.
fn configs(
    scenes: &[(String, Scene)],
    only: Option<TriangleAlgorithm>,
) -> Vec<(usize, TriangleAlgorithm)> {
    scenes
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
        .collect()
}

/// Runs the benchmark on `scenes` (name, scene) as `options` say, calling
/// `progress(done, total, label)` as it goes. The device is started here when a GPU
/// tracer is asked for.
pub fn run(
    scenes: &[(String, Scene)],
    options: &Options,
    progress: &mut dyn FnMut(usize, usize, &str),
) -> Result<Report, RenderError> {
    let gpu = if options.wants(Backend::Gpu) || options.wants(Backend::GpuRq) {
        Some(Gpu::with_options(&options.gpu)?)
    } else {
        None
    };
    let runs = options.runs.max(1);
    let mut rows = Vec::new();
    let configs = configs(scenes, options.triangle);
    let total = configs.len();
    for (done, (k, algo)) in configs.into_iter().enumerate() {
        let (name, scene) = &scenes[k];
        progress(done, total, &format!("{name} {algo}"));
        let (w, h) = options.size.unwrap_or(scene.size());
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
        let spec = Specialisation::for_scene(&buf).with_math(crate::buffers::MathMode {
            math: options.math,
            inexact_driver: false,
        });
        let truth = crate::cpu::render_f64(scene, &buf, spec);
        let mirror = crate::cpu::render_f32(&buf, spec);
        let mut rower = Rower {
            scene: name,
            algo,
            buf: &buf,
            build_ms,
            truth: &truth,
            mirror: &mirror,
            rows: &mut rows,
        };
        if let Some(gpu) = &gpu {
            gpu_rows(gpu, options, &buf, spec, runs, &mut rower)?;
        }
        if options.wants(Backend::Cpu) {
            // The packet tracer draws into the warm-up's image at every timed run, as a
            // sequence of frames would (and as Mitsuba's frames reuse their memory through
            // Dr.Jit's allocator cache): the frame, not the mapping of fresh memory.
            let mut img = mirror.clone();
            let mut t = Vec::new();
            for _ in 0..runs {
                let t0 = Instant::now();
                crate::cpu::render_f32_into(&buf, spec, &mut img);
                t.push(ms(t0.elapsed()));
            }
            rower.row(TracerKind::CpuF32, None, t, &img, None, None);
        }
        if options.wants(Backend::CpuF64) {
            let mut img = truth.clone();
            let mut t = Vec::new();
            for _ in 0..runs {
                let t0 = Instant::now();
                img = crate::cpu::render_f64(scene, &buf, spec);
                t.push(ms(t0.elapsed()));
            }
            rower.row(TracerKind::CpuF64, None, t, &img, None, None);
        }
    }
    progress(total, total, "done");
    Ok(Report {
        adapter: gpu
            .as_ref()
            .map(|g| g.describe())
            .unwrap_or_else(|| "none".into()),
        device_start_ms: gpu.as_ref().map(|g| ms(g.start_time)),
        cpu_threads: rayon::current_num_threads(),
        cpu_simd: crate::cpu::packet::Simd::Best.name().into(),
        runs,
        rows,
    })
}

/// Makes the rows of one configuration: its errors against the f64 image, and for the GPU
/// whether it equals the f32 mirror's.
struct Rower<'r> {
    scene: &'r str,
    algo: TriangleAlgorithm,
    buf: &'r SceneBuffers,
    build_ms: f64,
    truth: &'r Image,
    mirror: &'r Image,
    rows: &'r mut Vec<Row>,
}

impl Rower<'_> {
    /// A row of `tracer` with the frame `times` (ms) and its last image; `gpu_parts` the
    /// GPU's compile, upload, trace and readback (ms).
    fn row(
        &mut self,
        tracer: TracerKind,
        traversal: Option<&str>,
        times: Vec<f64>,
        img: &Image,
        gpu_parts: Option<[f64; 4]>,
        accel_ms: Option<f64>,
    ) {
        let (w, h) = (self.buf.params.width, self.buf.params.height);
        let d = diff(img, self.truth);
        let equals_cpu_f32 = gpu_parts.map(|_| diff(img, self.mirror).bit_exact());
        let med = median(times.clone());
        self.rows.push(Row {
            scene: self.scene.to_string(),
            tracer,
            traversal: traversal.map(Into::into),
            triangle: self.algo.name().into(),
            size: (w, h),
            primitives: self.buf.spheres.len() + self.buf.triangles.len(),
            build_ms: self.build_ms,
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
    }
}

/// The GPU rows of one configuration: the specialised and the general shader, and the
/// ray-query shader where the device has ray queries, each as `options` ask.
fn gpu_rows(
    gpu: &Gpu,
    options: &Options,
    buf: &SceneBuffers,
    spec: Specialisation,
    runs: usize,
    rower: &mut Rower<'_>,
) -> Result<(), RenderError> {
    let mut tracers: Vec<(TracerKind, &Kernel, Specialisation)> = Vec::new();
    if options.wants(Backend::Gpu) {
        let general = Specialisation::general(buf).with_math(spec.math);
        tracers.push((TracerKind::Gpu, gpu.compute_kernel(spec)?, spec));
        tracers.push((
            TracerKind::GpuGeneral,
            gpu.compute_kernel(general)?,
            general,
        ));
    }
    if options.wants(Backend::GpuRq) && gpu.has_ray_query() {
        tracers.push((TracerKind::GpuRq, gpu.ray_query_kernel()?, spec));
    }
    for (tracer, kernel, sp) in tracers {
        kernel.clear_cache();
        let compile = kernel.prepare(&gpu.device, sp)?;
        let mut parts = Vec::new();
        // Every run reads back into the warm-up's image, as the CPU rows draw into
        // theirs: the frame, not the mapping of fresh memory.
        let (mut img, _) = kernel.render(&gpu.device, &gpu.queue, buf, sp, &mut |_, _| {})?;
        for _ in 0..runs {
            let t =
                kernel.render_into(&gpu.device, &gpu.queue, buf, sp, &mut img, &mut |_, _| {})?;
            parts.push(t);
        }
        let times: Vec<f64> = parts.iter().map(|t| ms(t.trace + t.readback)).collect();
        let med =
            |f: &dyn Fn(&GpuTimings) -> Duration| median(parts.iter().map(|t| ms(f(t))).collect());
        let p = [
            ms(compile),
            med(&|t| t.upload),
            med(&|t| t.trace),
            med(&|t| t.readback),
        ];
        let accel = kernel.is_ray_query().then(|| med(&|t| t.accel));
        let traversal = (!kernel.is_ray_query()).then(|| kernel.traversal_name());
        rower.row(tracer, traversal, times, &img, Some(p), accel);
    }
    Ok(())
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
                    None => r.tracer.to_string(),
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
            let c = match r.tracer {
                TracerKind::Gpu => [220, 30, 30],
                TracerKind::GpuGeneral => [240, 150, 20],
                TracerKind::GpuRq => [150, 40, 200],
                TracerKind::CpuF32 => [30, 60, 220],
                TracerKind::CpuF64 => [30, 160, 60],
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
                    if dx * dx + dy * dy <= 16 || r.tracer == TracerKind::GpuRq {
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
