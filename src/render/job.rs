//! [`Job`]: one frame of a scene on a [`Renderer`], from the scene to the file, as
//! `glint render` makes it.

use std::fmt;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::Duration;
use web_time::Instant;

use super::aov::{Aov, AovImage, IdMap};
use super::output::{Output, Sink};
use super::renderer::{RenderError, RenderOptions, Renderer, Tracer, TracerKind};
use crate::buffers::{SceneBuffers, Specialisation};
use crate::gpu::{Gpu, GpuError, GpuTimings};
use crate::image::{Encoding, Image, ImageError};
use crate::scene::{Scene, TriangleAlgorithm};
use crate::stages::Stages;

/// Rows per band of the GPU: large, since each dispatch and readback has a fixed cost (about
/// 3.5 ms on lavapipe); about this many MiB of f32 pixels.
const GPU_BAND_MIB: u64 = 64;

/// Rows per band of the CPU tracers: small, since a band is the render's largest buffer once
/// the scene is built (the dragon's peak: 162 MiB with 64 MiB bands, which hold its whole
/// 1024×768 frame, 151 MiB with 4 MiB, 147 MiB with 2 MiB).
const CPU_BAND_MIB: u64 = 2;

/// Rows per band when a `w`×`h` frame is rendered and written band by band: about `mib` MiB
/// of f32 pixels, an even number (the CPU packets are two rows high), at least 2.
fn band_rows(w: u32, h: u32, mib: u64) -> u32 {
    let rows = ((mib << 20) / (w as u64 * 16)).max(2) as u32 & !1;
    rows.min(h.max(1))
}

/// Something a render should tell its user; it goes on, and the image is what it would be.
#[derive(Debug)]
pub enum Warning {
    /// From reading the scene (a degenerate triangle skipped, a mesh's normals, ...), with
    /// its file and line.
    Scene(String),
    /// A primitive outside the range where glint's tests are exact (far, tiny or huge
    /// geometry, `scene::range`).
    Range(String),
    /// The cache could not read or write an entry (the render is unaffected).
    Cache(crate::cache::Event),
}

impl fmt::Display for Warning {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Warning::Scene(m) | Warning::Range(m) => f.write_str(m),
            Warning::Cache(e) => {
                let m = e.to_string();
                f.write_str(m.strip_prefix("warning: ").unwrap_or(&m))
            }
        }
    }
}

/// A choice the renderer made that the user did not name.
#[derive(Debug)]
pub enum Note {
    /// `auto` chose the CPU tracer, and why ([`Renderer::note`]).
    Backend(String),
    /// `auto`'s GPU could not hold the scene (its error), so the CPU tracer rendered it.
    Fallback(GpuError),
}

impl fmt::Display for Note {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Note::Backend(m) => f.write_str(m),
            Note::Fallback(e) => write!(f, "{e}; so the CPU tracer renders this"),
        }
    }
}

/// What a [`Job`] tells its caller while it runs, in order.
#[derive(Debug)]
pub enum Event<'e> {
    /// A warning (also kept in [`RenderReport::warnings`]).
    Warning(&'e Warning),
    /// A note (also kept in [`RenderReport::notes`]).
    Note(&'e Note),
    /// What the cache did ("hit mesh", "stored bvh"): for a verbose front end.
    Cache(&'e crate::cache::Event),
    /// Rows of the frame done so far, of `total`.
    Rows {
        /// Rows done.
        done: u32,
        /// Rows in the frame.
        total: u32,
    },
}

impl fmt::Display for Event<'_> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Event::Warning(w) => write!(f, "warning: {w}"),
            Event::Note(n) => write!(f, "note: {n}"),
            Event::Cache(e) => write!(f, "cache: {e}"),
            Event::Rows { done, total } => write!(f, "{done}/{total} rows"),
        }
    }
}

