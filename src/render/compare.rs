//! [`compare()`]: `glint compare`'s procedure. The GPU's image against its CPU mirror (equal
//! in every bit where the driver computes as the mirror does), both against the f64 ground
//! truth, and the ray-query tracer against f64 where the device has one.

use std::fmt;
use std::path::PathBuf;
use std::time::Duration;

use super::aov::{Aov, AovImage, IdMap};
use super::job::Warning;
use super::renderer::{RenderError, RenderOptions};
use crate::buffers::{SceneBuffers, Specialisation};
use crate::compare::{Diff, diff, diff_image};
use crate::gpu::{Gpu, GpuError};
use crate::image::Image;
use crate::scene::{Scene, TriangleAlgorithm};

/// The ray-query tracer's part of a [`CompareReport`].
#[derive(Debug)]
pub enum RayQueryResult {
    /// Measured against f64 (its hits are the driver's, so it is not asserted equal).
    Measured {
        /// Its image against the f64 image.
        vs_f64: Diff,
        /// The driver's acceleration-structure build.
        accel: Duration,
        /// The trace.
        trace: Duration,
    },
    /// The device has no ray queries, or its kernel failed.
    NotMeasured(GpuError),
}

/// What [`compare()`] measured.
#[derive(Debug)]
pub struct CompareReport {
    /// The scene's file.
    pub scene: PathBuf,
    /// The frame's width.
    pub width: u32,
    /// The frame's height.
    pub height: u32,
    /// The triangle algorithm.
    pub algorithm: TriangleAlgorithm,
    /// The adapter and driver.
    pub adapter: String,
    /// The GPU's BVH traversal.
    pub traversal: &'static str,
    /// Whether the GPU's arithmetic is the mirror's by construction, in words.
    pub exactness: String,
    /// The scene's and the range's warnings.
    pub warnings: Vec<Warning>,
    /// The GPU's image against the f32 CPU mirror's.
    pub gpu_vs_cpu: Diff,
    /// The f32 CPU image against the f64 one.
    pub cpu_vs_f64: Diff,
    /// The GPU's image against the f64 one.
    pub gpu_vs_f64: Diff,
    /// The ray-query tracer.
    pub ray_query: RayQueryResult,
    /// Where the GPU's and the mirror's images differ ([`crate::compare::diff_image`]).
    pub difference: Image,
    /// Each AOV that [`RenderOptions::aovs`] named: the GPU's against the mirror's.
    pub aovs: Vec<(Aov, AovDiff)>,
}

/// One AOV of the GPU's frame against the mirror's, bit for bit.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct AovDiff {
    /// Pixels where some bit of the AOV differs.
    pub differing: usize,
    /// The first such pixel, (x, y).
    pub first: Option<(u32, u32)>,
}

/// Where `aov` of `a` and of `b` (frames of `width` pixels a row) differ in some bit; a
/// frame that does not hold `aov`, or holds fewer pixels, differs at every pixel it lacks.
pub fn diff_aov(aov: Aov, a: &AovImage, b: &AovImage) -> AovDiff {
    let pixels = |f: &AovImage| f.width as usize * f.height as usize;
    let (na, nb) = (pixels(a), pixels(b));
    let components = aov.channel_names().len();
    let mut out = AovDiff::default();
    for k in 0..na.max(nb) {
        let same = k < na.min(nb)
            && (0..components).all(|c| match (a.bits(aov, c, k), b.bits(aov, c, k)) {
                (Some(x), Some(y)) => x == y,
                _ => false,
            });
        if !same {
            out.differing += 1;
            if out.first.is_none() {
                out.first = Some((k as u32 % a.width.max(1), k as u32 / a.width.max(1)));
            }
        }
    }
    out
}

