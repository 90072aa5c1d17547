//! Directional and spot lights: exact answers where there is one (a directional light
//! straight down on a plane; a spot's full, soft and dark zones), shadows towards a light at
//! infinity, the keys' errors, the packet tracer and the GPU equal to the CPU mirror in
//! every bit on lavapipe, and point-light scenes untouched by the new code.

mod common;

gpu_sentinel!();

use common::{buffers, check_agreement, render_gpu};
use glint::buffers::Specialisation;
use glint::image::Image;
use glint::scene::{Scene, SceneError, TriangleAlgorithm};

fn parse(src: &str) -> Result<Scene, SceneError> {
    Scene::parse(src, std::path::Path::new("lights-test.toml"))
}

/// A white diffuse floor at y = 0 seen from straight above, lit by `light`, shadows on,
/// and (with `blocker`) a small sphere high above the floor's centre.
fn floor(light: &str, blocker: bool) -> Scene {
    let blocker = if blocker {
        "[[spheres]]\ncenter = [0.0, 50.0, 0.0]\nradius = 0.5\nmaterial = \"white\"\n"
    } else {
        ""
    };
    parse(&format!(
        "shadows = true\ntriangle = \"watertight\"\n[camera]\neye = [0.0, 10.0, 0.0]\nlook_at = [0.0, 0.0, 0.0]\nup = [0.0, 0.0, -1.0]\nfov = 90.0\nwidth = 41\nheight = 41\n\
         [materials.white]\nmodel = \"diffuse\"\nka = [0.0, 0.0, 0.0]\nkd = [1.0, 1.0, 1.0]\n\
         [[triangles]]\nvertices = [[-100.0, 0.0, -100.0], [100.0, 0.0, 100.0], [100.0, 0.0, -100.0]]\nmaterial = \"white\"\n\
         [[triangles]]\nvertices = [[-100.0, 0.0, -100.0], [-100.0, 0.0, 100.0], [100.0, 0.0, 100.0]]\nmaterial = \"white\"\n\
         {blocker}[[lights]]\n{light}\n"
    ))
    .unwrap_or_else(|e| panic!("{e}"))
}

fn render(scene: &Scene) -> (Image, Image) {
    let (buf, spec) = buffers(scene, 41, 41, scene.triangle);
    (
        glint::cpu::render_f32(&buf, spec),
        glint::cpu::render_f64(scene, &buf, spec),
    )
}

fn px(img: &Image, i: u32, j: u32) -> [f32; 4] {
    img.pixels[(j * img.width + i) as usize]
}

/// A directional light straight down gives kd·Ip·1 at every floor pixel: exactly the
/// colour, in f32 and f64. A blocker 50 units up shadows the centre (a shadow ray to
/// infinity), where a point light at 10 units would not be blocked by it. The twins: a
/// light at a slant gives less than the colour; without the blocker the centre is lit.
#[test]
fn a_directional_light_straight_down_is_exact_and_shadows_from_infinity() {
    let down = "kind = \"directional\"\ndirection = [0.0, -3.0, 0.0]\ncolor = [0.75, 0.5, 0.25]";
    let (c, r) = render(&floor(down, false));
    for img in [&c, &r] {
        for (i, j) in [(20, 20), (3, 5), (37, 30)] {
            assert_eq!(px(img, i, j)[..3], [0.75, 0.5, 0.25], "({i}, {j})");
        }
    }
    let (c, _) = render(&floor(down, true));
    assert_eq!(
        px(&c, 20, 20)[..3],
        [0.0, 0.0, 0.0],
        "the blocker at y = 50 shadows the centre"
    );
    assert_eq!(px(&c, 3, 5)[..3], [0.75, 0.5, 0.25], "not the corner");
    let point = "position = [0.0, 10.0, 0.0]\ncolor = [0.75, 0.5, 0.25]";
    let (c, _) = render(&floor(point, true));
    assert!(
        px(&c, 20, 20)[0] > 0.7,
        "a point light under the blocker is not blocked by it"
    );
    let slant = "kind = \"directional\"\ndirection = [1.0, -1.0, 0.0]\ncolor = [0.75, 0.5, 0.25]";
    let (c, _) = render(&floor(slant, false));
    let v = px(&c, 20, 20)[0];
    assert!((v as f64 - 0.75 * 0.5f64.sqrt()).abs() < 1e-6, "{v}");
}