/// What a [`Job`] did.
#[derive(Debug)]
pub struct RenderReport {
    /// Where the pixels went.
    pub output: Output,
    /// The frame's width.
    pub width: u32,
    /// The frame's height.
    pub height: u32,
    /// Triangles traced.
    pub triangles: u32,
    /// Spheres traced.
    pub spheres: usize,
    /// The top level's instances where the scene has `[[instances]]` (the scene's own
    /// primitives and each mesh drawn where its entry placed it are one each), else 0.
    pub instances: usize,
    /// The triangle algorithm.
    pub algorithm: TriangleAlgorithm,
    /// The tracer that made the image (the CPU's after a fallback).
    pub tracer: TracerKind,
    /// The tracer in words: the SIMD build, or the adapter, traversal and GPU timings.
    pub description: String,
    /// The frame's time: the trace (on the GPU, trace and readback), without the scene's
    /// preparation or the file's encoding.
    pub frame: Duration,
    /// The GPU's parts of the render, where the GPU made the image.
    pub gpu: Option<GpuTimings>,
    /// The warnings, in the order they came.
    pub warnings: Vec<Warning>,
    /// The notes, in the order they came.
    pub notes: Vec<Note>,
    /// The wall time of each stage of this render ([`crate::stages`]): the scene's reading
    /// and parsing where the job read the scene itself ([`Job::new`]; a scene the caller
    /// lends keeps its own in [`Scene::load_stages`]), then flattening and the BVH, the
    /// checks, the trace, the encoding and the writing.
    pub stages: Vec<(&'static str, Duration)>,
    /// From the job's start to its end.
    pub total: Duration,
    /// The image, for [`Output::Memory`].
    pub image: Option<Image>,
    /// The AOVs, for [`Output::Memory`] where [`RenderOptions::aovs`] named some.
    pub aovs: Option<AovImage>,
    /// The AOVs' PNGs written beside a PNG's colour ([`AovImage::png_path`]); an EXR holds
    /// its AOVs as channels of its own.
    pub aov_files: Vec<std::path::PathBuf>,
}

impl fmt::Display for RenderReport {
    /// One line: `glint render`'s.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self.output.path() {
            Some(p) => write!(f, "{}: ", p.display())?,
            None => f.write_str("memory: ")?,
        }
        let count = |n: usize, one: &str| match n {
            1 => format!("1 {one}"),
            n => format!("{n} {one}s"),
        };
        write!(f, "{}x{}, ", self.width, self.height)?;
        if self.triangles > 0 {
            write!(
                f,
                "{} ({}), ",
                count(self.triangles as usize, "triangle"),
                self.algorithm
            )?;
        }
        if self.spheres > 0 || self.triangles == 0 {
            write!(f, "{}, ", count(self.spheres, "sphere"))?;
        }
        if self.instances > 0 {
            write!(f, "{}, ", count(self.instances, "instance"))?;
        }
        write!(
            f,
            "{:.1} ms, {}",
            self.frame.as_secs_f64() * 1e3,
            self.description
        )
    }
}

/// The scene a job renders: its own (whose primitives the buffers take, so they are not
/// held twice), or the caller's.
enum Source<'a> {
    Owned(Box<Scene>),
    Borrowed(&'a Scene),
}

/// One frame of a scene on a [`Renderer`]: everything `glint render` does.
///
/// - The frame goes to its [`Output`] band by band (bounded memory for a PNG, whatever the
///   size), after a check that it fits in memory.
/// - `auto`: where the GPU cannot hold the scene, the CPU tracer renders it, with a
///   [`Note::Fallback`].
/// - The scene's cache (`Scene::cache`, when it was loaded with one) is drained of its
///   events, and its writes waited for before the report.
/// - Warnings, notes, cache events and progress reach [`Job::on_event`] as they happen.
pub struct Job<'a> {
    scene: Source<'a>,
    output: Output,
    options: RenderOptions,
    events: Box<dyn FnMut(Event<'_>) + 'a>,
    cancel: Option<Arc<AtomicBool>>,
    buffers: Option<&'a mut SceneBuffers>,
}

