//! The `glint` command line: `render`, `check`, `view`, `compare`, `diff`, `adapters`,
//! `bench`. It parses
//! the arguments, reads the environment once, draws the progress bar and prints; the
//! library ([`glint::render`]) does the work.

mod cli;

use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::time::Instant;

use anyhow::{Context, Result, bail};
use clap::Parser;
use cli::args::{Cli, Command, CommonArgs, FrameArgs};
use cli::env::{cache_settings, gpu_options, max_input_bytes};
use cli::progress::ProgressBar;
use glint::cache::Cache;
use glint::render::{Event, Job, Output};
use glint::scene::Scene;
use glint::scene::set::Setting;
use glint::{RenderOptions, Renderer};

fn main() {
    cli::alloc::fix_mmap_threshold();
    cli::env::quiet_driver();
    // SIGINT / SIGTERM: remove the half-written temporary image (the output file itself is
    // only ever replaced whole) and the cache entries' temporary files, then exit as
    // interrupted.
    let _ = ctrlc::set_handler(|| {
        glint::image::remove_pending_temp();
        glint::cache::remove_pending_temps();
        std::process::exit(130);
    });
    let cli = Cli::parse();
    if let Err(e) = cli::env::check() {
        eprintln!("error: {e}");
        std::process::exit(2);
    }
    // compare and diff keep 1 for "different": their errors exit 3 (usage errors: clap's 2).
    let verdict = matches!(cli.command, Command::Compare { .. } | Command::Diff { .. });
    // --threads: every parallel loop of the library runs in this process's one pool.
    let pool = cli.threads.map(|n| {
        rayon::ThreadPoolBuilder::new()
            .num_threads(n as usize)
            .build()
    });
    let result = match pool {
        Some(Ok(pool)) => pool.install(|| run(cli)),
        Some(Err(e)) => Err(anyhow::anyhow!("--threads: {e}")),
        None => run(cli),
    };
    match result {
        Ok(Verdict::Equal) => {}
        Ok(Verdict::Different) => std::process::exit(1),
        Err(e) => {
            eprintln!("error: {e:#}");
            std::process::exit(if verdict { 3 } else { 1 });
        }
    }
}

/// What a command found: compare and diff may find their images different.
enum Verdict {
    /// Success, or equal images.
    Equal,
    /// The images differ by the command's criterion (exit status 1).
    Different,
}