/// A spot 10 units over the floor pointing down, angle 40°, falloff 20°: full light
/// inside 20° of the axis, none outside 40°, and between them kd·Ip·cos(i)·s²(3 − 2s) for
/// the f64 smoothstep of the cosines, to f32 rounding. The twin: a spot without falloff
/// is full right up to its edge.
#[test]
fn a_spot_is_full_soft_and_dark_where_it_should_be() {
    let spot = |falloff: f32| {
        floor(
            &format!(
                "kind = \"spot\"\nposition = [0.0, 10.0, 0.0]\ndirection = [0.0, -1.0, 0.0]\nangle = 40.0\nfalloff = {falloff:?}\ncolor = [1.0, 1.0, 1.0]"
            ),
            false,
        )
    };
    let (c, r) = render(&spot(20.0));
    // Pixel i along the centre row sees floor point x = (i + 0.5 - 20.5) / 20.5 · 10.
    let (mut full, mut soft, mut dark) = (0, 0, 0);
    for i in 0..41u32 {
        let x = ((i as f64 + 0.5) - 20.5) / 20.5 * 10.0;
        let d = (x * x + 100.0).sqrt();
        let cos = 10.0 / d; // to the axis, and the floor's incidence too
        let (o, inn) = (40f64.to_radians().cos(), 20f64.to_radians().cos());
        let want = if cos >= inn {
            full += 1;
            cos
        } else if cos <= o {
            dark += 1;
            0.0
        } else {
            soft += 1;
            let s = (cos - o) / (inn - o);
            cos * s * s * (3.0 - 2.0 * s)
        };
        for img in [&c, &r] {
            let got = px(img, i, 20)[0] as f64;
            assert!((got - want).abs() < 2e-6, "pixel {i}: {got} against {want}");
        }
    }
    assert!(full > 0 && soft > 0 && dark > 0, "{full} {soft} {dark}");
    let (hard, _) = render(&spot(0.0));
    let (soft_img, _) = render(&spot(20.0));
    assert_ne!(
        hard.pixels, soft_img.pixels,
        "the twin: no falloff, a hard edge"
    );
}

/// The packet tracer, the mirror and (on lavapipe, in every bit) the GPU agree on the
/// spot scene with each triangle algorithm, and on a smooth mesh lit by both new kinds.
#[test]
fn gpu_packet_and_mirror_agree_on_new_lights() {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/spot.toml");
    let scene = Scene::load(&path).unwrap();
    let gpu = common::gpu();
    for algo in TriangleAlgorithm::ALL {
        let (buf, spec) = buffers(&scene, 160, 120, algo);
        assert!(spec.light_kinds);
        let c = glint::cpu::render_f32(&buf, spec);
        let m = glint::cpu::render_f32_mirror(&buf, spec);
        assert!(
            glint::compare::diff(&c, &m).bit_exact(),
            "{algo}: packets against the mirror"
        );
        if let Some(gpu) = gpu {
            check_agreement(
                &render_gpu(gpu, &buf, spec),
                &c,
                common::bit_exact_expected(gpu),
            )
            .unwrap_or_else(|e| panic!("{algo}: {e}"));
        }
    }
    // The twin: the same scene with its spot made a point light differs.
    let point = Scene::parse(
        &std::fs::read_to_string(&path)
            .unwrap()
            .replacen("kind = \"spot\"", "", 1)
            .replacen(
                "direction = [0.0, -1.0, -0.1]\nangle = 40.0\nfalloff = 15.0\n",
                "",
                1,
            ),
        &path,
    )
    .unwrap();
    let (a, sa) = buffers(&scene, 160, 120, scene.triangle);
    let (b, sb) = buffers(&point, 160, 120, point.triangle);
    assert!(
        !glint::compare::diff(
            &glint::cpu::render_f32(&a, sa),
            &glint::cpu::render_f32(&b, sb)
        )
        .bit_exact()
    );
}

