//! What smooth shading and antialiasing buy and cost, as a Markdown report:
//!
//! 1. accuracy: a unit icosphere subdivided k = 1..5 times, shaded flat and smooth,
//!    against the analytic unit sphere under the same light (largest and RMS channel error
//!    over the pixels both hit, and the silhouette pixels where only one hits);
//! 2. cost: frame time (median of `--runs`) against samples N on a seed scene, and flat
//!    against smooth on the bunny, on the CPU packet tracer and on the GPU (when present).
//!
//! `cargo run --release --example smooth_bench -- [--runs 5] [--no-gpu] [--out FILE]`

use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

use anyhow::{Context, Result};
use glint::buffers::{SceneBuffers, Specialisation};
use glint::gpu::Gpu;
use glint::image::Image;
use glint::scene::Scene;

const LIGHT: &str = "[[lights]]\nposition = [3.0, 4.0, 5.0]\ncolor = [0.9, 0.9, 0.9]\n";
const MATERIAL: &str = "[materials.m]\nmodel = \"phong\"\nka = [0.2, 0.2, 0.2]\nkd = [0.7, 0.6, 0.5]\nks = [0.4, 0.4, 0.4]\nn = 30.0\n";

fn camera(size: u32) -> String {
    format!(
        "[camera]\neye = [0.0, 0.0, 3.0]\nlook_at = [0.0, 0.0, 0.0]\nfov = 45.0\nwidth = {size}\nheight = {size}\n"
    )
}

fn load(dir: &Path, name: &str, text: &str) -> Result<Scene> {
    let path = dir.join(name);
    std::fs::write(&path, text)?;
    Scene::load(&path).with_context(|| path.display().to_string())
}

fn buffers(scene: &Scene) -> (SceneBuffers, Specialisation) {
    let (w, h) = scene.size();
    let buf = SceneBuffers::new(scene, w, h, scene.triangle);
    let spec = Specialisation::for_scene(&buf);
    (buf, spec)
}

/// (largest, RMS) channel error over the pixels both images hit, and the pixels only one hits.
fn error(img: &Image, reference: &Image) -> (f32, f64, usize) {
    let (mut max, mut sum, mut n, mut edge) = (0.0f32, 0.0f64, 0usize, 0usize);
    for (a, b) in img.pixels.iter().zip(&reference.pixels) {
        match (a[3] >= 0.0, b[3] >= 0.0) {
            (true, true) => {
                for c in 0..3 {
                    let d = (a[c] - b[c]).abs();
                    max = max.max(d);
                    sum += (d as f64) * (d as f64);
                    n += 3;
                }
            }
            (false, false) => {}
            _ => edge += 1,
        }
    }
    (max, (sum / n.max(1) as f64).sqrt(), edge)
}

fn median(mut v: Vec<Duration>) -> f64 {
    v.sort();
    v[v.len() / 2].as_secs_f64() * 1e3
}

/// Median frame time in ms on the CPU packet tracer and on the GPU (trace only).
fn frame_times(
    scene: &Scene,
    runs: usize,
    gpu: Option<&Gpu>,
    timing: bool,
) -> Result<(f64, Option<f64>)> {
    let (buf, spec) = buffers(scene);
    let _ = glint::cpu::render_f32(&buf, spec); // warm-up
    let cpu = median(
        (0..runs)
            .map(|_| {
                let t = Instant::now();
                std::hint::black_box(glint::cpu::render_f32(&buf, spec));
                t.elapsed()
            })
            .collect(),
    );
    let gpu_ms = match gpu.filter(|_| timing) {
        None => None,
        Some(g) => {
            g.compute_kernel(spec)?
                .render(&g.device, &g.queue, &buf, spec, &mut |_, _| {})?;
            let mut v = Vec::new();
            for _ in 0..runs {
                let (_, t) = g.compute_kernel(spec)?.render(
                    &g.device,
                    &g.queue,
                    &buf,
                    spec,
                    &mut |_, _| {},
                )?;
                v.push(t.trace);
            }
            Some(median(v))
        }
    };
    Ok((cpu, gpu_ms))
}