fn run(cli: Cli) -> Result<Verdict> {
    let done = |r: Result<()>| r.map(|()| Verdict::Equal);
    match cli.command {
        Command::Render {
            scene,
            output,
            verbose,
            quiet,
            backend,
            no_cache,
            encoding,
            frames,
            resume,
            frame,
            mut common,
        } => {
            if let Some(e) = encoding {
                common.set.push(format!("output.encoding={e}").parse()?);
            }
            let chatter = Chatter { verbose, quiet };
            match frames {
                Some(range) => {
                    let Some(template) = output else {
                        anyhow::bail!(
                            "--frames needs -o with {{}} or {{:04}} in the file name (out/frame_{{:04}}.png)"
                        )
                    };
                    let to = (template.as_path(), range, resume);
                    done(render_frames(
                        &scene, to, chatter, backend, no_cache, frame, common,
                    ))
                }
                None => {
                    let output = output.unwrap_or_else(|| default_output(&scene));
                    done(render(
                        &scene, &output, chatter, backend, no_cache, frame, common,
                    ))
                }
            }
        }
        Command::Check {
            scenes,
            confine,
            set,
        } => check(&scenes, confine, &set),
        Command::Compare {
            scene,
            frame,
            common,
            diff,
            tolerance,
        } => compare(&scene, frame, common, &diff, tolerance),
        Command::Diff {
            a,
            b,
            diff,
            tolerance,
        } => diff_images(&a, &b, &diff, tolerance),
        Command::Adapters => done(adapters()),
        Command::Completions { shell } => {
            let mut cmd = <Cli as clap::CommandFactory>::command();
            clap_complete::generate(shell, &mut cmd, "glint", &mut std::io::stdout());
            Ok(Verdict::Equal)
        }
        Command::Manpage => {
            let man = clap_mangen::Man::new(<Cli as clap::CommandFactory>::command());
            man.render(&mut std::io::stdout())?;
            Ok(Verdict::Equal)
        }
        #[cfg(feature = "view")]
        Command::View {
            scene,
            backend,
            size,
            samples,
            frames,
            screenshot,
            math,
            common,
        } => done(cli::view::run(cli::view::Options {
            scene,
            backend,
            size,
            samples,
            frames,
            screenshot,
            math: math.into(),
            adapter: common.adapter,
            load: glint::scene::LoadOptions {
                max_input_bytes: max_input_bytes(),
                confine: common.confine,
                cache: None,
                settings: common.set,
            },
        })),
        #[cfg(not(feature = "view"))]
        Command::View { .. } => Err(anyhow::anyhow!(
            "glint view: this glint was built without the viewer; build it with \
             `--features view` (cargo install --path . --features view)"
        )),
        Command::Stats {
            scene,
            size,
            triangle,
            json,
            common,
        } => {
            let s = load(&scene, common.confine, None, &common.set)?;
            let algo = triangle.unwrap_or(s.triangle);
            let buf = glint::buffers::SceneBuffers::new(&s, size.0, size.1, algo);
            let spec = glint::buffers::Specialisation::for_scene(&buf);
            let stats = glint::traversal_stats::traversal_stats(&buf, spec);
            if json {
                println!("{}", stats.to_json());
            } else {
                println!(
                    "{}: {}x{}, {} spheres, {} triangles, {} BVH nodes",
                    scene.display(),
                    size.0,
                    size.1,
                    buf.spheres.len(),
                    buf.triangles.len(),
                    buf.nodes.len()
                );
                print!("{stats}");
            }
            Ok(Verdict::Equal)
        }
        Command::Bench {
            scenes,
            size,
            runs,
            out,
            common,
            no_gpu,
            triangle,
            samples,
            max_depth,
            math,
        } => {
            let options = glint::bench::Options {
                size: Some(size),
                triangle,
                runs,
                backends: if no_gpu {
                    vec![glint::Backend::Cpu, glint::Backend::CpuF64]
                } else {
                    glint::bench::Options::default().backends
                },
                gpu: gpu_options(common.adapter.as_deref()),
                math: math.into(),
            };
            done(bench(
                scenes,
                samples,
                max_depth,
                &options,
                &load_options(common.confine, None, &common.set),
                &out,
            ))
        }
    }
}

/// The scene at `path`, read with the command line's limits, `cache` and `--set`
/// settings.
fn load(
    path: &Path,
    confine: bool,
    cache: Option<Arc<Cache>>,
    settings: &[Setting],
) -> Result<Scene> {
    Ok(Scene::load_with(
        path,
        &load_options(confine, cache, settings),
    )?)
}

fn load_options(
    confine: bool,
    cache: Option<Arc<Cache>>,
    settings: &[Setting],
) -> glint::scene::LoadOptions {
    glint::scene::LoadOptions {
        max_input_bytes: max_input_bytes(),
        confine,
        cache,
        settings: settings.to_vec(),
    }
}

/// Waits, when dropped, for the cache's entries still being written behind, so that the
/// next render finds them whatever happened to this one.
struct FinishWrites(Option<Arc<Cache>>);

impl Drop for FinishWrites {
    fn drop(&mut self) {
        if let Some(c) = &self.0 {
            let _ = c.finish_writes();
        }
    }
}

/// The cache `render` reads and writes (none with `--no-cache`), and the guard that waits
/// for its writes when dropped.
fn render_cache(no_cache: bool) -> (Option<Arc<Cache>>, FinishWrites) {
    let cache = glint::cache::default_dir()
        .filter(|_| !no_cache)
        .map(|dir| Arc::new(Cache::new(cache_settings(dir))));
    (cache.clone(), FinishWrites(cache))
}

fn options(frame: FrameArgs) -> RenderOptions {
    RenderOptions {
        size: frame.size,
        triangle: frame.triangle,
        samples: frame.samples,
        max_depth: frame.max_depth,
        math: frame.math.into(),
        inexact_driver: frame.inexact_driver,
        aovs: frame.aov.map(|a| a.0).unwrap_or_default(),
    }
}

/// `render`'s output when `-o` is absent: the scene's file name with `.png`, in the current
/// folder, as pbrt and Mitsuba derive theirs.
fn default_output(scene: &Path) -> PathBuf {
    let stem = scene.file_stem().unwrap_or(std::ffi::OsStr::new("glint"));
    PathBuf::from(stem).with_extension("png")
}

