//! The same scene renders the same bits every time: the CPU tracer with any thread count
//! and at sizes that leave partial packets and bands, a cold and a warm cache, and the GPU
//! tracer, on a hard case: the camera inside a closed triangulated sphere far from the
//! origin, traced with the naive triangle test, whose gaps at shared edges show the
//! background. A render that depended on scheduling, on the cache or on the run would show
//! here as a different count of those pixels.

mod common;

use std::path::{Path, PathBuf};

use glint::image::Image;

gpu_sentinel!();

/// A UV sphere of 2·250·250 triangles (more than the cache's least number of primitives,
/// so a render stores and reads it), placed by the scene far from the origin, and a scene
/// looking at its inside from its centre.
fn ball(dir: &Path) -> PathBuf {
    let n = 250usize;
    let mut obj = String::new();
    for i in 0..=n {
        let th = std::f64::consts::PI * i as f64 / n as f64;
        for j in 0..n {
            let ph = 2.0 * std::f64::consts::PI * j as f64 / n as f64;
            obj += &format!(
                "v {} {} {}\n",
                (th.sin() * ph.cos()) as f32,
                th.cos() as f32,
                (th.sin() * ph.sin()) as f32
            );
        }
    }
    let at = |i: usize, j: usize| i * n + j % n + 1;
    for i in 0..n {
        for j in 0..n {
            let (a, b, c, d) = (at(i, j), at(i, j + 1), at(i + 1, j), at(i + 1, j + 1));
            obj += &format!("f {a} {c} {b}\nf {b} {c} {d}\n");
        }
    }
    std::fs::write(dir.join("ball.obj"), obj).unwrap();
    let scene = dir.join("inside.toml");
    std::fs::write(
        &scene,
        r#"triangle = "naive"
ambient = [1.0, 1.0, 1.0]
background = [1.0, 0.0, 0.0]
[camera]
eye = [12345.6, -7654.3, 23456.7]
look_at = [12346.6, -7654.1, 23456.2]
fov = 60.0
width = 200
height = 150
[materials.m]
model = "ambient"
ka = [0.0, 0.0, 1.0]
[[meshes]]
file = "ball.obj"
material = "m"
scale = [3.0, 3.0, 3.0]
rotate = [10.0, 20.0, 30.0]
translate = [12345.6, -7654.3, 23456.7]
"#,
    )
    .unwrap();
    scene
}

/// `glint render SCENE ARGS -o OUT.exr`, read back.
fn render(dir: &Path, scene: &Path, out: &str, args: &[&str]) -> Image {
    let o = common::glint_command()
        .current_dir(dir)
        .env("GLINT_CACHE_DIR", dir.join("cache"))
        .arg("render")
        .arg(scene)
        .args(["-q", "-o", out])
        .args(args)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", common::status_and_text(&o).1);
    Image::load(&dir.join(out)).unwrap()
}

fn bits(img: &Image) -> Vec<u32> {
    img.pixels.iter().flatten().map(|x| x.to_bits()).collect()
}

fn misses(img: &Image) -> usize {
    img.pixels.len() - img.hit_count()
}

#[test]
fn cpu_renders_are_the_same_bits_every_time() {
    let d = common::Scratch::new("determinism-cpu");
    let scene = ball(&d);
    let cpu = ["--backend", "cpu"];
    let base = render(
        &d,
        &scene,
        "base.exr",
        &[&cpu[..], &["--no-cache"]].concat(),
    );
    // A hard case: the naive test leaves gaps, and most rays hit.
    let gaps = misses(&base);
    assert!(gaps > 0 && gaps < base.pixels.len() / 10, "{gaps} gaps");
    // A cold cache (stores), then a warm one (reads), twice.
    for run in ["cold.exr", "warm.exr", "warm2.exr"] {
        let img = render(&d, &scene, run, &cpu);
        assert_eq!(
            bits(&img),
            bits(&base),
            "{run}: {} gaps against {gaps}",
            misses(&img)
        );
    }
    // Thread counts, and sizes that leave partial packets, tiles and bands.
    for size in ["200x150", "201x149", "97x61"] {
        let first = render(
            &d,
            &scene,
            "size.exr",
            &[&cpu[..], &["--size", size]].concat(),
        );
        for threads in ["1", "2", "3", "7"] {
            let img = render(
                &d,
                &scene,
                "t.exr",
                &[&["--threads", threads][..], &cpu, &["--size", size]].concat(),
            );
            assert_eq!(bits(&img), bits(&first), "{size}, {threads} threads");
        }
    }
    // The twin: the comparison sees a change of one ulp in the camera.
    std::fs::write(
        d.join("moved.toml"),
        std::fs::read_to_string(&scene).unwrap().replacen(
            "12345.6, -7654.3, 23456.7]\nlook_at",
            "12345.601, -7654.3, 23456.7]\nlook_at",
            1,
        ),
    )
    .unwrap();
    let moved = render(
        &d,
        &d.join("moved.toml"),
        "moved.exr",
        &[&cpu[..], &["--no-cache"]].concat(),
    );
    assert_ne!(bits(&moved), bits(&base));
}

#[test]
fn gpu_renders_are_the_cpus_bits_every_time() {
    let Some(gpu) = common::gpu() else { return };
    let d = common::Scratch::new("determinism-gpu");
    let scene = ball(&d);
    let cpu = render(&d, &scene, "cpu.exr", &["--backend", "cpu", "--no-cache"]);
    let adapter = std::env::var("GLINT_ADAPTER").unwrap_or_default();
    for run in ["gpu1.exr", "gpu2.exr", "gpu3.exr"] {
        let img = render(
            &d,
            &scene,
            run,
            &["--backend", "gpu", "--adapter", &adapter],
        );
        // Exact math (the default): the mirror's bits on every driver.
        assert_eq!(bits(&img), bits(&cpu), "{run} on {}", gpu.describe());
    }
}