/// Renders `scene` with `options` on `gpu`'s shader, on the f32 CPU mirror and in f64, and
/// measures the differences. It holds three whole frames and a difference image, and checks
/// first that they fit in memory.
pub fn compare(
    scene: &Scene,
    options: &RenderOptions,
    gpu: &Gpu,
) -> Result<CompareReport, RenderError> {
    scene.validate()?;
    let (w, h) = options.checked_size(scene)?;
    let algo = options.triangle.unwrap_or(scene.triangle);
    let mut warnings: Vec<Warning> = scene.warnings.iter().cloned().map(Warning::Scene).collect();
    warnings.extend(scene.range_warnings(algo).into_iter().map(Warning::Range));
    let aov_bytes = if options.aovs.is_empty() {
        0
    } else {
        2 * 64 + 8
    };
    super::check_memory(w, h, w as u64 * h as u64 * (16 * 4 + aov_bytes))?;
    let mut buf = SceneBuffers::new(scene, w, h, algo);
    options.apply(&mut buf);
    let spec = Specialisation::for_scene(&buf).with_math(options.math_mode());
    let kernel = gpu.compute_kernel(spec)?;
    let (g, _) = kernel.render(&gpu.device, &gpu.queue, &buf, spec, &mut |_, _| {})?;
    let c = crate::cpu::render_f32(&buf, spec);
    let r = crate::cpu::render_f64(scene, &buf, spec);
    let ray_query = match gpu.ray_query_kernel() {
        Ok(k) => {
            let (rq, t) = k.render(&gpu.device, &gpu.queue, &buf, spec, &mut |_, _| {})?;
            RayQueryResult::Measured {
                vs_f64: diff(&rq, &r),
                accel: t.accel,
                trace: t.trace,
            }
        }
        Err(e) => RayQueryResult::NotMeasured(e),
    };
    let mut aovs = Vec::new();
    if !options.aovs.is_empty() {
        let mut on_gpu = Vec::with_capacity(w as usize * h as usize);
        kernel.render_aov_bands(
            &gpu.device,
            &gpu.queue,
            &buf,
            spec,
            u32::MAX,
            &mut |_, px| on_gpu.extend_from_slice(px),
        )?;
        let frame =
            |records: &[_]| AovImage::from_records(w, h, &options.aovs, IdMap::new(scene), records);
        let g = frame(&on_gpu);
        let c = frame(&crate::cpu::render_aov_rows(None, &buf, spec, 0, h));
        aovs = options
            .aovs
            .iter()
            .map(|&a| (a, diff_aov(a, &g, &c)))
            .collect();
    }
    Ok(CompareReport {
        scene: scene.path.clone(),
        width: w,
        height: h,
        algorithm: algo,
        adapter: gpu.describe(),
        traversal: kernel.traversal_name(),
        exactness: kernel.exactness().describe(),
        warnings,
        gpu_vs_cpu: diff(&g, &c),
        cpu_vs_f64: diff(&c, &r),
        gpu_vs_f64: diff(&g, &r),
        ray_query,
        difference: diff_image(&g, &c),
        aovs,
    })
}

impl fmt::Display for CompareReport {
    /// `glint compare`'s lines (without the warnings, which go to stderr).
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let (d, e) = (&self.gpu_vs_cpu, &self.cpu_vs_f64);
        writeln!(f, "adapter: {}", self.adapter)?;
        writeln!(
            f,
            "scene: {} at {}x{}, triangles: {}, traversal: {}, {}",
            self.scene.display(),
            self.width,
            self.height,
            self.algorithm,
            self.traversal,
            self.exactness
        )?;
        writeln!(
            f,
            "gpu vs cpu: {} differing pixels (8-bit), {} differing in some f32 bit, {} hit/miss disagreements, \
             {} hits at a distance t that differs in some bit, \
             largest channel difference {:.3e} ({} in 8 bits), mean {:.3e}",
            d.differing_pixels,
            d.differing_bits,
            d.hit_miss,
            d.differing_t,
            d.max_abs,
            d.max_u8,
            d.mean_abs
        )?;
        writeln!(
            f,
            "gpu = cpu in every bit (colour, hit/miss, t): {}",
            if d.bit_exact() { "yes" } else { "NO" }
        )?;
        writeln!(
            f,
            "cpu f32 vs f64: {} differing pixels (8-bit), {} hit/miss, largest {:.3e}, rms {:.3e}",
            e.differing_pixels, e.hit_miss, e.max_abs, e.rms
        )?;
        let line = |f: &mut fmt::Formatter<'_>, name: &str, x: &Diff| {
            writeln!(
                f,
                "{name} vs f64: {} hit/miss disagreements, largest channel error {:.3e}, rms {:.3e}, {} pixels off in 8 bits",
                x.hit_miss, x.max_abs, x.rms, x.differing_pixels
            )
        };
        for (aov, d) in &self.aovs {
            write!(f, "gpu vs cpu, AOV {aov}: {} differing pixels", d.differing)?;
            if let Some((x, y)) = d.first {
                write!(f, " (the first at {x},{y})")?;
            }
            writeln!(f)?;
        }
        line(f, "gpu", &self.gpu_vs_f64)?;
        match &self.ray_query {
            RayQueryResult::Measured {
                vs_f64,
                accel,
                trace,
            } => {
                line(f, "gpu-rq", vs_f64)?;
                write!(
                    f,
                    "gpu-rq: acceleration structure {:.1} ms, trace {:.1} ms",
                    accel.as_secs_f64() * 1e3,
                    trace.as_secs_f64() * 1e3
                )
            }
            RayQueryResult::NotMeasured(e) => write!(f, "gpu-rq: not measured: {e}"),
        }
    }
}
