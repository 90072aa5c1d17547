//! The `glint` command line: `render`, `compare`, `bench`.

use std::io::IsTerminal;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex};
use std::time::Instant;

use anyhow::{Context, Result, bail};
use clap::{Parser, Subcommand, ValueEnum};
use glint::buffers::{SceneBuffers, Specialisation};
use glint::gpu::Gpu;
use glint::scene::{Scene, TriangleAlgorithm};

#[derive(Parser)]
#[command(
    name = "glint",
    version,
    about = "A WGSL compute-shader ray tracer with a bit-exact CPU mirror"
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

impl From<Backend> for glint::Backend {
    fn from(b: Backend) -> glint::Backend {
        match b {
            Backend::Auto => glint::Backend::Auto,
            Backend::Gpu => glint::Backend::Gpu,
            Backend::GpuRq => glint::Backend::GpuRq,
            Backend::Cpu => glint::Backend::Cpu,
            Backend::CpuF64 => glint::Backend::CpuF64,
        }
    }
}

#[derive(Clone, Copy, PartialEq, Eq, ValueEnum)]
enum Backend {
    /// A real GPU when there is one; the CPU tracer when the only adapters are CPU Vulkan
    /// implementations (lavapipe: slower than the CPU tracer for every whole render measured) or
    /// there is none (said in one line); the CPU tracer too when the scene exceeds the GPU's
    /// buffers.
    Auto,
    /// The WGSL compute shader through wgpu (Vulkan).
    Gpu,
    /// The shader with the triangles traced by the driver's ray queries (VK_KHR_ray_query:
    /// ray-tracing GPUs, Mesa ≥ 24.1's lavapipe); an error where there are none.
    GpuRq,
    /// The f32 CPU mirror of the shader.
    Cpu,
    /// The f64 CPU ground truth.
    CpuF64,
}

/// The options every subcommand that loads a scene shares.
#[derive(clap::Args)]
struct CommonArgs {
    /// Use the first Vulkan adapter whose name contains this.
    #[arg(long)]
    adapter: Option<String>,
    /// Read only files below the scene's own folder (meshes, MTLs; links followed).
    #[arg(long)]
    confine: bool,
}

/// The frame options of `render` and `compare`.
#[derive(clap::Args)]
struct FrameArgs {
    /// Image size WxH (default: the scene's camera).
    #[arg(long, value_parser = parse_size)]
    size: Option<(u32, u32)>,
    /// Triangle algorithm (default: the scene's).
    #[arg(long)]
    triangle: Option<TriangleAlgorithm>,
    /// Antialiasing: N×N samples a pixel (default: the scene camera's `samples`).
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..=glint::scene::MAX_SAMPLES as i64))]
    samples: Option<u32>,
}

#[derive(Subcommand)]
enum Command {
    /// Render a scene to a PNG (or an EXR).
    Render {
        /// The scene file (TOML).
        scene: PathBuf,
        /// Output image: .png (8-bit) or .exr (the f32 image exactly, t in alpha).
        #[arg(short, long)]
        output: PathBuf,
        /// Print the time of each stage (read, gunzip, parse, BVH build, trace, PNG, ...).
        #[arg(short, long)]
        verbose: bool,
        /// Which tracer.
        #[arg(long, value_enum, default_value = "auto")]
        backend: Backend,
        /// Neither read nor write the cache of large meshes and BVHs (kept in
        /// GLINT_CACHE_DIR, else $XDG_CACHE_HOME/glint or ~/.cache/glint).
        #[arg(long)]
        no_cache: bool,
        #[command(flatten)]
        frame: FrameArgs,
        #[command(flatten)]
        common: CommonArgs,
    },
    /// Render a scene on the GPU and on the CPU mirror and measure the difference.
    Compare {
        /// The scene file (TOML).
        scene: PathBuf,
        #[command(flatten)]
        frame: FrameArgs,
        #[command(flatten)]
        common: CommonArgs,
        /// Where to write the difference image.
        #[arg(long, default_value = "diff.png")]
        diff: PathBuf,
    },
    /// List the Vulkan adapters, best first, with their drivers and versions.
    Adapters,
    /// Compare two images (PNG or EXR) with `compare`'s metrics and write a difference
    /// image: an EXR made on a GPU machine against one made on the CPU elsewhere, bit for bit.
    Diff {
        /// The first image.
        a: PathBuf,
        /// The second image.
        b: PathBuf,
        /// Where to write the difference image (PNG).
        #[arg(long, default_value = "diff.png")]
        diff: PathBuf,
    },
    /// Speed against error: every scene × tracer × triangle algorithm, with a warm-up and
    /// timed runs; writes report.md, report.json and plot.png to --out.
    Bench {
        /// Scene files (default: the five seed scenes in scenes/).
        scenes: Vec<PathBuf>,
        /// Image size WxH (default 1024x768).
        #[arg(long, value_parser = parse_size, default_value = "1024x768")]
        size: (u32, u32),
        /// Timed runs per configuration.
        #[arg(long, default_value_t = 5)]
        runs: usize,
        /// Output folder.
        #[arg(long, default_value = "bench-out")]
        out: PathBuf,
        #[command(flatten)]
        common: CommonArgs,
        /// Skip the GPU (CPU tracers only).
        #[arg(long)]
        no_gpu: bool,
        /// Only this triangle algorithm (default: all three where a scene has triangles).
        #[arg(long)]
        triangle: Option<TriangleAlgorithm>,
        /// Antialiasing for every scene: N×N samples a pixel (default: each scene's own).
        #[arg(long, value_parser = clap::value_parser!(u32).range(1..=glint::scene::MAX_SAMPLES as i64))]
        samples: Option<u32>,
    },
}