/// A point-light scene compiled with `LIGHT_KINDS` gives the image it gives without, in
/// every bit, on the CPU and the GPU: the new code leaves point lights' arithmetic as it
/// was, and such scenes compile none of it (`light_kinds` is off for them).
#[test]
fn point_lights_are_untouched() {
    for name in ["bb8-shadows", "mitsubishi-shadows", "whitted"] {
        let scene = common::seed_scene(name);
        let (buf, spec) = buffers(&scene, 96, 72, scene.triangle);
        assert!(!spec.light_kinds, "{name}");
        let on = Specialisation {
            light_kinds: true,
            ..spec
        };
        let today = glint::cpu::render_f32(&buf, spec);
        assert!(
            glint::compare::diff(&today, &glint::cpu::render_f32(&buf, on)).bit_exact(),
            "{name}"
        );
        assert!(
            glint::compare::diff(&today, &glint::cpu::render_f32_mirror(&buf, on)).bit_exact(),
            "{name}"
        );
        if let Some(gpu) = common::gpu() {
            let g = render_gpu(gpu, &buf, spec);
            let g_on = render_gpu(gpu, &buf, on);
            assert!(
                glint::compare::diff(&g, &g_on).bit_exact(),
                "{name} on the GPU"
            );
        }
    }
}

/// Each kind takes its keys and no others; bad values name file, line and key. The twin:
/// the good lights parse.
#[test]
fn light_keys_are_checked() {
    let base = "[camera]\neye = [0.0, 0.0, 5.0]\nlook_at = [0.0, 0.0, 0.0]\nfov = 45.0\nwidth = 8\nheight = 8\n[[lights]]\n";
    let ok = [
        "position = [1.0, 1.0, 1.0]\ncolor = [1.0, 1.0, 1.0]",
        "kind = \"directional\"\ndirection = [0.0, -1.0, 0.0]\ncolor = [1.0, 1.0, 1.0]",
        "kind = \"spot\"\nposition = [0.0, 1.0, 0.0]\ndirection = [0.0, -1.0, 0.0]\nangle = 30.0\ncolor = [1.0, 1.0, 1.0]",
    ];
    for l in ok {
        parse(&format!("{base}{l}\n")).unwrap_or_else(|e| panic!("{l}: {e}"));
    }
    let bad = [
        (
            "kind = \"area\"\nposition = [1.0, 1.0, 1.0]\ncolor = [1.0, 1.0, 1.0]",
            8,
            "lights[0].kind",
            "unknown kind \"area\"",
        ),
        (
            "kind = \"directional\"\ncolor = [1.0, 1.0, 1.0]",
            8,
            "lights[0].direction",
            "missing: a directional light needs it",
        ),
        (
            "kind = \"directional\"\nposition = [1.0, 1.0, 1.0]\ndirection = [0.0, -1.0, 0.0]\ncolor = [1.0, 1.0, 1.0]",
            8,
            "lights[0].position",
            "a directional light has none",
        ),
        (
            "kind = \"directional\"\ndirection = [0.0, 0.0, 0.0]\ncolor = [1.0, 1.0, 1.0]",
            9,
            "lights[0].direction",
            "has no direction",
        ),
        (
            "kind = \"spot\"\nposition = [0.0, 1.0, 0.0]\ndirection = [0.0, -1.0, 0.0]\ncolor = [1.0, 1.0, 1.0]",
            8,
            "lights[0].angle",
            "missing: a spot light needs it",
        ),
        (
            "kind = \"spot\"\nposition = [0.0, 1.0, 0.0]\ndirection = [0.0, -1.0, 0.0]\nangle = 95.0\ncolor = [1.0, 1.0, 1.0]",
            11,
            "lights[0].angle",
            "95 must be in (0, 90] degrees",
        ),
        (
            "kind = \"spot\"\nposition = [0.0, 1.0, 0.0]\ndirection = [0.0, -1.0, 0.0]\nangle = 30.0\nfalloff = 31.0\ncolor = [1.0, 1.0, 1.0]",
            12,
            "lights[0].falloff",
            "31 must be in [0, angle = 30] degrees",
        ),
        (
            "position = [1.0, 1.0, 1.0]\nangle = 30.0\ncolor = [1.0, 1.0, 1.0]",
            10,
            "lights[0].angle",
            "a point light has none",
        ),
    ];
    for (l, line, key, msg) in bad {
        let e = parse(&format!("{base}{l}\n")).expect_err(l);
        assert_eq!((e.line(), e.key()), (Some(line), Some(key)), "{e}");
        assert!(e.to_string().contains(msg), "{e}");
    }
}
