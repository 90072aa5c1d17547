//! Float output and image diffs: an EXR holds the f32 image exactly (t in alpha), and
//! `glint diff` finds two EXRs equal in every bit, or says how they differ.

mod common;

gpu_sentinel!();

use glint::buffers::{SceneBuffers, Specialisation};
use glint::image::Image;

fn dir(name: &str) -> common::Scratch {
    common::Scratch::new(&format!("exr-{name}"))
}

#[test]
fn exr_round_trips_every_bit() {
    let scene = common::seed_scene("bb8-shadows");
    let buf = SceneBuffers::new(&scene, 160, 120, scene.triangle);
    let mut img = glint::cpu::render_f32(&buf, Specialisation::for_scene(&buf));
    assert!(
        img.pixels.iter().any(|p| p[3] < 0.0),
        "misses (t = -1) are part of the test"
    );
    // Values a PNG could never hold: subnormal, above 1, negative zero.
    img.pixels[0] = [1e-40, 3.5, -0.0, 1e30];
    let d = dir("round");
    let path = d.join("round.exr");
    img.save(&path).unwrap();
    let back = Image::load(&path).unwrap();
    assert_eq!((back.width, back.height), (160, 120));
    let bits = |i: &Image| -> Vec<u32> { i.pixels.iter().flatten().map(|x| x.to_bits()).collect() };
    assert_eq!(bits(&back), bits(&img));
}

#[test]
fn glint_diff_says_equal_or_how_two_renders_differ() {
    let d = dir("diff");
    let render = |name: &str, extra: &[&str]| {
        let out = d.join(name);
        let scene = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/umbrella.toml");
        let o = common::glint_command()
            .args([
                "render",
                scene.to_str().unwrap(),
                "-o",
                out.to_str().unwrap(),
                "--size",
                "128x96",
            ])
            .args(extra)
            .output()
            .unwrap();
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        out
    };
    let a = render("a.exr", &["--backend", "cpu"]);
    // The GPU the tests use (GLINT_ADAPTER), or the CPU again when GPU tests are skipped.
    let adapter = std::env::var("GLINT_ADAPTER").unwrap_or_default();
    let args: Vec<&str> = match common::gpu() {
        Some(_) if adapter.is_empty() => vec!["--backend", "gpu"],
        Some(_) => vec!["--backend", "gpu", "--adapter", &adapter],
        None => vec!["--backend", "cpu"],
    };
    let b = render("b.exr", &args);
    let c = render("c.exr", &["--backend", "cpu", "--triangle", "naive"]);
    let diff = |x: &std::path::Path, y: &std::path::Path| {
        let o = common::glint_command()
            .args(["diff", x.to_str().unwrap(), y.to_str().unwrap(), "--diff"])
            .arg(d.join("d.png"))
            .output()
            .unwrap();
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        String::from_utf8_lossy(&o.stdout).into_owned()
    };
    // CPU here against the GPU (lavapipe: bit for bit) as if rendered elsewhere.
    let same = diff(&a, &b);
    if common::gpu().is_none_or(common::is_lavapipe) {
        assert!(
            same.contains("equal in every bit (colour, hit/miss, t): yes"),
            "{same}"
        );
    }
    // The twin: another triangle algorithm moves some t and edges.
    let other = diff(&a, &c);
    assert!(
        other.contains("equal in every bit (colour, hit/miss, t): NO"),
        "{other}"
    );
}
