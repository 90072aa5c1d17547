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
    let diff = |x: &std::path::Path, y: &std::path::Path| run_diff(&d, x, y, &[]);
    // CPU here against the GPU (lavapipe: bit for bit) as if rendered elsewhere.
    let (code, same) = diff(&a, &b);
    if common::gpu().is_none_or(common::bit_exact_expected) {
        assert!(
            same.contains("equal in every bit (colour, hit/miss, t): yes"),
            "{same}"
        );
        assert_eq!(code, Some(0), "{same}");
    }
    // The twin: another triangle algorithm moves some t and edges, and the status says so.
    let (code, other) = diff(&a, &c);
    assert!(
        other.contains("equal in every bit (colour, hit/miss, t): NO"),
        "{other}"
    );
    assert_eq!(code, Some(1), "{other}");
}

/// `glint diff A B --diff d.png [extra]`: its exit status and standard output.
fn run_diff(
    d: &common::Scratch,
    x: &std::path::Path,
    y: &std::path::Path,
    extra: &[&str],
) -> (Option<i32>, String) {
    let o = common::glint_command()
        .args(["diff", x.to_str().unwrap(), y.to_str().unwrap(), "--diff"])
        .arg(d.join("d.png"))
        .args(extra)
        .output()
        .unwrap();
    common::status_and_text(&o)
}

#[test]
fn diff_exit_status_is_the_verdict_by_the_tolerance_asked() {
    let d = dir("status");
    let scene = common::seed_scene("sphere");
    let buf = SceneBuffers::new(&scene, 32, 24, scene.triangle);
    let img = glint::cpu::render_f32(&buf, Specialisation::for_scene(&buf));
    let a = d.join("a.exr");
    img.save(&a).unwrap();
    // One colour channel one f32 step up: unequal in bits, equal in 8 bits and by 1e-3.
    let mut near = img.clone();
    let i = near.pixels.iter().position(|p| p[3] >= 0.0).unwrap();
    near.pixels[i] = [0.25, 0.25, 0.25, near.pixels[i][3]];
    let mut nearer = near.clone();
    nearer.pixels[i][0] = f32::from_bits(0.25f32.to_bits() + 1);
    let (b, c) = (d.join("b.exr"), d.join("c.exr"));
    near.save(&b).unwrap();
    nearer.save(&c).unwrap();
    let status = |x: &std::path::Path, y: &std::path::Path, extra: &[&str]| {
        let (code, out) = run_diff(&d, x, y, extra);
        assert!(code.is_some(), "{out}");
        (code.unwrap(), out)
    };
    assert_eq!(status(&a, &a, &[]).0, 0);
    assert_eq!(status(&b, &b, &["--tolerance", "bits"]).0, 0);
    let (code, out) = status(&b, &c, &[]);
    assert_eq!(code, 1, "{out}");
    assert!(out.contains("NO (exit status 1)"), "{out}");
    assert_eq!(status(&b, &c, &["--tolerance", "8bit"]).0, 0);
    assert_eq!(status(&b, &c, &["--tolerance", "1e-3"]).0, 0);
    // The twin of the tolerance: zero allowed, one step found.
    assert_eq!(status(&b, &c, &["--tolerance", "0"]).0, 1);
    // A hit turned into a miss is unequal by every tolerance.
    let mut missed = near.clone();
    missed.pixels[i][3] = -1.0;
    let m = d.join("m.exr");
    missed.save(&m).unwrap();
    for t in ["bits", "8bit", "1e9"] {
        assert_eq!(status(&b, &m, &["--tolerance", t]).0, 1, "{t}");
    }
    // Images of different sizes differ.
    let small_buf = SceneBuffers::new(&scene, 16, 12, scene.triangle);
    let small = glint::cpu::render_f32(&small_buf, Specialisation::for_scene(&small_buf));
    let s = d.join("s.exr");
    small.save(&s).unwrap();
    assert_eq!(status(&a, &s, &[]).0, 1);
    // Usage errors are clap's 2; a file that cannot be read is a runtime error, 3.
    let (code, out) = status(&a, &b, &["--tolerance", "banana"]);
    assert_eq!(code, 2, "{out}");
    assert!(out.contains("banana"), "{out}");
    let (code, out) = status(&a, &d.join("absent.exr"), &[]);
    assert_eq!(code, 3, "{out}");
    assert!(out.contains("absent.exr"), "{out}");
}