fn parse_size(s: &str) -> Result<(u32, u32), String> {
    let (w, h) = s
        .split_once(['x', 'X'])
        .ok_or_else(|| format!("{s:?}: expected WxH, e.g. 640x480"))?;
    let p = |v: &str| -> Result<u32, String> {
        let n: u32 = v
            .trim()
            .parse()
            .map_err(|_| format!("{s:?}: {v:?} is not a whole number"))?;
        if n == 0 || n as i64 > glint::scene::MAX_IMAGE_SIDE {
            return Err(format!(
                "{s:?}: each side must be in 1..={}",
                glint::scene::MAX_IMAGE_SIDE
            ));
        }
        Ok(n)
    };
    Ok((p(w)?, p(h)?))
}

/// A one-line progress bar on stderr for renders that take longer than half a second,
/// drawn only when stderr is a terminal (logs get no carriage returns).
struct ProgressBar {
    start: Instant,
    shown: AtomicBool,
    lock: Mutex<()>,
}

impl ProgressBar {
    fn new(start: Instant) -> Self {
        ProgressBar {
            start,
            shown: AtomicBool::new(false),
            lock: Mutex::new(()),
        }
    }

    fn show(&self, done: u32, total: u32) {
        if !std::io::stderr().is_terminal() || self.start.elapsed().as_secs_f64() < 0.5 {
            return;
        }
        let Ok(_guard) = self.lock.try_lock() else {
            return;
        };
        let width = 40;
        let filled = (done as u64 * width / total.max(1) as u64) as usize;
        eprint!(
            "\r[{}{}] {done}/{total} rows, {:.1} s",
            "#".repeat(filled),
            ".".repeat(width as usize - filled),
            self.start.elapsed().as_secs_f64()
        );
        self.shown.store(true, Ordering::Relaxed);
    }

    fn finish(&self) {
        if self.shown.load(Ordering::Relaxed) {
            eprintln!();
        }
    }
}

/// The most bytes read from one input: `GLINT_MAX_INPUT_MIB` (MiB) when set to a number,
/// else the library's default; read here, once.
fn max_input_bytes() -> u64 {
    std::env::var("GLINT_MAX_INPUT_MIB")
        .ok()
        .and_then(|v| v.trim().parse::<u64>().ok())
        .map_or(
            glint::scene::LoadOptions::default().max_input_bytes,
            |mib| mib.saturating_mul(1 << 20),
        )
}

fn load(scene: &Path, confine: bool, cache: Option<Arc<glint::cache::Cache>>) -> Result<Scene> {
    let options = glint::scene::LoadOptions {
        max_input_bytes: max_input_bytes(),
        confine,
        cache,
    };
    let s = Scene::load_with(scene, &options)?;
    for w in &s.warnings {
        eprintln!("warning: {w}");
    }
    Ok(s)
}

/// Rows per band when a frame is rendered and written band by band: about `mib` MiB of
/// f32 pixels, an even number (the CPU packets are two rows high), at least 2.
fn band_rows(w: u32, h: u32, mib: u64) -> u32 {
    let rows = ((mib << 20) / (w as u64 * 16)).max(2) as u32 & !1;
    rows.min(h.max(1))
}

/// A GPU render's band callback: each band of a `w`×`h` frame written by `write` (timed as
/// "encode") until a write fails, whose error stays in `written`; the progress bar moved.
fn on_band<'a, T>(
    written: &'a mut Result<(), glint::image::ImageError>,
    bar: &'a ProgressBar,
    w: u32,
    h: u32,
    mut write: impl FnMut(&[T]) -> Result<(), glint::image::ImageError> + 'a,
) -> impl FnMut(u32, &[T]) + 'a {
    move |y, px| {
        if written.is_ok() {
            *written = glint::stages::time("encode", || write(px));
        }
        bar.show(y + (px.len() / w as usize) as u32, h);
    }
}