/// How much `render` prints besides warnings and errors.
#[derive(Clone, Copy)]
struct Chatter {
    /// Every stage's time.
    verbose: bool,
    /// Nothing: no summary, no notes, no progress bar.
    quiet: bool,
}

/// `glint check`: each scene read and validated as `render` reads it; the first error of
/// each is printed, and the status is 1 when any scene is bad.
fn check(scenes: &[PathBuf], confine: bool, settings: &[Setting]) -> Result<Verdict> {
    let mut bad = 0;
    for path in scenes {
        match load(path, confine, None, settings) {
            Ok(scene) => {
                for w in &scene.warnings {
                    eprintln!("warning: {w}");
                }
                let (t, s) = (scene.triangles.len(), scene.spheres.len());
                let plural = |n: usize| if n == 1 { "" } else { "s" };
                println!(
                    "{}: good ({t} triangle{}, {s} sphere{}, {} light{})",
                    path.display(),
                    plural(t),
                    plural(s),
                    scene.lights.len(),
                    plural(scene.lights.len())
                );
            }
            Err(e) => {
                bad += 1;
                eprintln!("error: {e:#}");
            }
        }
    }
    if bad > 0 {
        bail!(
            "{bad} of {} scene{} did not pass",
            scenes.len(),
            if scenes.len() == 1 { "" } else { "s" }
        );
    }
    Ok(Verdict::Equal)
}