/// The parts of a job that its stages share.
struct Run<'j, 'a> {
    events: &'j mut (dyn FnMut(Event<'_>) + 'a),
    warnings: Vec<Warning>,
    notes: Vec<Note>,
    cancel: Option<&'j AtomicBool>,
    /// This render's stage times ([`RenderReport::stages`]).
    stages: Stages,
    /// The frame's AOVs, which the f32 CPU tracer writes as it traces the colour (`None`:
    /// no AOVs asked for).
    aov_frame: Option<AovImage>,
    /// Whether `aov_frame` is one band, rewritten for each band and streamed with the
    /// colour to an EXR (the f32 CPU tracer's, to an EXR), not the whole frame.
    aov_band: bool,
}

impl Run<'_, '_> {
    /// Whether [`Job::cancel_on`]'s flag is set.
    fn cancelled(&self) -> bool {
        self.cancel.is_some_and(|c| c.load(Ordering::Relaxed))
    }

    fn warn(&mut self, w: Warning) {
        (self.events)(Event::Warning(&w));
        self.warnings.push(w);
    }

    fn note(&mut self, n: Note) {
        (self.events)(Event::Note(&n));
        self.notes.push(n);
    }

    /// What `cache` did since the last call: its warnings as warnings, the rest as events.
    fn drain_cache(&mut self, cache: Option<&crate::cache::Cache>) {
        for e in cache.map(|c| c.take_events()).unwrap_or_default() {
            if e.is_warning() {
                self.warn(Warning::Cache(e));
            } else {
                (self.events)(Event::Cache(&e));
            }
        }
    }
}