/// Band sizes: the GPU's tiles are large (each dispatch and readback has a fixed cost,
/// about 3.5 ms on lavapipe); the CPU's bands small, since a band is the render's largest
/// buffer once the scene is built (the dragon's peak: 162 MiB with 64 MiB bands, which
/// hold its whole 1024×768 frame, 151 MiB with 4 MiB, 147 MiB with 2 MiB).
const GPU_BAND_MIB: u64 = 64;
const CPU_BAND_MIB: u64 = 2;

/// Fails, before any work, when the `bytes` a `w`×`h` frame needs at once cannot fit in this
/// process's memory: what the system has available and what the address-space limit
/// (`ulimit -v`) leaves, with 512 MiB to spare for the scene, the driver and the encoder.
fn check_memory(w: u32, h: u32, bytes: u64) -> Result<()> {
    let need = bytes + (512 << 20);
    let read = |path: &str| std::fs::read_to_string(path).unwrap_or_default();
    let field = |text: &str, key: &str| -> Option<u64> {
        text.lines()
            .find(|l| l.starts_with(key))
            .and_then(|l| l.split_whitespace().nth(1))
            .and_then(|v| v.parse().ok())
    };
    let available = field(&read("/proc/meminfo"), "MemAvailable:").map(|kb| kb << 10);
    let limit = read("/proc/self/limits")
        .lines()
        .find(|l| l.starts_with("Max address space"))
        .and_then(|l| l.split_whitespace().nth(3).map(str::to_owned))
        .and_then(|v| v.parse::<u64>().ok());
    let used = field(&read("/proc/self/status"), "VmSize:").map_or(0, |kb| kb << 10);
    let room = [available, limit.map(|l| l.saturating_sub(used))]
        .into_iter()
        .flatten()
        .min();
    if let Some(room) = room
        && need > room
    {
        bail!(
            "a {w}x{h} frame needs about {} MiB of memory at once and this process has {} MiB \
             (available memory, and the ulimit -v address-space limit): choose a smaller --size",
            need >> 20,
            room >> 20
        );
    }
    Ok(())
}

/// Where a render's bands go: straight into a PNG, or into the whole f32 image for an EXR.
enum Sink {
    Png(Box<glint::image::PngStream>),
    Exr(glint::image::Image, usize),
}

impl Sink {
    fn create(
        path: &Path,
        format: glint::image::Format,
        w: u32,
        h: u32,
    ) -> Result<Sink, glint::image::ImageError> {
        Ok(match format {
            glint::image::Format::Png => {
                Sink::Png(Box::new(glint::image::PngStream::create(path, w, h)?))
            }
            glint::image::Format::Exr => Sink::Exr(glint::image::Image::new(w, h, [0.0; 4]), 0),
        })
    }

    fn write_rows(&mut self, px: &[[f32; 4]]) -> Result<(), glint::image::ImageError> {
        match self {
            Sink::Png(p) => p.write_rows(px),
            Sink::Exr(img, at) => {
                img.pixels[*at..*at + px.len()].copy_from_slice(px);
                *at += px.len();
                Ok(())
            }
        }
    }

    fn finish(self, path: &Path) -> Result<(), glint::image::ImageError> {
        match self {
            Sink::Png(p) => p.finish(),
            Sink::Exr(img, _) => img.save_exr(path),
        }
    }
}

/// The system allocator, asking Linux to back each block of 4 MiB or more with huge pages
/// (`MADV_HUGEPAGE`: 2 MiB a page fault instead of 4 KiB) where transparent huge pages are
/// on "madvise". A mesh's big vectors (the inflated text, the faces, the triangles, the
/// tree) are written once each, so their first touch was a page fault every 4 KiB.
#[cfg(all(target_os = "linux", target_env = "gnu"))]
struct HugeBlocks;

#[cfg(all(target_os = "linux", target_env = "gnu"))]
impl HugeBlocks {
    const MIN: usize = 4 << 20;
    const HUGE: usize = 2 << 20;

    /// Advises the whole huge pages inside `len` bytes at `p`.
    fn advise(p: *mut u8, len: usize) {
        if p.is_null() || len < Self::MIN {
            return;
        }
        let start = (p as usize).next_multiple_of(Self::HUGE);
        let end = (p as usize + len) / Self::HUGE * Self::HUGE;
        if end > start {
            // SAFETY: the range lies inside the block just allocated; madvise only hints.
            unsafe { libc::madvise(start as *mut libc::c_void, end - start, libc::MADV_HUGEPAGE) };
        }
    }
}