fn render(
    scene: &Path,
    output: &Path,
    chatter: Chatter,
    backend: glint::Backend,
    no_cache: bool,
    frame: FrameArgs,
    common: CommonArgs,
) -> Result<()> {
    let start = Instant::now();
    let (cache, _finish) = render_cache(no_cache);
    // Before any work: the folder exists and a file can be made there.
    let output = Output::file(output)?;
    let scene = load(scene, common.confine, cache, &common.set)?;
    let renderer = Renderer::with_options(backend, &gpu_options(common.adapter.as_deref()))?;
    let bar = ProgressBar::new(Instant::now());
    let Chatter { verbose, quiet } = chatter;
    let report = Job::new(scene, output)
        .options(options(frame))
        .on_event(|e| match e {
            Event::Rows { .. } if quiet => {}
            Event::Rows { done, total } => bar.show(done, total),
            Event::Cache(_) if !verbose => {}
            Event::Note(_) if quiet => {}
            e => eprintln!("{e}"),
        })
        .run(&renderer);
    bar.finish();
    let report = report?;
    if !quiet {
        println!("{report}");
        for f in &report.aov_files {
            println!("{}", f.display());
        }
    }
    if verbose {
        let total: f64 = report.stages.iter().map(|(_, d)| d.as_secs_f64()).sum();
        for (name, d) in &report.stages {
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

/// `glint render --frames`: the scene loaded once, then each frame of its camera path.
fn render_frames(
    scene: &Path,
    (template, range, resume): (&Path, glint::render::FrameRange, bool),
    chatter: Chatter,
    backend: glint::Backend,
    no_cache: bool,
    frame: FrameArgs,
    common: CommonArgs,
) -> Result<()> {
    glint::render::check_template(template)?;
    glint::image::check_extension(template)?;
    let (cache, _finish) = render_cache(no_cache);
    let mut scene = load(scene, common.confine, cache, &common.set)?;
    if scene.camera_keys.is_empty() && !chatter.quiet {
        eprintln!(
            "note: {} has no [[camera.keys]]: every frame is [camera]'s",
            scene.path.display()
        );
    }
    let renderer = Renderer::with_options(backend, &gpu_options(common.adapter.as_deref()))?;
    let (mut written, mut kept) = (0u32, 0u32);
    glint::render::render_frames(
        &mut scene,
        &renderer,
        &options(frame),
        (template, range, resume),
        &mut |f, done| match done {
            glint::render::FrameDone::Written(path, report) => {
                written += 1;
                // The scene's warnings are every frame's: said once.
                if written == 1 {
                    for w in &report.warnings {
                        eprintln!("warning: {w}");
                    }
                }
                if !chatter.quiet {
                    println!(
                        "frame {f}: {} ({:.1} ms)",
                        path.display(),
                        report.total.as_secs_f64() * 1e3
                    );
                }
            }
            glint::render::FrameDone::Kept(path) => {
                kept += 1;
                if chatter.verbose {
                    println!("frame {f}: {} kept (--resume)", path.display());
                }
            }
        },
    )?;
    if !chatter.quiet {
        println!("{written} frames written, {kept} kept");
    }
    Ok(())
}

fn compare(
    scene: &Path,
    frame: FrameArgs,
    common: CommonArgs,
    diff: &Path,
    tolerance: glint::compare::Tolerance,
) -> Result<Verdict> {
    glint::image::check_extension(diff)?;
    let s = load(scene, common.confine, None, &common.set)?;
    let gpu = glint::gpu::Gpu::with_options(&gpu_options(common.adapter.as_deref()))?;
    let report = glint::render::compare(&s, &options(frame), &gpu)?;
    for w in &report.warnings {
        eprintln!("warning: {w}");
    }
    println!("{report}");
    report
        .difference
        .save(diff)
        .with_context(|| "writing the difference image")?;
    println!("difference image: {}", diff.display());
    // The AOVs count bit for bit whatever the tolerance: ids and hit masks have no
    // "close enough".
    let aovs_equal = report.aovs.iter().all(|(_, d)| d.differing == 0);
    Ok(verdict(
        report.gpu_vs_cpu.within(tolerance) && aovs_equal,
        tolerance,
    ))
}

/// The verdict line (equal by `tolerance`, or not) and the exit status it means.
fn verdict(equal: bool, tolerance: glint::compare::Tolerance) -> Verdict {
    println!(
        "equal by {tolerance}: {}",
        if equal { "yes" } else { "NO (exit status 1)" }
    );
    if equal {
        Verdict::Equal
    } else {
        Verdict::Different
    }
}

fn diff_images(
    a: &Path,
    b: &Path,
    diff: &Path,
    tolerance: glint::compare::Tolerance,
) -> Result<Verdict> {
    glint::image::check_extension(diff)?;
    let (x, y) = (
        glint::image::Image::load_limited(a, max_input_bytes())?,
        glint::image::Image::load_limited(b, max_input_bytes())?,
    );
    if (x.width, x.height) != (y.width, y.height) {
        println!(
            "the images differ in size: {} is {}x{}, {} is {}x{}",
            a.display(),
            x.width,
            x.height,
            b.display(),
            y.width,
            y.height
        );
        return Ok(verdict(false, tolerance));
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
    if exr(a) && exr(b) {
        println!(
            "{} hit/miss disagreements, {} hits at a distance t that differs in some bit",
            d.hit_miss, d.differing_t
        );
        println!(
            "equal in every bit (colour, hit/miss, t): {}",
            if d.bit_exact() { "yes" } else { "NO" }
        );
    } else {
        println!("(a PNG holds 8-bit colour only: hit/miss and t are compared between two EXRs)");
    }
    glint::compare::diff_image(&x, &y).save(diff)?;
    println!("difference image: {}", diff.display());
    Ok(verdict(d.within(tolerance), tolerance))
}

fn adapters() -> Result<()> {
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

fn bench(
    scenes: Vec<PathBuf>,
    samples: Option<u32>,
    max_depth: Option<u32>,
    options: &glint::bench::Options,
    load: &glint::scene::LoadOptions,
    out: &Path,
) -> Result<()> {
    if cfg!(debug_assertions) {
        eprintln!("warning: a debug build: build with --release for figures that mean anything");
    }
    let mut list = Vec::new();
    let mut add = |name: String, mut s: Scene| {
        for w in &s.warnings {
            eprintln!("warning: {w}");
        }
        s.camera.samples = samples.unwrap_or(s.camera.samples);
        s.max_depth = max_depth.unwrap_or(s.max_depth);
        list.push((name, s));
    };
    if scenes.is_empty() {
        // The seed scenes as shipped in the binary: `glint bench` works from any folder.
        for (name, text) in glint::bench::SEED_SCENES {
            let path = PathBuf::from(format!("scenes/{name}.toml"));
            add(name.to_string(), Scene::parse_options(text, &path, load)?);
        }
    }
    for p in &scenes {
        let name = p
            .file_stem()
            .map(|s| s.to_string_lossy().into_owned())
            .unwrap_or_default();
        add(name, Scene::load_with(p, load)?);
    }
    let report = glint::bench::run(&list, options, &mut |done, total, label| {
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
    })?;
    std::fs::create_dir_all(out).with_context(|| format!("creating {}", out.display()))?;
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
