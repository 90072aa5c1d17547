//! Known answers on the CPU tracers, computed by hand from SPEC.md's formulas.

mod common;

use common::{buffers, seed_scene};
use glint::scene::{Scene, TriangleAlgorithm};

/// The sphere scene's centre pixel (801×601 so that pixel (400, 300) looks straight down
/// the view axis): the ray hits (0, 0, 1) at t = 4 with N = V = (0, 0, 1), the light is at
/// (−4, 4, 6), so N·L = R·V = 5/√57 and I = 0.2·ka + kd·(5/√57) + ks·(5/√57)^32.
#[test]
fn sphere_centre_pixel() {
    let scene = seed_scene("sphere");
    let (buf, spec) = buffers(&scene, 801, 601, scene.triangle);
    let ndl = 5.0 / 57f64.sqrt();
    let spec_term = ndl.powi(32);
    let want = [0.2 + ndl + spec_term, spec_term, spec_term];
    let k = 300 * 801 + 400;
    let f64_img = glint::cpu::render_f64(&scene, &buf, spec);
    let f32_img = glint::cpu::render_f32(&buf, spec);
    for c in 0..3 {
        assert!(
            (f64_img.pixels[k][c] as f64 - want[c]).abs() < 1e-6,
            "f64 channel {c}: {:?} vs {want:?}",
            f64_img.pixels[k]
        );
        assert!(
            (f32_img.pixels[k][c] as f64 - want[c]).abs() < 1e-5,
            "f32 channel {c}: {:?} vs {want:?}",
            f32_img.pixels[k]
        );
    }
    assert!(
        (f32_img.pixels[k][3] - 4.0).abs() < 1e-5,
        "t = {}",
        f32_img.pixels[k][3]
    );
}

/// A corner pixel misses and gets the background, with t = −1.
#[test]
fn miss_gets_background() {
    let src = std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/scenes/sphere.toml"))
        .unwrap();
    let src = src.replace(
        "background = [0.0, 0.0, 0.0]",
        "background = [0.25, 0.5, 0.75]",
    );
    let scene = Scene::parse(&src, "sphere-bg.toml".as_ref()).unwrap();
    let (buf, spec) = buffers(&scene, 80, 60, scene.triangle);
    for img in [
        glint::cpu::render_f32(&buf, spec),
        glint::cpu::render_f64(&scene, &buf, spec),
    ] {
        assert_eq!(img.pixels[0], [0.25, 0.5, 0.75, -1.0]);
    }
}

fn one_triangle(model: &str, extra: &str) -> Scene {
    let src = format!(
        r#"
ambient = [0.2, 0.4, 0.6]
[camera]
eye = [0.0, 0.0, 3.0]
look_at = [0.0, 0.0, 0.0]
fov = 60.0
width = 33
height = 33
[[lights]]
position = [0.0, 0.0, 3.0]
color = [1.0, 1.0, 1.0]
[materials.m]
model = "{model}"
ka = [0.5, 0.5, 0.5]
kd = [0.25, 0.5, 0.75]
ks = [1.0, 1.0, 1.0]
{extra}
[[triangles]]
vertices = [[-1.0, -1.0, 0.0], [1.0, -1.0, 0.0], [0.0, 1.0, 0.0]]
material = "m"
"#
    );
    Scene::parse(&src, "one-triangle.toml".as_ref()).unwrap()
}

/// An ambient material computes Ia·ka and nothing else, wherever it is hit.
#[test]
fn ambient_model_is_ambient_only() {
    let scene = one_triangle("ambient", "");
    for algo in TriangleAlgorithm::ALL {
        let (buf, spec) = buffers(&scene, 33, 33, algo);
        assert!(
            !spec.uses_diffuse && !spec.uses_phong,
            "ambient-only scene specialises the lighting away"
        );
        let img = glint::cpu::render_f32(&buf, spec);
        let centre = img.pixels[16 * 33 + 16];
        assert_eq!(
            &centre[..3],
            &[0.2f32 * 0.5, 0.4 * 0.5, 0.6 * 0.5],
            "{algo}"
        );
    }
}

/// Diffuse at normal incidence: the light on the axis gives N·L = 1 at the centre.
#[test]
fn diffuse_at_normal_incidence() {
    let scene = one_triangle("diffuse", "");
    let (buf, spec) = buffers(&scene, 33, 33, TriangleAlgorithm::MollerTrumbore);
    let img = glint::cpu::render_f64(&scene, &buf, spec);
    let c = img.pixels[16 * 33 + 16];
    let want = [0.1 + 0.25, 0.2 + 0.5, 1.0]; // blue: 0.3 + 0.75 clamps to 1
    for k in 0..3 {
        assert!((c[k] as f64 - want[k]).abs() < 1e-6, "{c:?} vs {want:?}");
    }
}

/// The exponent n = 0 makes the specular term ks·Ip (0^0 = 1, taken by squaring on both
/// tracers, where lavapipe's `pow(0, 0)` would give 0).
#[test]
fn phong_exponent_zero_is_one() {
    let scene = one_triangle("phong", "n = 0.0");
    let (buf, spec) = buffers(&scene, 33, 33, TriangleAlgorithm::MollerTrumbore);
    assert_eq!(buf.materials[0].n_int, 0);
    let img = glint::cpu::render_f32(&buf, spec);
    assert_eq!(
        &img.pixels[16 * 33 + 16][..3],
        &[1.0, 1.0, 1.0],
        "ambient + diffuse + 1 clamps to white"
    );
}