// SAFETY: every call is the system allocator's, with a hint added after it.
#[cfg(all(target_os = "linux", target_env = "gnu"))]
unsafe impl std::alloc::GlobalAlloc for HugeBlocks {
    unsafe fn alloc(&self, layout: std::alloc::Layout) -> *mut u8 {
        // SAFETY: as the caller's contract for `alloc`.
        let p = unsafe { std::alloc::System.alloc(layout) };
        Self::advise(p, layout.size());
        p
    }
    unsafe fn alloc_zeroed(&self, layout: std::alloc::Layout) -> *mut u8 {
        // SAFETY: as the caller's contract for `alloc_zeroed`.
        let p = unsafe { std::alloc::System.alloc_zeroed(layout) };
        Self::advise(p, layout.size());
        p
    }
    unsafe fn dealloc(&self, p: *mut u8, layout: std::alloc::Layout) {
        // SAFETY: as the caller's contract for `dealloc`.
        unsafe { std::alloc::System.dealloc(p, layout) }
    }
    unsafe fn realloc(&self, p: *mut u8, layout: std::alloc::Layout, size: usize) -> *mut u8 {
        // SAFETY: as the caller's contract for `realloc`.
        let q = unsafe { std::alloc::System.realloc(p, layout, size) };
        Self::advise(q, size);
        q
    }
}

#[cfg(all(target_os = "linux", target_env = "gnu"))]
#[global_allocator]
static ALLOCATOR: HugeBlocks = HugeBlocks;

/// Asks Mesa not to print its conformance warning for lavapipe on every start, and gives
/// this process (only) a runtime folder when `XDG_RUNTIME_DIR` is unset, so Mesa's window
/// system code does not print "XDG_RUNTIME_DIR is invalid or not set" up to four times.
/// Called first in `main`, before any thread exists (the library sets no variable).
fn quiet_driver() {
    if std::env::var_os("MESA_VK_IGNORE_CONFORMANCE_WARNING").is_none() {
        // SAFETY: called at the start of `main`, before any other thread exists.
        unsafe { std::env::set_var("MESA_VK_IGNORE_CONFORMANCE_WARNING", "1") };
    }
    if std::env::var_os("XDG_RUNTIME_DIR").is_none()
        && let Some(dir) = private_runtime_dir()
    {
        // SAFETY: as above.
        unsafe { std::env::set_var("XDG_RUNTIME_DIR", dir) };
    }
}

/// A folder only this user can enter, under the temporary folder, made when missing; None
/// when it cannot be made or someone else owns it.
#[cfg(unix)]
fn private_runtime_dir() -> Option<std::path::PathBuf> {
    use std::os::unix::fs::{DirBuilderExt, MetadataExt, PermissionsExt};
    let uid = std::fs::metadata("/proc/self").ok()?.uid();
    let dir = std::env::temp_dir().join(format!("glint-runtime-{uid}"));
    let _ = std::fs::DirBuilder::new().mode(0o700).create(&dir);
    let m = std::fs::symlink_metadata(&dir).ok()?;
    (m.is_dir() && m.uid() == uid && m.permissions().mode() & 0o077 == 0).then_some(dir)
}

#[cfg(not(unix))]
fn private_runtime_dir() -> Option<std::path::PathBuf> {
    None
}

/// The GPU settings for `--adapter NAME`, with what the environment adds, read here once:
/// `GLINT_MAX_BUFFER_BYTES` (a smaller GPU's buffer limit) and `GLINT_TRAVERSAL=ray`.
fn gpu_options(adapter: Option<&str>) -> glint::gpu::GpuOptions {
    glint::gpu::GpuOptions {
        adapter: adapter.map(str::to_string),
        max_buffer_bytes: std::env::var("GLINT_MAX_BUFFER_BYTES")
            .ok()
            .and_then(|v| v.trim().parse::<u64>().ok()),
        per_ray_traversal: std::env::var("GLINT_TRAVERSAL").as_deref() == Ok("ray"),
    }
}