impl<'a> Job<'a> {
    /// A job rendering `scene` (which it consumes: its primitives move into the render's
    /// buffers) to `output`, with the scene's own size, samples and algorithm.
    pub fn new(scene: Scene, output: Output) -> Job<'a> {
        Job {
            scene: Source::Owned(Box::new(scene)),
            output,
            options: RenderOptions::default(),
            events: Box::new(|_| {}),
            cancel: None,
            buffers: None,
        }
    }

    /// A job rendering the caller's `scene` (copied into the render's buffers).
    pub fn borrowed(scene: &'a Scene, output: Output) -> Job<'a> {
        Job {
            scene: Source::Borrowed(scene),
            output,
            options: RenderOptions::default(),
            events: Box::new(|_| {}),
            cancel: None,
            buffers: None,
        }
    }

    /// The frame's size, samples and algorithm, where they differ from the scene's.
    pub fn options(mut self, options: RenderOptions) -> Job<'a> {
        self.options = options;
        self
    }

    /// Renders from `buffers`, made by the caller from this job's scene
    /// ([`SceneBuffers::new`]) and kept across jobs: the job sets their camera and frame
    /// values ([`SceneBuffers::set_camera`], then the options) and neither rebuilds nor
    /// frees their geometry, so frames of one scene under moving cameras build the BVH
    /// once. Buffers made with another triangle algorithm than the job's are made again.
    /// Every other buffer must be the scene's: a job cannot check that the primitives,
    /// materials or lights are still the ones they were made from.
    pub fn buffers(mut self, buffers: &'a mut SceneBuffers) -> Job<'a> {
        self.buffers = Some(buffers);
        self
    }

    /// Calls `f` with each [`Event`] as it happens (progress at each band).
    pub fn on_event(mut self, f: impl FnMut(Event<'_>) + 'a) -> Job<'a> {
        self.events = Box::new(f);
        self
    }

    /// Stops the job at the next band once `flag` is set (from another thread, or a signal
    /// handler): [`Job::run`] then returns [`RenderError::Cancelled`] and leaves no file
    /// behind. The CPU tracers look at it between bands of at most 2 MiB of pixels; the GPU
    /// finishes the frame's dispatches and writes nothing more.
    pub fn cancel_on(mut self, flag: Arc<AtomicBool>) -> Job<'a> {
        self.cancel = Some(flag);
        self
    }

    /// Renders the frame on `renderer` and writes it to the output.
    pub fn run(self, renderer: &Renderer) -> Result<RenderReport, RenderError> {
        let start = Instant::now();
        let Job {
            scene,
            output,
            options,
            mut events,
            cancel,
            buffers,
        } = self;
        let mut run = Run {
            events: &mut *events,
            warnings: Vec::new(),
            notes: Vec::new(),
            cancel: cancel.as_deref(),
            stages: Stages::new(),
            aov_frame: None,
            aov_band: false,
        };
        let (mut owned, borrowed) = match scene {
            Source::Owned(s) => (Some(s), None),
            Source::Borrowed(s) => (None, Some(s)),
        };
        if let Some(s) = &owned {
            run.stages.record_all(&s.load_stages.0);
        }
        let (w, h, algo) = prepare(pick(&owned, borrowed), &output, &options, &mut run)?;
        let aovs = options.aovs.clone();
        // The f32 CPU tracer makes the colour and AOVs at once: to an EXR, both are
        // streamed band by band.
        let band = matches!(output, Output::Exr(_))
            && !aovs.is_empty()
            && matches!(renderer.tracer(), Tracer::Cpu);
        // The rows of AOVs held at once: a band where streamed, else the whole frame.
        let aov_rows = if band {
            band_rows(w, h, CPU_BAND_MIB)
        } else {
            h
        };
        check_aov_output(&output, &aovs, w, h, aov_rows)?;
        // Only the f64 tracer reads the scene's primitives once they are flat, so the
        // others take them from a scene of the job's own (the dragon's are 35 MB, a sixth
        // of the former peak).
        let mut made;
        let keep = buffers.is_some();
        let buf: &mut SceneBuffers = match buffers {
            Some(b) => {
                if b.triangle_algo != algo.code() {
                    *b = SceneBuffers::new(pick(&owned, borrowed), w, h, algo);
                    run.stages.record_all(&b.stages.0);
                }
                let scene = pick(&owned, borrowed);
                b.set_camera(&scene.camera, w, h);
                b.params.max_depth = scene.max_depth;
                b
            }
            None => {
                made = match owned.as_deref_mut() {
                    Some(s) if !matches!(renderer.tracer(), Tracer::CpuF64) => {
                        SceneBuffers::from_scene_taking(s, w, h, algo)
                    }
                    _ => SceneBuffers::new(pick(&owned, borrowed), w, h, algo),
                };
                run.stages.record_all(&made.stages.0);
                &mut made
            }
        };
        let scene = pick(&owned, borrowed);
        let cache = scene.cache.as_deref();
        options.apply(buf);
        run.drain_cache(cache);
        if let Some(note) = renderer.note() {
            run.note(Note::Backend(note.to_string()));
        }
        // An EXR's rows interleave the colour's channels and the AOVs': the f32 CPU tracer
        // streams them through one band of AOVs, rewritten for each band (its memory
        // touched once, not a whole frame's); the other tracers trace the AOVs after the
        // colour, so their EXR is written whole at the end.
        let to_sink = match &output {
            Output::Exr(_) if !aovs.is_empty() && !band => Output::Memory,
            o => o.clone(),
        };
        let math = options.math_mode();
        let keep_geometry = keep || !aovs.is_empty();
        if !aovs.is_empty() {
            run.aov_frame = Some(AovImage::new(w, aov_rows, &aovs, IdMap::new(scene)));
            run.aov_band = band;
        }
        let mut sink = match (&output, &run.aov_frame) {
            (Output::Exr(p), Some(a)) if band => Sink::open_exr_aov(p, w, h, a)?,
            _ => Sink::open(&to_sink, w, h, scene.encoding)?,
        };
        let traced = trace(
            renderer,
            scene,
            buf,
            math,
            keep_geometry,
            &mut sink,
            &mut run,
        )?;
        if run.cancelled() {
            return Err(RenderError::Cancelled);
        }
        let mut aov_image = None;
        let mut aov_files = Vec::new();
        if let Some(mut a) = run.aov_frame.take().filter(|_| !run.aov_band) {
            // The f32 CPU tracer wrote them with the colour, from the same camera rays.
            if traced.tracer != TracerKind::CpuF32 {
                let spec = Specialisation::for_scene(buf).with_math(math);
                let t = Instant::now();
                trace_aovs(renderer, traced.tracer, scene, buf, spec, &mut a)?;
                run.stages.record("aov", t.elapsed());
            }
            // The AOVs' files first: the colour's, renamed into place last, marks the
            // frame done (`render --frames --resume`).
            if let Output::Png(p) = &output {
                let t = Instant::now();
                aov_files = a.write_pngs(p)?;
                run.stages.record("write", t.elapsed());
            }
            aov_image = Some(a);
        }
        let mut image = run.stages.time("write", || sink.finish())?;
        if let Output::Exr(p) = &output
            && let Some(colour) = &image
            && let Some(a) = aov_image.take()
        {
            // The frame whole, through the same writer and channel layout as a streamed one.
            run.stages.time("write", || {
                let mut exr = Sink::open_exr_aov(p, w, h, &a)?;
                exr.write_rows_aov(&colour.pixels, &a)?;
                exr.finish()
            })?;
            image = None;
        }
        let aov_image = aov_image.filter(|_| output == Output::Memory);
        let t_wait = Instant::now();
        if cache.is_some_and(|c| c.finish_writes() > 0) {
            run.stages.record("cache wait", t_wait.elapsed());
        }
        run.drain_cache(cache);
        run.stages.record("trace", traced.frame);
        Ok(RenderReport {
            output,
            width: w,
            height: h,
            triangles: buf.params.n_triangles,
            spheres: buf.spheres.len(),
            instances: buf.instances.len(),
            algorithm: algo,
            tracer: traced.tracer,
            description: traced.description,
            frame: traced.frame,
            gpu: traced.gpu,
            warnings: run.warnings,
            notes: run.notes,
            stages: run.stages.into_times(),
            total: start.elapsed(),
            image,
            aovs: aov_image,
            aov_files,
        })
    }
}