fn main() -> Result<()> {
    let args: Vec<String> = std::env::args().collect();
    let runs = args
        .iter()
        .position(|a| a == "--runs")
        .and_then(|k| args.get(k + 1))
        .map(|s| s.parse())
        .transpose()?
        .unwrap_or(5usize);
    let out = args
        .iter()
        .position(|a| a == "--out")
        .and_then(|k| args.get(k + 1))
        .map(PathBuf::from);
    let gpu = if args.iter().any(|a| a == "--no-gpu") {
        None
    } else {
        Some(Gpu::new(std::env::var("GLINT_ADAPTER").ok().as_deref())?)
    };
    let dir = std::env::temp_dir().join(format!("glint-smooth-bench-{}", std::process::id()));
    std::fs::create_dir_all(&dir)?;
    let mut md = String::new();
    let machine = format!(
        "{} CPU threads; GPU: {}",
        std::thread::available_parallelism().map_or(1, |n| n.get()),
        gpu.as_ref().map_or("none".into(), |g| g.describe())
    );
    md += &format!(
        "# Smooth shading and antialiasing: accuracy and cost\n\nMachine: {machine}. Release build; `cargo run --release --example smooth_bench`.\n\n"
    );

    // 1. Accuracy against the analytic sphere.
    let size = 512;
    let sphere = load(
        &dir,
        "sphere.toml",
        &format!(
            "ambient = [0.2, 0.2, 0.2]\n{}{LIGHT}{MATERIAL}[[spheres]]\ncenter = [0.0, 0.0, 0.0]\nradius = 1.0\nmaterial = \"m\"\n",
            camera(size)
        ),
    )?;
    let (sb, ss) = buffers(&sphere);
    let reference = glint::cpu::render_f32(&sb, ss);
    md += &format!(
        "## Icosphere against the analytic sphere ({size}×{size}, one light, Phong n = 30)\n\n"
    );
    md += "Error over the pixels that both the mesh and the sphere hit, colour channels in [0, 1]; \
           'silhouette' counts pixels that only one of them hits (the polygon outline: smooth \
           normals do not move it).\n\n";
    md += "| k | triangles | flat largest | flat RMS | smooth largest | smooth RMS | RMS flat / smooth | silhouette px |\n|---|---|---|---|---|---|---|---|\n";
    for k in 1..=5u32 {
        std::fs::write(dir.join("ico.obj"), glint::oracle::icosphere_obj(k))?;
        let mut row = Vec::new();
        let mut tris = 0;
        let mut edge = 0;
        for smooth in [false, true] {
            let s = load(
                &dir,
                "ico.toml",
                &format!(
                    "ambient = [0.2, 0.2, 0.2]\ntriangle = \"watertight\"\n{}{LIGHT}{MATERIAL}[[meshes]]\nfile = \"ico.obj\"\nmaterial = \"m\"\nsmooth = {smooth}\n",
                    camera(size)
                ),
            )?;
            tris = s.triangles.len();
            let (b, sp) = buffers(&s);
            let img = glint::cpu::render_f32(&b, sp);
            let (max, rms, e) = error(&img, &reference);
            edge = e;
            row.push((max, rms));
        }
        md += &format!(
            "| {k} | {tris} | {:.4} | {:.5} | {:.4} | {:.5} | {:.1}× | {edge} |\n",
            row[0].0,
            row[0].1,
            row[1].0,
            row[1].1,
            row[0].1 / row[1].1
        );
    }

    // 2. Cost.
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    md += &format!(
        "\n## Cost: frame time against samples (bb8, 800×600; median of {runs}, ms)\n\n\
         The CPU column is the packet tracer; the GPU column is the dispatches until the \
         device finished (no upload, compile or readback).\n\n| samples | rays | CPU | GPU |\n|---|---|---|---|\n"
    );
    let mut bb8 = Scene::load(root.join("scenes/bb8.toml"))?;
    for n in 1..=4u32 {
        bb8.camera.samples = n;
        let (cpu, g) = frame_times(&bb8, runs, gpu.as_ref(), true)?;
        md += &format!(
            "| {n}×{n} | {} | {cpu:.1} | {} |\n",
            n * n * 800 * 600,
            g.map_or("–".into(), |g| format!("{g:.1}"))
        );
    }
    let bunny = root.join("scenes/bunny.toml");
    if bunny.exists() && root.join("scenes/meshes/bunny_glmark2.obj.gz").exists() {
        md += &format!(
            "\n## Cost: flat against smooth (bunny, 69,666 triangles, 1024×768, one sample; median of {runs}, ms)\n\n| shading | load | CPU frame | GPU frame |\n|---|---|---|---|\n"
        );
        let text = std::fs::read_to_string(&bunny)?;
        for smooth in [false, true] {
            let t = text.replace(
                "material = \"porcelain\"\n",
                &format!("material = \"porcelain\"\nsmooth = {smooth}\n"),
            );
            let path = root.join("scenes/.smooth-bench.toml");
            std::fs::write(&path, t)?;
            let t0 = Instant::now();
            let s = Scene::load(&path);
            let load_ms = t0.elapsed().as_secs_f64() * 1e3;
            let _ = std::fs::remove_file(&path);
            let s = s?;
            let (cpu, g) = frame_times(&s, runs, gpu.as_ref(), true)?;
            md += &format!(
                "| {} | {load_ms:.0} | {cpu:.1} | {} |\n",
                if smooth { "smooth" } else { "flat" },
                g.map_or("–".into(), |g| format!("{g:.1}"))
            );
        }
    } else {
        md += "\n(The bunny rows need `bash scenes/fetch-meshes.sh`.)\n";
    }
    let _ = std::fs::remove_dir_all(&dir);
    match out {
        Some(p) => std::fs::write(&p, &md)?,
        None => print!("{md}"),
    }
    Ok(())
}