/// The cache's settings for `dir`, with what the environment adds, read here once:
/// `GLINT_CACHE_MIB` (the folder's size limit) and `GLINT_CACHE_MIN_PRIMS`.
fn cache_settings(dir: std::path::PathBuf) -> glint::cache::Settings {
    let var = |k: &str| {
        std::env::var(k)
            .ok()
            .and_then(|v| v.trim().parse::<u64>().ok())
    };
    let mut s = glint::cache::Settings::new(dir);
    if let Some(mib) = var("GLINT_CACHE_MIB") {
        s.max_bytes = mib.saturating_mul(1 << 20);
    }
    if let Some(n) = var("GLINT_CACHE_MIN_PRIMS") {
        s.min_prims = n as usize;
    }
    // `FinishWrites` waits for the writes before the render ends.
    s.write_behind = true;
    s
}

/// What the cache did: warnings always, the rest as `cache: ...` when `verbose`.
fn print_cache_events(cache: Option<&glint::cache::Cache>, verbose: bool) {
    for e in cache.map(|c| c.take_events()).unwrap_or_default() {
        if e.is_warning() {
            eprintln!("{e}");
        } else if verbose {
            eprintln!("cache: {e}");
        }
    }
}

/// Waits, when dropped, for the cache's entries still being written behind.
struct FinishWrites(Option<Arc<glint::cache::Cache>>);

impl Drop for FinishWrites {
    fn drop(&mut self) {
        if let Some(c) = &self.0 {
            let _ = c.finish_writes();
        }
    }
}

fn main() {
    // glibc raises its mmap threshold to the size of the largest block freed (up to 32 MiB),
    // after which a mesh's big vectors come from the heap, whose freed middle is never
    // given back: the dragon's peak was 225 MB, 145 MB with the threshold fixed at 1 MiB
    // (each block of a MiB or more is mapped, and unmapped when freed).
    #[cfg(all(target_os = "linux", target_env = "gnu"))]
    // SAFETY: mallopt only sets a parameter of the allocator; called before any thread.
    unsafe {
        libc::mallopt(libc::M_MMAP_THRESHOLD, 1 << 20);
    }
    quiet_driver();
    // SIGINT / SIGTERM: remove the half-written temporary image (the output file itself is
    // only ever replaced whole) and the cache entries' temporary files, then exit as
    // interrupted.
    let _ = ctrlc::set_handler(|| {
        glint::image::remove_pending_temp();
        glint::cache::remove_pending_temps();
        std::process::exit(130);
    });
    let result = run(Cli::parse());
    if let Err(e) = result {
        eprintln!("error: {e:#}");
        std::process::exit(1);
    }
}

