//! Known answers on the CPU tracers, computed by hand from the formulas of docs/scene-format.md.

mod common;

gpu_sentinel!();

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
    one_triangle_lit(model, extra, [0.0, 0.0, 3.0])
}

fn one_triangle_lit(model: &str, extra: &str, light: [f64; 3]) -> Scene {
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
position = {light:?}
color = [1.0, 1.0, 1.0]
[materials.m]
model = "{model}"
ka = [0.5, 0.5, 0.5]
kd = [0.25, 0.5, 0.75]
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
/// tracers, where lavapipe's `pow(0, 0)` would give 0): evaluated where R·V ≤ 0, so the
/// base really is 0. A light far to the right and low over the triangle reflects away from
/// the camera on the triangle's left half.
#[test]
fn phong_exponent_zero_is_one() {
    let light = [10.0f64, 0.0, 0.1];
    let scene = one_triangle_lit("phong", "ks = [0.5, 0.5, 0.5]\nn = 0.0", light);
    let (buf, spec) = buffers(&scene, 33, 33, TriangleAlgorithm::MollerTrumbore);
    assert_eq!(buf.materials[0].n_int, 0);
    let img = glint::cpu::render_f32(&buf, spec);
    // Pixel (12, 16): the ray from (0, 0, 3) meets z = 0 at x ≈ −0.42, y = 0 (to an ulp).
    let px = img.pixels[16 * 33 + 12];
    let t = px[3] as f64;
    assert!(t > 0.0, "pixel (12, 16) must hit the triangle");
    let x = -(t * t - 9.0).sqrt();
    let p = [x, 0.0, 0.0];
    let norm = |v: [f64; 3]| {
        let l = (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
        [v[0] / l, v[1] / l, v[2] / l]
    };
    let l = norm([light[0] - p[0], light[1] - p[1], light[2] - p[2]]);
    let v = norm([-p[0], -p[1], 3.0 - p[2]]);
    let ndl = l[2];
    let r = [-l[0], -l[1], 2.0 * ndl - l[2]];
    let rv = r[0] * v[0] + r[1] * v[1] + r[2] * v[2];
    assert!(
        ndl > 0.0 && rv < -0.1,
        "the pixel must have N·L > 0 and R·V < 0: {ndl} {rv}"
    );
    // Ia·ka + kd·(N·L) + ks·0^0, with 0^0 = 1. (0^0 = 0 would leave out 0.5.)
    let want = [0.2 * 0.5, 0.4 * 0.5, 0.6 * 0.5].map(|a| a + 0.5);
    let kd = [0.25, 0.5, 0.75];
    for k in 0..3 {
        let w = want[k] + kd[k] * ndl;
        assert!(
            (px[k] as f64 - w).abs() < 1e-4,
            "channel {k}: {px:?}, want {w}"
        );
    }
    if let Some(gpu) = common::gpu() {
        let g = common::render_gpu(gpu, &buf, spec);
        common::check_agreement(&g, &img, common::bit_exact_expected(gpu)).unwrap();
    }
}

/// The twin: with a nonzero exponent the same pixel has no specular term at all (R·V < 0),
/// so the 0^0 check above is really what decides that pixel.
#[test]
fn phong_exponent_one_at_the_same_pixel_has_no_highlight() {
    let light = [10.0f64, 0.0, 0.1];
    let scene = one_triangle_lit("phong", "ks = [0.5, 0.5, 0.5]\nn = 1.0", light);
    let (buf, spec) = buffers(&scene, 33, 33, TriangleAlgorithm::MollerTrumbore);
    let img = glint::cpu::render_f32(&buf, spec);
    let px = img.pixels[16 * 33 + 12];
    assert!(px[0] < 0.2, "no specular term where R·V < 0: {px:?}");
}