/// The job's scene: its own, else the caller's.
fn pick<'s>(owned: &'s Option<Box<Scene>>, borrowed: Option<&'s Scene>) -> &'s Scene {
    match (owned, borrowed) {
        (Some(s), _) => s,
        (None, Some(s)) => s,
        (None, None) => unreachable!("a job has a scene"),
    }
}

/// The checks before any work: the output does not overwrite the scene, the scene's and
/// the range's warnings, and the frame fits in memory; the frame's size and algorithm.
fn prepare(
    scene: &Scene,
    output: &Output,
    options: &RenderOptions,
    run: &mut Run<'_, '_>,
) -> Result<(u32, u32, TriangleAlgorithm), RenderError> {
    if let Some(p) = output.path()
        && same_file(&scene.path, p)
    {
        return Err(RenderError::OverwritesScene(p.to_owned()));
    }
    run.stages.time("checks", || scene.validate())?;
    for w in &scene.warnings {
        run.warn(Warning::Scene(w.clone()));
    }
    let (w, h) = options.checked_size(scene)?;
    let algo = options.triangle.unwrap_or(scene.triangle);
    for m in run.stages.time("checks", || scene.range_warnings(algo)) {
        run.warn(Warning::Range(m));
    }
    let band = band_rows(w, h, GPU_BAND_MIB);
    super::check_memory(w, h, output.bytes_at_once(w, h, band))?;
    Ok((w, h, algo))
}

/// Checks, before any work, that `aovs` can go to `output` (a PNG's AOVs each to a PNG of
/// its own, which must be writable) and that `rows` rows of them fit in memory.
fn check_aov_output(
    output: &Output,
    aovs: &[Aov],
    w: u32,
    h: u32,
    rows: u32,
) -> Result<(), RenderError> {
    if aovs.is_empty() {
        return Ok(());
    }
    if let Output::Png(p) = output {
        AovImage::check_png(p, aovs)?;
        for &a in aovs {
            crate::image::check_writable(&AovImage::png_path(p, a))?;
        }
    }
    // The AOVs' planes (4 bytes a channel) and the colour, whole or a band of each where
    // they are streamed, and 16 bytes a pixel of headroom (once an EXR's copy of R, G, B,
    // A, which the writer no longer makes).
    let channels: usize = aovs.iter().map(|a| a.channel_names().len()).sum();
    let per_pixel = 4 * channels as u64 + 16 + 16;
    super::check_memory(w, h, w as u64 * rows as u64 * per_pixel)?;
    Ok(())
}