fn run(cli: Cli) -> Result<()> {
    match cli.command {
        Command::Render {
            scene,
            output,
            verbose,
            backend,
            no_cache,
            frame:
                FrameArgs {
                    size,
                    triangle,
                    samples,
                },
            common: CommonArgs { adapter, confine },
        } => {
            let cache = glint::cache::default_dir()
                .filter(|_| !no_cache)
                .map(|dir| Arc::new(glint::cache::Cache::new(cache_settings(dir))));
            // Entries still being written behind are finished, whatever happens, so that
            // the next render finds them.
            let _finish = FinishWrites(cache.clone());
            if same_file(&scene, &output) {
                bail!(
                    "{}: the output would overwrite the scene file",
                    output.display()
                );
            }
            let start = Instant::now();
            // Before any work: the folder exists and a file can be made there.
            glint::image::check_writable(&output)?;
            let mut s = load(&scene, confine, cache.clone())?;
            s.camera.samples = samples.unwrap_or(s.camera.samples);
            let (w, h) = size.unwrap_or(s.size());
            let algo = triangle.unwrap_or(s.triangle);
            for w in glint::stages::time("checks", || s.range_warnings(algo)) {
                eprintln!("warning: {w}");
            }
            let format = glint::image::format_of(&output)?;
            let band = band_rows(w, h, GPU_BAND_MIB);
            let cpu_band = band_rows(w, h, CPU_BAND_MIB);
            check_memory(
                w,
                h,
                match format {
                    glint::image::Format::Png => band as u64 * w as u64 * (16 + 3),
                    // An EXR is written whole: the frame and its encoder's copy.
                    glint::image::Format::Exr => w as u64 * h as u64 * 16 * 2,
                },
            )?;
            // Only the f64 tracer reads the scene's primitives once they are flat, so the
            // others hand them over (the dragon's are 35 MB, a sixth of the former peak).
            let mut buf = if matches!(backend, Backend::CpuF64) {
                SceneBuffers::new(&s, w, h, algo)
            } else {
                SceneBuffers::from_scene_taking(&mut s, w, h, algo)
            };
            print_cache_events(cache.as_deref(), verbose);
            let spec = Specialisation::for_scene(&buf);
            let renderer =
                glint::Renderer::with_options(backend.into(), &gpu_options(adapter.as_deref()))?;
            if let Some(note) = renderer.note() {
                eprintln!("note: {note}");
            }
            let t0 = Instant::now();
            let bar = ProgressBar::new(t0);
            let mut sink = Sink::create(&output, format, w, h)?;
            let mut frame = std::time::Duration::ZERO;
            // The frame in bands of `band` rows, each written to the PNG as it comes: memory
            // stays bounded by a band, whatever the frame size.
            let cpu_bands = |buf: &SceneBuffers,
                             sink: &mut Sink,
                             frame: &mut std::time::Duration,
                             f64: bool|
             -> Result<()> {
                let mut y = 0;
                while y < h {
                    let rows = cpu_band.min(h - y);
                    let t = Instant::now();
                    let px = if f64 {
                        glint::cpu::render_f64_rows(&s, buf, spec, y, rows)
                    } else {
                        glint::cpu::render_f32_rows(buf, spec, y, rows)
                    };
                    *frame += t.elapsed();
                    glint::stages::time("encode", || sink.write_rows(&px))?;
                    y += rows;
                    bar.show(y, h);
                }
                Ok(())
            };
            let what = match renderer.tracer() {
                glint::Tracer::Cpu => {
                    cpu_bands(&buf, &mut sink, &mut frame, false)?;
                    glint::cpu::describe_f32()
                }
                glint::Tracer::CpuF64 => {
                    cpu_bands(&buf, &mut sink, &mut frame, true)?;
                    "cpu-f64".to_string()
                }
                glint::Tracer::Gpu(gpu) | glint::Tracer::GpuRq(gpu) => {
                    let rq = matches!(renderer.tracer(), glint::Tracer::GpuRq(_));
                    let kernel = if rq {
                        gpu.ray_query_kernel()?
                    } else {
                        gpu.compute_kernel(spec)?
                    };
                    let mut written: Result<(), glint::image::ImageError> = Ok(());
                    let result = match &mut sink {
                        // A PNG holds 8 bits a channel: the shader packs them (the lean
                        // frame). The host's geometry is freed once uploaded.
                        Sink::Png(png) => kernel.render_bands_rgba8_releasing(
                            &gpu.device,
                            &gpu.queue,
                            &mut buf,
                            spec,
                            band,
                            &mut on_band(&mut written, &bar, w, h, |px| png.write_rgba8_rows(px)),
                        ),
                        Sink::Exr(..) => kernel.render_bands(
                            &gpu.device,
                            &gpu.queue,
                            &buf,
                            spec,
                            band,
                            &mut on_band(&mut written, &bar, w, h, |px| sink.write_rows(px)),
                        ),
                    };
                    match result {
                        Ok(t) => {
                            written?;
                            frame = t.trace + t.readback;
                            format!(
                                "{}: {} (device {:.0} ms, compile {:.0} ms,{} trace {:.1} ms, readback {:.1} ms)",
                                if rq {
                                    "gpu-rq".to_string()
                                } else {
                                    format!("gpu (traversal: {})", kernel.traversal_name())
                                },
                                gpu.describe(),
                                gpu.start_time.as_secs_f64() * 1e3,
                                t.compile.as_secs_f64() * 1e3,
                                if rq {
                                    format!(
                                        " acceleration structure {:.1} ms,",
                                        t.accel.as_secs_f64() * 1e3
                                    )
                                } else {
                                    String::new()
                                },
                                t.trace.as_secs_f64() * 1e3,
                                t.readback.as_secs_f64() * 1e3
                            )
                        }
                        // Too large for this device's buffers: the CPU has no such limit.
                        Err(e @ glint::gpu::GpuError::TooLarge { .. })
                            if backend == Backend::Auto =>
                        {
                            eprintln!("note: {e}; so the CPU tracer renders this");
                            cpu_bands(&buf, &mut sink, &mut frame, false)?;
                            glint::cpu::describe_f32()
                        }
                        Err(e) => return Err(e.into()),
                    }
                }
            };
            bar.finish();
            glint::stages::time("write", || sink.finish(&output))?;
            let t_wait = Instant::now();
            if cache.as_ref().is_some_and(|c| c.finish_writes() > 0) {
                glint::stages::record("cache wait", t_wait.elapsed());
            }
            print_cache_events(cache.as_deref(), verbose);
            println!(
                "{}: {}x{}, {} triangles ({}), {} spheres, {:.1} ms, {}",
                output.display(),
                w,
                h,
                buf.params.n_triangles,
                algo,
                buf.spheres.len(),
                frame.as_secs_f64() * 1e3,
                what
            );
            if verbose {
                glint::stages::record("trace", frame);
                let stages = glint::stages::take();
                let total: f64 = stages.iter().map(|(_, d)| d.as_secs_f64()).sum();
                for (name, d) in &stages {
                    eprintln!("  {name:<12} {:>8.1} ms", d.as_secs_f64() * 1e3);
                }
                eprintln!(
                    "  {:<12} {:>8.1} ms (stages), {:.1} ms since start",
                    "total",
                    total * 1e3,
                    start.elapsed().as_secs_f64() * 1e3
                );
            }
            Ok(())
        }
        Command::Bench {
            scenes,
            size,
            runs,
            out,
            common: CommonArgs { adapter, confine },
            no_gpu,
            triangle,
            samples,
        } => bench(
            scenes, size, triangle, samples, runs, out, adapter, no_gpu, confine,
        ),
        Command::Diff { a, b, diff } => {
            glint::image::check_extension(&diff)?;
            let (x, y) = (
                glint::image::Image::load_limited(&a, max_input_bytes())?,
                glint::image::Image::load_limited(&b, max_input_bytes())?,
            );
            if (x.width, x.height) != (y.width, y.height) {
                bail!(
                    "the images differ in size: {} is {}x{}, {} is {}x{}",
                    a.display(),
                    x.width,
                    x.height,
                    b.display(),
                    y.width,
                    y.height
                );
            }
            let d = glint::compare::diff(&x, &y);
            let exr = |p: &Path| glint::image::format_of(p).ok() == Some(glint::image::Format::Exr);
            println!(
                "{} against {}, {}x{}",
                a.display(),
                b.display(),
                x.width,
                x.height
            );
            println!(
                "{} differing pixels (8-bit), {} differing in some f32 bit, largest channel difference {:.3e} ({} in 8 bits), RMS {:.3e}",
                d.differing_pixels, d.differing_bits, d.max_abs, d.max_u8, d.rms
            );
            if exr(&a) && exr(&b) {
                println!(
                    "{} hit/miss disagreements, {} hits at a distance t that differs in some bit",
                    d.hit_miss, d.differing_t
                );
                println!(
                    "equal in every bit (colour, hit/miss, t): {}",
                    if d.bit_exact() { "yes" } else { "NO" }
                );
            } else {
                println!(
                    "(a PNG holds 8-bit colour only: hit/miss and t are compared between two EXRs)"
                );
            }
            glint::compare::diff_image(&x, &y).save(&diff)?;
            println!("difference image: {}", diff.display());
            Ok(())
        }
        Command::Adapters => {
            let list = glint::gpu::adapters();
            if list.is_empty() {
                bail!("{}", glint::gpu::GpuError::NoAdapter);
            }
            for a in list {
                let i = a.get_info();
                println!(
                    "{} ({:?}, {} {}): {}",
                    i.name,
                    i.device_type,
                    i.driver,
                    i.driver_info,
                    glint::gpu::exact::adapter_exactness(&a).describe()
                );
            }
            Ok(())
        }
        Command::Compare {
            scene,
            frame:
                FrameArgs {
                    size,
                    triangle,
                    samples,
                },
            common: CommonArgs { adapter, confine },
            diff,
        } => {
            glint::image::check_extension(&diff)?;
            let mut s = load(&scene, confine, None)?;
            s.camera.samples = samples.unwrap_or(s.camera.samples);
            let (w, h) = size.unwrap_or(s.size());
            let algo = triangle.unwrap_or(s.triangle);
            for w in s.range_warnings(algo) {
                eprintln!("warning: {w}");
            }
            // compare holds three whole f32 frames (GPU, CPU, f64) and a difference image.
            check_memory(w, h, w as u64 * h as u64 * 16 * 4)?;
            let buf = SceneBuffers::new(&s, w, h, algo);
            let spec = Specialisation::for_scene(&buf);
            let gpu = Gpu::with_options(&gpu_options(adapter.as_deref()))?;
            let (g, _) = gpu.compute_kernel(spec)?.render(
                &gpu.device,
                &gpu.queue,
                &buf,
                spec,
                &mut |_, _| {},
            )?;
            let c = glint::cpu::render_f32(&buf, spec);
            let r = glint::cpu::render_f64(&s, &buf, spec);
            let d = glint::compare::diff(&g, &c);
            let e = glint::compare::diff(&c, &r);
            println!("adapter: {}", gpu.describe());
            let kernel = gpu.compute_kernel(spec)?;
            println!(
                "scene: {} at {w}x{h}, triangles: {algo}, traversal: {}, {}",
                scene.display(),
                kernel.traversal_name(),
                kernel.exactness().describe()
            );
            println!(
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
            );
            println!(
                "gpu = cpu in every bit (colour, hit/miss, t): {}",
                if d.bit_exact() { "yes" } else { "NO" }
            );
            println!(
                "cpu f32 vs f64: {} differing pixels (8-bit), {} hit/miss, largest {:.3e}, rms {:.3e}",
                e.differing_pixels, e.hit_miss, e.max_abs, e.rms
            );
            // The ray-query tracer where the device has one: its hits are the driver's, so it
            // is measured against f64 beside the compute tracer, not asserted equal.
            let q = glint::compare::diff(&g, &r);
            let line = |name: &str, x: &glint::compare::Diff| {
                println!(
                    "{name} vs f64: {} hit/miss disagreements, largest channel error {:.3e}, rms {:.3e}, {} pixels off in 8 bits",
                    x.hit_miss, x.max_abs, x.rms, x.differing_pixels
                )
            };
            line("gpu", &q);
            match gpu.ray_query_kernel() {
                Ok(k) => {
                    let (rq, t) = k.render(&gpu.device, &gpu.queue, &buf, spec, &mut |_, _| {})?;
                    line("gpu-rq", &glint::compare::diff(&rq, &r));
                    println!(
                        "gpu-rq: acceleration structure {:.1} ms, trace {:.1} ms",
                        t.accel.as_secs_f64() * 1e3,
                        t.trace.as_secs_f64() * 1e3
                    );
                }
                Err(e) => println!("gpu-rq: not measured: {e}"),
            }
            glint::compare::diff_image(&g, &c)
                .save(&diff)
                .with_context(|| "writing the difference image")?;
            println!("difference image: {}", diff.display());
            Ok(())
        }
    }
}