/// The frame's AOVs on the tracer that made its colour (`tracer`: the CPU's after `auto`'s
/// fallback), written into `frame`: the GPU's band by band, the CPU's all at once.
fn trace_aovs(
    renderer: &Renderer,
    tracer: TracerKind,
    scene: &Scene,
    buf: &SceneBuffers,
    spec: Specialisation,
    frame: &mut AovImage,
) -> Result<(), RenderError> {
    // The renderer's GPU kernel, unless `auto` fell back to the CPU.
    let kernel = match tracer == renderer.tracer().kind() {
        true => renderer.tracer().kernel(spec)?,
        false => None,
    };
    let Some((gpu, kernel)) = kernel else {
        let f64_scene = (tracer == TracerKind::CpuF64).then_some(scene);
        let h = buf.params.height;
        frame.put_rows(0, &crate::cpu::render_aov_rows(f64_scene, buf, spec, 0, h));
        return Ok(());
    };
    kernel.render_aov_bands(
        &gpu.device,
        &gpu.queue,
        buf,
        spec,
        u32::MAX,
        &mut |y, px| frame.put_rows(y, px),
    )?;
    Ok(())
}

/// What [`trace`] did.
struct Traced {
    tracer: TracerKind,
    description: String,
    frame: Duration,
    gpu: Option<GpuTimings>,
}

/// Traces the frame into `sink` on the renderer's tracer; `auto`'s GPU falls back to the
/// CPU where the scene is too large for it.
fn trace(
    renderer: &Renderer,
    scene: &Scene,
    buf: &mut SceneBuffers,
    math: crate::buffers::MathMode,
    keep: bool,
    sink: &mut Sink,
    run: &mut Run<'_, '_>,
) -> Result<Traced, RenderError> {
    let spec = Specialisation::for_scene(buf).with_math(math);
    let cpu = |f64: bool, buf: &SceneBuffers, sink: &mut Sink, run: &mut Run<'_, '_>| {
        let frame = cpu_bands(f64.then_some(scene), buf, spec, sink, run)?;
        Ok::<_, RenderError>(Traced {
            tracer: if f64 {
                TracerKind::CpuF64
            } else {
                TracerKind::CpuF32
            },
            description: if f64 {
                "cpu-f64".to_string()
            } else {
                crate::cpu::describe_f32()
            },
            frame,
            gpu: None,
        })
    };
    match renderer.tracer() {
        Tracer::Cpu => cpu(false, buf, sink, run),
        Tracer::CpuF64 => cpu(true, buf, sink, run),
        Tracer::Gpu(gpu) | Tracer::GpuRq(gpu) => {
            let rq = matches!(renderer.tracer(), Tracer::GpuRq(_));
            match gpu_bands(gpu, rq, buf, spec, keep, sink, run) {
                Err(RenderError::Gpu(e @ GpuError::TooLarge { .. }))
                    if renderer.backend() == super::Backend::Auto =>
                {
                    // Too large for this device's buffers: the CPU has no such limit.
                    run.note(Note::Fallback(e));
                    cpu(false, buf, sink, run)
                }
                other => other,
            }
        }
    }
}