#[allow(clippy::too_many_arguments)]
fn bench(
    scenes: Vec<PathBuf>,
    size: (u32, u32),
    triangle: Option<TriangleAlgorithm>,
    samples: Option<u32>,
    runs: usize,
    out: PathBuf,
    adapter: Option<String>,
    no_gpu: bool,
    confine: bool,
) -> Result<()> {
    if cfg!(debug_assertions) {
        eprintln!("warning: a debug build: build with --release for figures that mean anything");
    }
    let paths = if scenes.is_empty() {
        ["sphere", "triangle", "umbrella", "bb8", "mitsubishi"]
            .iter()
            .map(|s| PathBuf::from(format!("scenes/{s}.toml")))
            .collect()
    } else {
        scenes
    };
    let mut list = Vec::new();
    for p in &paths {
        let name = p
            .file_stem()
            .map(|s| s.to_string_lossy().into_owned())
            .unwrap_or_default();
        let mut s = load(p, confine, None)?;
        s.camera.samples = samples.unwrap_or(s.camera.samples);
        list.push((name, s));
    }
    let gpu = if no_gpu {
        None
    } else {
        Some(Gpu::with_options(&gpu_options(adapter.as_deref()))?)
    };
    let report = glint::bench::run(
        &list,
        Some(size),
        triangle,
        runs,
        gpu.as_ref(),
        &mut |done, total, label| {
            let width = 30;
            let filled = done * width / total.max(1);
            eprint!(
                "\r[{}{}] {done}/{total} {label:<30}",
                "#".repeat(filled),
                ".".repeat(width - filled)
            );
            if done == total {
                eprintln!();
            }
        },
    )?;
    std::fs::create_dir_all(&out).with_context(|| format!("creating {}", out.display()))?;
    let md = report.markdown();
    print!("{md}");
    std::fs::write(out.join("report.md"), &md)?;
    std::fs::write(
        out.join("report.json"),
        serde_json::to_string_pretty(&report)?,
    )?;
    report.plot().save(out.join("plot.png"))?;
    eprintln!(
        "wrote {0}/report.md, {0}/report.json, {0}/plot.png",
        out.display()
    );
    Ok(())
}

fn same_file(a: &Path, b: &Path) -> bool {
    match (a.canonicalize(), b.canonicalize()) {
        (Ok(x), Ok(y)) => x == y,
        _ => false,
    }
}

#[cfg(test)]
mod tests {
    use super::Backend;
    use clap::ValueEnum;

    /// The command line's backend names are the library's (`glint::Backend::NAMES`), each
    /// for the same backend, so `--backend` and a library user name a backend one way.
    #[test]
    fn cli_backend_names_are_the_librarys() {
        for b in Backend::value_variants() {
            let name = b
                .to_possible_value()
                .expect("a visible value")
                .get_name()
                .to_string();
            assert_eq!(
                name.parse::<glint::Backend>(),
                Ok(glint::Backend::from(*b)),
                "{name}"
            );
        }
        assert_eq!(Backend::value_variants().len(), glint::Backend::NAMES.len());
    }
}