/// The frame on a CPU tracer (f64 where `scene` is given), in bands written to `sink` as
/// they come; the time spent tracing.
fn cpu_bands(
    f64_scene: Option<&Scene>,
    buf: &SceneBuffers,
    spec: Specialisation,
    sink: &mut Sink,
    run: &mut Run<'_, '_>,
) -> Result<Duration, RenderError> {
    let (w, h) = (buf.params.width, buf.params.height);
    let rows_per_band = band_rows(w, h, CPU_BAND_MIB);
    let mut frame = Duration::ZERO;
    let mut y = 0;
    while y < h {
        if run.cancelled() {
            return Err(RenderError::Cancelled);
        }
        let rows = rows_per_band.min(h - y);
        let t = Instant::now();
        let px = match (f64_scene, run.aov_frame.as_mut()) {
            (Some(s), _) => crate::cpu::render_f64_rows(s, buf, spec, y, rows),
            (None, None) => crate::cpu::render_f32_rows(buf, spec, y, rows),
            (None, Some(aovs)) => {
                let at = if run.aov_band { 0 } else { y };
                let blocks = aovs.blocks(at, rows, crate::cpu::packet::PACKET_H);
                crate::cpu::render_f32_rows_aov(buf, spec, y, rows, blocks)
            }
        };
        frame += t.elapsed();
        match run.aov_frame.as_ref().filter(|_| run.aov_band) {
            Some(band) => run
                .stages
                .time("encode", || sink.write_rows_aov(&px, band))?,
            None => run.stages.time("encode", || sink.write_rows(&px))?,
        }
        y += rows;
        (run.events)(Event::Rows { done: y, total: h });
    }
    Ok(frame)
}

/// The frame on the GPU (the ray-query tracer where `rq`), in tiles written to `sink` as
/// they are read back. A PNG's tiles are packed to 8 bits by the shader, and the host's
/// geometry is freed once uploaded (except where the upload fails, so the CPU can still
/// trace `buf`, or where the caller keeps `buf` for more frames: `keep`).
fn gpu_bands(
    gpu: &Gpu,
    rq: bool,
    buf: &mut SceneBuffers,
    spec: Specialisation,
    keep: bool,
    sink: &mut Sink,
    run: &mut Run<'_, '_>,
) -> Result<Traced, RenderError> {
    let (w, h) = (buf.params.width, buf.params.height);
    let band = band_rows(w, h, GPU_BAND_MIB);
    let kernel = if rq {
        gpu.ray_query_kernel()?
    } else {
        gpu.compute_kernel(spec)?
    };
    let mut written: Result<(), ImageError> = Ok(());
    let cancel = run.cancel;
    let mut rows = |y: u32, n: usize, write: &mut dyn FnMut() -> Result<(), ImageError>| {
        if written.is_ok() && !cancel.is_some_and(|c| c.load(Ordering::Relaxed)) {
            written = run.stages.time("encode", write);
        }
        let done = y + (n / w as usize) as u32;
        (run.events)(Event::Rows { done, total: h });
    };
    let t = match sink {
        Sink::Png(png) if png.encoding() == Encoding::Linear && !keep => kernel
            .render_bands_rgba8_releasing(
                &gpu.device,
                &gpu.queue,
                buf,
                spec,
                band,
                &mut |y, px| rows(y, px.len(), &mut || png.write_rgba8_rows(px)),
            ),
        Sink::Png(..) | Sink::Exr(..) | Sink::ExrAov(..) | Sink::Frame(..) => {
            kernel.render_bands(&gpu.device, &gpu.queue, buf, spec, band, &mut |y, px| {
                rows(y, px.len(), &mut || sink.write_rows(px))
            })
        }
    }?;
    written?;
    let accel = if rq {
        format!(
            " acceleration structure {:.1} ms,",
            t.accel.as_secs_f64() * 1e3
        )
    } else {
        String::new()
    };
    let description = format!(
        "{}: {} (device {:.0} ms, compile {:.0} ms,{accel} trace {:.1} ms, readback {:.1} ms)",
        if rq {
            "gpu-rq".to_string()
        } else {
            format!("gpu (traversal: {})", kernel.traversal_name())
        },
        gpu.describe(),
        gpu.start_time.as_secs_f64() * 1e3,
        t.compile.as_secs_f64() * 1e3,
        t.trace.as_secs_f64() * 1e3,
        t.readback.as_secs_f64() * 1e3
    );
    Ok(Traced {
        tracer: if rq {
            TracerKind::GpuRq
        } else {
            TracerKind::Gpu
        },
        description,
        frame: t.trace + t.readback,
        gpu: Some(t),
    })
}

fn same_file(a: &std::path::Path, b: &std::path::Path) -> bool {
    match (a.canonicalize(), b.canonicalize()) {
        (Ok(x), Ok(y)) => x == y,
        _ => false,
    }
}
