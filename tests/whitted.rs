//! Whitted's secondary rays (`shaders/whitted.wgsl`, `src/cpu/whitted.rs`): exact answers
//! where the model has one, the mirror and the lens doing what optics says, spawned rays
//! that never find their own surface, the cuts of `max_depth` and `min_weight`, the scene
//! keys' errors, and the GPU equal to its CPU mirror. Each check has a twin that fails.

mod common;

gpu_sentinel!();

use common::{Rng, buffers, check_agreement, render_gpu};
use glint::buffers::{RayIn, SceneBuffers, Specialisation};
use glint::image::Image;
use glint::scene::{Scene, TriangleAlgorithm};

fn parse(src: &str) -> Scene {
    Scene::parse(src, std::path::Path::new("whitted-test.toml")).unwrap_or_else(|e| panic!("{e}"))
}

fn f32_and_f64(scene: &Scene, w: u32, h: u32) -> (Image, Image, SceneBuffers, Specialisation) {
    let (buf, spec) = buffers(scene, w, h, scene.triangle);
    let c = glint::cpu::render_f32(&buf, spec);
    let r = glint::cpu::render_f64(scene, &buf, spec);
    (c, r, buf, spec)
}

/// A square of side 20 at z = `z`, as two triangles of material `m`.
fn wall_z(z: f32, m: &str) -> String {
    format!(
        "[[triangles]]\nvertices = [[-10.0, -10.0, {z:?}], [10.0, -10.0, {z:?}], [10.0, 10.0, {z:?}]]\nmaterial = \"{m}\"\n\
         [[triangles]]\nvertices = [[-10.0, -10.0, {z:?}], [10.0, 10.0, {z:?}], [-10.0, 10.0, {z:?}]]\nmaterial = \"{m}\"\n"
    )
}

/// Two facing ambient mirrors with ka = kr = ½ under Ia = 1, the camera between them on
/// their axis: the centre pixel is 1 − ½^(D+1) exactly, for max_depth D. Watertight, so
/// that the rays along the diagonal the two triangles of each wall share hit on every
/// adapter (a GPU's division may let Möller–Trumbore's through).
fn hall(depth: u32, min_weight: f32) -> Scene {
    parse(&format!(
        "ambient = [1.0, 1.0, 1.0]\ntriangle = \"watertight\"\nmax_depth = {depth}\nmin_weight = {min_weight:?}\n\
         [camera]\neye = [0.0, 0.0, 0.0]\nlook_at = [0.0, 0.0, -1.0]\nfov = 30.0\nwidth = 9\nheight = 9\n\
         [materials.m]\nmodel = \"ambient\"\nka = [0.5, 0.5, 0.5]\nkr = [0.5, 0.5, 0.5]\n{}{}",
        wall_z(-1.0, "m"),
        wall_z(1.0, "m")
    ))
}

fn centre(img: &Image) -> [f32; 4] {
    img.pixels[(img.height / 2 * img.width + img.width / 2) as usize]
}

#[test]
fn hall_of_mirrors_sums_exactly() {
    for d in 0..=12u32 {
        let (c, r, buf, spec) = f32_and_f64(&hall(d, 0.0), 9, 9);
        let want = 1.0 - 0.5f64.powi(d as i32 + 1);
        assert_eq!(centre(&c)[0] as f64, want, "f32, max_depth {d}");
        assert_eq!(centre(&r)[0] as f64, want, "f64, max_depth {d}");
        assert_eq!(
            spec.whitted,
            d > 0,
            "WHITTED is compiled in only where it can act"
        );
        if let Some(gpu) = common::gpu() {
            let g = render_gpu(gpu, &buf, spec);
            check_agreement(&g, &c, common::bit_exact_expected(gpu))
                .unwrap_or_else(|e| panic!("max_depth {d}: {e}"));
        }
    }
    // The twin: the same walls with kr = 0 stop at the first hit.
    let flat = parse(&format!(
        "ambient = [1.0, 1.0, 1.0]\n[camera]\neye = [0.0, 0.0, 0.0]\nlook_at = [0.0, 0.0, -1.0]\n\
         fov = 30.0\nwidth = 9\nheight = 9\n[materials.m]\nmodel = \"ambient\"\nka = [0.5, 0.5, 0.5]\n{}{}",
        wall_z(-1.0, "m"),
        wall_z(1.0, "m")
    ));
    assert_eq!(centre(&f32_and_f64(&flat, 9, 9).0)[0], 0.5);
}

/// `min_weight` = 1/255 stops the walk where the weight ½^k falls below it (k = 8), and
/// the light it drops is at most min_weight × the largest radiance (1 here).
#[test]
fn min_weight_cuts_where_it_should() {
    let cut = centre(&f32_and_f64(&hall(12, 1.0 / 255.0), 9, 9).0)[0] as f64;
    assert_eq!(cut, 1.0 - 0.5f64.powi(8));
    let full = 1.0 - 0.5f64.powi(13);
    assert!(full - cut <= 1.0 / 255.0, "{}", full - cut);
    // The twin: with min_weight 0 nothing is cut.
    assert_eq!(centre(&f32_and_f64(&hall(12, 0.0), 9, 9).0)[0] as f64, full);
}

/// The scene for the planar mirror: a ball over a black perfect mirror at y = 0, or (with
/// `mirrored`) the ball and light reflected in y and no floor; `light_y` the light's height.
fn mirror_scene(mirrored: bool, floor_kr: f32, light_y: f32) -> Scene {
    let s = if mirrored { -1.0f32 } else { 1.0 };
    let floor = if mirrored {
        String::new()
    } else {
        "[[triangles]]\nvertices = [[-50.0, 0.0, -50.0], [-50.0, 0.0, 50.0], [50.0, 0.0, 50.0]]\nmaterial = \"floor\"\n\
         [[triangles]]\nvertices = [[-50.0, 0.0, -50.0], [50.0, 0.0, 50.0], [50.0, 0.0, -50.0]]\nmaterial = \"floor\"\n"
            .to_string()
    };
    parse(&format!(
        "ambient = [0.1, 0.1, 0.1]\nmax_depth = 1\nmin_weight = 0.0\n\
         [camera]\neye = [0.0, 1.0, 6.0]\nlook_at = [0.0, 0.2, 0.0]\nfov = 40.0\nwidth = 64\nheight = 64\n\
         [[lights]]\nposition = [2.0, {:?}, 3.0]\ncolor = [1.0, 1.0, 1.0]\n\
         [materials.ball]\nmodel = \"phong\"\nka = [1.0, 1.0, 1.0]\nkd = [0.7, 0.5, 0.3]\nks = [0.5, 0.5, 0.5]\nn = 20.0\n\
         [materials.floor]\nmodel = \"ambient\"\nka = [0.0, 0.0, 0.0]\nkr = [{floor_kr:?}, {floor_kr:?}, {floor_kr:?}]\n\
         [[spheres]]\ncenter = [0.0, {:?}, 0.0]\nradius = 0.6\nmaterial = \"ball\"\n{floor}",
        light_y,
        s * 1.0
    ))
}

/// A ball over a black perfect mirror: in the floor's pixels the image is what the
/// mirrored scene (ball and light reflected, no floor) shows directly (f64, so only the
/// reflection's rounding separates them).
#[test]
fn planar_mirror_shows_the_mirrored_scene() {
    let f64_of = |s: &Scene| f32_and_f64(s, 64, 64).1;
    let a = f64_of(&mirror_scene(false, 1.0, 5.0));
    let black = f64_of(&mirror_scene(false, 0.0, 5.0));
    let compare = |b: &Image| {
        let (mut floor_ball, mut off) = (0, 0);
        for k in 0..a.pixels.len() {
            let on_floor = black.pixels[k][3] >= 0.0 && black.pixels[k][..3] == [0.0; 3];
            if on_floor && b.pixels[k][3] >= 0.0 {
                floor_ball += 1;
                let e = (0..3)
                    .map(|c| (a.pixels[k][c] - b.pixels[k][c]).abs())
                    .fold(0.0, f32::max);
                off += (e > 1e-5) as usize;
            }
        }
        (floor_ball, off)
    };
    let (n, off) = compare(&f64_of(&mirror_scene(true, 0.0, -5.0)));
    assert!(n > 50, "the reflection must cover pixels: {n}");
    assert!(
        off <= 2,
        "{off} of {n} floor pixels differ from the mirrored scene"
    );
    // The twin: the light not reflected lights the mirrored ball from below.
    let (n, off) = compare(&f64_of(&mirror_scene(true, 0.0, 5.0)));
    assert!(off > n / 2, "{off} of {n}");
}

/// A glass ball (ior 1.5, kt = 1) in front of a far wall, red above y = 0.5 and green
/// below: the ray through the centre is not deviated (the centre pixel is the wall's green,
/// as without the ball), and what lies behind is turned upside down.
#[test]
fn glass_ball_lens_inverts_and_keeps_the_axis() {
    let scene = |ball: bool| {
        let sphere = if ball {
            "[[spheres]]\ncenter = [0.0, 0.0, 0.0]\nradius = 1.0\nmaterial = \"glass\"\n"
        } else {
            ""
        };
        parse(&format!(
            "ambient = [1.0, 1.0, 1.0]\nbackground = [0.0, 0.0, 1.0]\nmax_depth = 4\nmin_weight = 0.0\n\
             [camera]\neye = [0.0, 0.0, 5.0]\nlook_at = [0.0, 0.0, 0.0]\nfov = 20.0\nwidth = 33\nheight = 33\n\
             [materials.glass]\nmodel = \"ambient\"\nka = [0.0, 0.0, 0.0]\nkt = [1.0, 1.0, 1.0]\nior = 1.5\n\
             [materials.red]\nmodel = \"ambient\"\nka = [1.0, 0.0, 0.0]\n\
             [materials.green]\nmodel = \"ambient\"\nka = [0.0, 1.0, 0.0]\n\
             [[triangles]]\nvertices = [[-300.0, 0.5, -40.0], [300.0, 0.5, -40.0], [300.0, 300.0, -40.0]]\nmaterial = \"red\"\n\
             [[triangles]]\nvertices = [[-300.0, 0.5, -40.0], [300.0, 300.0, -40.0], [-300.0, 300.0, -40.0]]\nmaterial = \"red\"\n\
             [[triangles]]\nvertices = [[-300.0, -300.0, -40.0], [300.0, -300.0, -40.0], [300.0, 0.5, -40.0]]\nmaterial = \"green\"\n\
             [[triangles]]\nvertices = [[-300.0, -300.0, -40.0], [300.0, 0.5, -40.0], [-300.0, 0.5, -40.0]]\nmaterial = \"green\"\n\
             {sphere}"
        ))
    };
    let px = |img: &Image, i: u32, j: u32| img.pixels[(j * 33 + i) as usize];
    for img in [
        f32_and_f64(&scene(true), 33, 33).0,
        f32_and_f64(&scene(true), 33, 33).1,
    ] {
        assert_eq!(
            px(&img, 16, 16)[..3],
            [0.0, 1.0, 0.0],
            "the axis is not deviated"
        );
        assert_eq!(
            px(&img, 16, 16)[3],
            4.0,
            "the centre ray meets the ball at t = 4"
        );
        assert_eq!(
            px(&img, 16, 12)[..3],
            [0.0, 1.0, 0.0],
            "above the axis: the lower half"
        );
        assert_eq!(
            px(&img, 16, 20)[..3],
            [1.0, 0.0, 0.0],
            "below the axis: the upper half"
        );
    }
    // The twin: without the ball, above is above.
    let bare = f32_and_f64(&scene(false), 33, 33).0;
    assert_eq!(px(&bare, 16, 16)[..3], [0.0, 1.0, 0.0]);
    assert_eq!(px(&bare, 16, 12)[..3], [1.0, 0.0, 0.0]);
    assert_eq!(px(&bare, 16, 20)[..3], [0.0, 1.0, 0.0]);
}

/// pbrt's `Reintersect`, for secondary rays: a random triangle or sphere of glass and
/// mirror (kr = kt = ½), hit by a random ray from outside (and, for spheres, from inside);
/// the reflected and transmitted rays that leave it, traced against it again, never find
/// the surface they left: a triangle is missed, a sphere is missed from outside and met
/// from inside only across a chord, never near the origin. Near the origin and at 10⁴.
#[test]
fn spawned_rays_never_find_their_own_surface() {
    let mut rng = Rng::new(0x5eed_3517);
    let (mut rays, mut grazing) = (0, 0);
    for trial in 0..3000 {
        let offset = if trial % 2 == 0 { 0.0 } else { 1.0e4 };
        let sphere = trial % 3 != 0;
        let inside = sphere && trial % 3 == 2;
        let o = [
            rng.range(-1.0, 1.0) + offset,
            rng.range(-1.0, 1.0),
            rng.range(-1.0, 1.0),
        ];
        let (prim, target, radius) = if sphere {
            let r = rng.range(0.05, 3.0);
            (
                format!(
                    "[[spheres]]\ncenter = [{:?}, {:?}, {:?}]\nradius = {r:?}\nmaterial = \"g\"\n",
                    o[0], o[1], o[2]
                ),
                o,
                r,
            )
        } else {
            let v = |rng: &mut Rng| {
                [
                    o[0] + rng.range(-2.0, 2.0),
                    o[1] + rng.range(-2.0, 2.0),
                    o[2] + rng.range(-2.0, 2.0),
                ]
            };
            let (a, b, c) = (v(&mut rng), v(&mut rng), v(&mut rng));
            let centroid = [
                (a[0] + b[0] + c[0]) / 3.0,
                (a[1] + b[1] + c[1]) / 3.0,
                (a[2] + b[2] + c[2]) / 3.0,
            ];
            (
                format!("[[triangles]]\nvertices = [{a:?}, {b:?}, {c:?}]\nmaterial = \"g\"\n"),
                centroid,
                1.0,
            )
        };
        let from = if inside {
            o
        } else {
            let d = [
                rng.range(-1.0, 1.0),
                rng.range(-1.0, 1.0),
                rng.range(-1.0, 1.0),
            ];
            [
                target[0] + 8.0 * d[0],
                target[1] + 8.0 * d[1] + 9.0,
                target[2] + 8.0 * d[2],
            ]
        };
        let aim = if inside {
            [
                rng.range(-1.0, 1.0),
                rng.range(-1.0, 1.0),
                rng.range(-1.0, 1.0),
            ]
        } else {
            [
                target[0] - from[0],
                target[1] - from[1],
                target[2] - from[2],
            ]
        };
        let scene = parse(&format!(
            "max_depth = 2\nmin_weight = 0.0\n[camera]\neye = [0.0, 0.0, 9.0]\nlook_at = [0.0, 0.0, 0.0]\n\
             fov = 40.0\nwidth = 8\nheight = 8\n[materials.g]\nmodel = \"ambient\"\nka = [0.1, 0.1, 0.1]\n\
             kr = [0.5, 0.5, 0.5]\nkt = [0.5, 0.5, 0.5]\nior = 1.5\n{prim}"
        ));
        let (buf, spec) = buffers(&scene, 8, 8, TriangleAlgorithm::Watertight);
        for (origin, dir) in glint::cpu::secondary_rays_f32(&buf, spec, from, aim) {
            let h = glint::cpu::query_f32(
                &buf,
                spec,
                &[RayIn {
                    origin,
                    t_min: 0.0,
                    dir,
                    t_max: f32::INFINITY,
                }],
            )[0];
            rays += 1;
            let len = (dir[0] * dir[0] + dir[1] * dir[1] + dir[2] * dir[2]).sqrt();
            let back_in = sphere && {
                let c = [origin[0] - o[0], origin[1] - o[1], origin[2] - o[2]];
                c[0] * dir[0] + c[1] * dir[1] + c[2] * dir[2] < 0.0
            };
            if !back_in {
                assert_eq!(
                    h.prim,
                    u32::MAX,
                    "trial {trial}: a ray leaving the surface met it at t = {} (sphere {sphere}, inside {inside}, centre {o:?}, r {radius}, from {from:?}, aim {aim:?}, origin {origin:?}, dir {dir:?})",
                    h.t
                );
                continue;
            }
            // Heading into the sphere: it crosses a chord of 2 r cos θ; a self-hit would be
            // at t ≈ 0. Chords of grazing rays (cos θ < 10⁻³) are too short to tell.
            let cos = {
                let c = [origin[0] - o[0], origin[1] - o[1], origin[2] - o[2]];
                let cl = (c[0] * c[0] + c[1] * c[1] + c[2] * c[2]).sqrt();
                -(c[0] * dir[0] + c[1] * dir[1] + c[2] * dir[2]) / (cl * len)
            };
            if cos < 1e-3 {
                grazing += 1;
                continue;
            }
            assert_eq!(
                h.prim, 0,
                "trial {trial}: the ray into the sphere must cross it"
            );
            assert!(
                h.t * len > radius * cos,
                "trial {trial}: a self-hit at t = {} (chord {})",
                h.t,
                2.0 * radius * cos
            );
        }
    }
    assert!(rays > 3000, "{rays} secondary rays");
    assert!(grazing < rays / 100, "{grazing} grazing of {rays}");
}

/// The twin of the spawning test: an origin left on the surface (no offset) does find it.
#[test]
fn an_origin_on_the_surface_would_self_intersect() {
    let scene = parse(
        "[camera]\neye = [0.0, 0.0, 9.0]\nlook_at = [0.0, 0.0, 0.0]\nfov = 40.0\nwidth = 8\nheight = 8\n\
         [materials.g]\nmodel = \"ambient\"\nka = [0.1, 0.1, 0.1]\n\
         [[spheres]]\ncenter = [0.3, 0.1, 0.2]\nradius = 1.7\nmaterial = \"g\"\n",
    );
    let (buf, spec) = buffers(&scene, 8, 8, TriangleAlgorithm::Watertight);
    let mut rng = Rng::new(7);
    let mut self_hits = 0;
    for _ in 0..200 {
        let d = [rng.range(-1.0, 1.0), rng.range(-1.0, 1.0), 1.0f32];
        let ray = RayIn {
            origin: [0.3, 0.1, 9.0],
            t_min: 0.0,
            dir: [d[0] * 0.1, d[1] * 0.1, -1.0],
            t_max: f32::INFINITY,
        };
        let h = glint::cpu::query_f32(&buf, spec, &[ray])[0];
        let p = [
            ray.origin[0] + ray.dir[0] * h.t,
            ray.origin[1] + ray.dir[1] * h.t,
            ray.origin[2] + ray.dir[2] * h.t,
        ];
        let n = [p[0] - 0.3, p[1] - 0.1, p[2] - 0.2];
        let back = RayIn {
            origin: p,
            t_min: 0.0,
            dir: n,
            t_max: f32::INFINITY,
        };
        let h2 = glint::cpu::query_f32(&buf, spec, &[back])[0];
        self_hits += (h2.prim == 0) as usize;
    }
    assert!(
        self_hits > 0,
        "an unspawned origin must self-intersect sometimes"
    );
}

/// A camera inside a glass ball (kt = 1, ior 1.5, nothing else): every ray leaves through
/// the surface and the image is the background seen through it (blue), with the glass's
/// own ambient (0 here) added; the GPU gives the mirror's image. The twin: with kt = 0 the
/// image is black.
#[test]
fn rays_starting_inside_glass_leave_it() {
    let scene = |kt: f32| {
        parse(&format!(
            "ambient = [1.0, 1.0, 1.0]\nbackground = [0.0, 0.0, 1.0]\nmin_weight = 0.0\n\
             [camera]\neye = [0.0, 0.0, 0.0]\nlook_at = [0.0, 0.0, -1.0]\nfov = 60.0\nwidth = 16\nheight = 16\n\
             [materials.glass]\nmodel = \"ambient\"\nka = [0.0, 0.0, 0.0]\nkt = [{kt:?}, {kt:?}, {kt:?}]\nior = 1.5\n\
             [[spheres]]\ncenter = [0.1, -0.2, 0.05]\nradius = 3.0\nmaterial = \"glass\"\n"
        ))
    };
    let (c, r, buf, spec) = f32_and_f64(&scene(1.0), 16, 16);
    for img in [&c, &r] {
        assert!(
            img.pixels
                .iter()
                .all(|p| p[..3] == [0.0, 0.0, 1.0] && p[3] > 2.0),
            "{:?}",
            img.pixels[0]
        );
    }
    if let Some(gpu) = common::gpu() {
        check_agreement(
            &render_gpu(gpu, &buf, spec),
            &c,
            common::bit_exact_expected(gpu),
        )
        .unwrap();
    }
    let dark = f32_and_f64(&scene(0.0), 16, 16).0;
    assert!(dark.pixels.iter().all(|p| p[..3] == [0.0, 0.0, 0.0]));
}

/// Total internal reflection: inside a glass slab's far face at 60° (beyond the critical
/// angle 41.8°) no ray is transmitted, and kt joins kr; at 20° the ray is transmitted.
#[test]
fn total_internal_reflection_sends_everything_back() {
    let scene = parse(
        "max_depth = 1\nmin_weight = 0.0\n[camera]\neye = [0.0, 0.0, 9.0]\nlook_at = [0.0, 0.0, 0.0]\n\
         fov = 40.0\nwidth = 8\nheight = 8\n[materials.g]\nmodel = \"ambient\"\nka = [0.0, 0.0, 0.0]\n\
         kr = [0.25, 0.25, 0.25]\nkt = [0.5, 0.5, 0.5]\nior = 1.5\n\
         [[triangles]]\nvertices = [[-5.0, -5.0, 0.0], [5.0, -5.0, 0.0], [0.0, 5.0, 0.0]]\nmaterial = \"g\"\n",
    );
    let (buf, spec) = buffers(&scene, 8, 8, TriangleAlgorithm::Watertight);
    // From below the plane (inside the glass, normal +z faces away): leaving.
    let at = |deg: f32| {
        let (s, c) = deg.to_radians().sin_cos();
        glint::cpu::secondary_rays_f32(&buf, spec, [-s, 0.0, -c], [s, 0.0, c])
    };
    let tir = at(60.0);
    assert_eq!(tir.len(), 1, "only the reflected ray");
    assert!(
        tir[0].1[2] < 0.0,
        "it goes back into the glass: {:?}",
        tir[0].1
    );
    let through = at(20.0);
    assert_eq!(through.len(), 2, "transmitted and reflected");
    assert!(
        through[0].1[2] > 0.0,
        "the transmitted ray leaves: {:?}",
        through[0].1
    );
}

/// Grazing rays, a mirror and a glass triangle in one plane, and the Whitted scenes: the
/// GPU gives the CPU mirror's image on every triangle algorithm, with antialiasing and
/// through the general pipeline; the f32 error against f64 is measured. Every other
/// (scene, algorithm) pair here, the rest in the next test, so that the harness compiles
/// their pipelines on two threads (a cold lavapipe spends a minute on them).
#[test]
fn whitted_scenes_gpu_equals_cpu() {
    whitted_sweep(0);
}

/// [`whitted_scenes_gpu_equals_cpu`] on the other (scene, algorithm) pairs.
#[test]
fn whitted_scenes_gpu_equals_cpu_second_half() {
    whitted_sweep(1);
}

/// The Whitted sweep on the (scene, triangle algorithm) pairs whose index is `half`
/// modulo 2 (scenes in order, each with every algorithm).
fn whitted_sweep(half: usize) {
    let Some(gpu) = common::gpu() else { return };
    let lavapipe = common::bit_exact_expected(gpu);
    let coplanar = parse(
        "ambient = [0.2, 0.2, 0.2]\nbackground = [0.3, 0.5, 0.8]\nshadows = true\n\
         [camera]\neye = [0.0, 0.05, 6.0]\nlook_at = [0.0, 0.0, 0.0]\nfov = 50.0\nwidth = 64\nheight = 48\n\
         [[lights]]\nposition = [3.0, 5.0, 4.0]\ncolor = [1.0, 1.0, 1.0]\n\
         [materials.mirror]\nmodel = \"diffuse\"\nka = [0.1, 0.1, 0.1]\nkd = [0.2, 0.2, 0.2]\nkr = [0.7, 0.7, 0.7]\n\
         [materials.glass]\nmodel = \"phong\"\nka = [0.0, 0.0, 0.0]\nkd = [0.0, 0.0, 0.0]\nks = [0.5, 0.5, 0.5]\nn = 50.0\n\
         kr = [1.0, 1.0, 1.0]\nkt = [1.0, 1.0, 1.0]\nior = 1.33\nfresnel = true\n\
         [materials.ball]\nmodel = \"phong\"\nka = [0.3, 0.1, 0.1]\nkd = [0.8, 0.2, 0.2]\nks = [0.5, 0.5, 0.5]\nn = 10.0\n\
         [[triangles]]\nvertices = [[-9.0, -1.0, -9.0], [-9.0, -1.0, 9.0], [9.0, -1.0, 9.0]]\nmaterial = \"mirror\"\n\
         [[triangles]]\nvertices = [[-9.0, -1.0, -9.0], [9.0, -1.0, 9.0], [9.0, -1.0, -9.0]]\nmaterial = \"glass\"\n\
         [[triangles]]\nvertices = [[-9.0, -1.0, -9.0], [9.0, -1.0, 9.0], [9.0, -1.0, -9.0]]\nmaterial = \"mirror\"\n\
         [[spheres]]\ncenter = [0.5, 0.0, -1.0]\nradius = 1.0\nmaterial = \"ball\"\n\
         [[spheres]]\ncenter = [-1.5, -0.5, 1.0]\nradius = 0.5\nmaterial = \"glass\"\n",
    );
    let mut scenes = vec![("coplanar and grazing".to_string(), coplanar)];
    for name in ["whitted", "bb8-mirror"] {
        scenes.push((name.to_string(), common::seed_scene(name)));
    }
    let pairs = scenes
        .iter()
        .flat_map(|(name, scene)| TriangleAlgorithm::ALL.map(|algo| (name, scene, algo)));
    for (name, scene, algo) in pairs.skip(half).step_by(2) {
        let (mut buf, spec) = buffers(scene, 160, 120, algo);
        assert!(spec.whitted, "{name}");
        let c = glint::cpu::render_f32(&buf, spec);
        let g = render_gpu(gpu, &buf, spec);
        let d = check_agreement(&g, &c, lavapipe).unwrap_or_else(|e| panic!("{name}/{algo}: {e}"));
        let e = glint::compare::diff(&c, &glint::cpu::render_f64(scene, &buf, spec));
        eprintln!(
            "{name}/{algo}: GPU vs CPU {} pixels; f32 vs f64: largest {:.2e}, rms {:.2e}, {} pixels off in 8 bits",
            d.differing_pixels, e.max_abs, e.rms, e.differing_pixels
        );
        let general = Specialisation::general(&buf);
        check_agreement(
            &render_gpu(gpu, &buf, general),
            &glint::cpu::render_f32(&buf, general),
            lavapipe,
        )
        .unwrap_or_else(|e| panic!("{name}/{algo} general: {e}"));
        buf.params.samples = 2;
        let aa = Specialisation::for_scene(&buf);
        check_agreement(
            &render_gpu(gpu, &buf, aa),
            &glint::cpu::render_f32(&buf, aa),
            lavapipe,
        )
        .unwrap_or_else(|e| panic!("{name}/{algo} 2x2: {e}"));
    }
}

/// A scene without kr or kt compiles none of this (`WHITTED` off) and gives its image
/// unchanged; `max_depth = 0` turns it off for a scene that has mirrors, which then renders
/// as if they were plain. The twin: max_depth 1 changes the mirror scene's image.
#[test]
fn scenes_without_mirrors_pay_nothing() {
    let plain = common::seed_scene("bb8-shadows");
    let (buf, spec) = buffers(&plain, 96, 72, plain.triangle);
    assert!(!spec.whitted);
    let mut mirror = common::seed_scene("bb8-mirror");
    mirror.max_depth = 0;
    let (mbuf, mspec) = buffers(&mirror, 96, 72, mirror.triangle);
    assert!(!mspec.whitted);
    let strip = |s: &Scene| {
        let mut s = s.clone();
        for m in &mut s.materials {
            m.optics = Default::default();
        }
        s
    };
    let (sbuf, sspec) = buffers(&strip(&mirror), 96, 72, mirror.triangle);
    let a = glint::cpu::render_f32(&mbuf, mspec);
    assert!(glint::compare::diff(&a, &glint::cpu::render_f32(&sbuf, sspec)).bit_exact());
    mirror.max_depth = 1;
    let (buf1, spec1) = buffers(&mirror, 96, 72, mirror.triangle);
    assert!(spec1.whitted);
    assert!(!glint::compare::diff(&a, &glint::cpu::render_f32(&buf1, spec1)).bit_exact());
    let _ = (buf, spec);
}

/// Bad values name the file, the line and the key; the twin: the good file loads.
#[test]
fn bad_optics_name_file_line_and_key() {
    let base = "[camera]\neye = [0.0, 0.0, 5.0]\nlook_at = [0.0, 0.0, 0.0]\nfov = 40.0\nwidth = 8\nheight = 8\n\
                [materials.g]\nmodel = \"ambient\"\nka = [0.1, 0.1, 0.1]\n";
    let cases = [
        ("kt = [0.5, 0.5, 0.5]\n", "materials.g.ior", "missing"),
        (
            "kt = [0.5, 0.5, 0.5]\nior = 0.0\n",
            "materials.g.ior",
            "> 0",
        ),
        (
            "kt = [0.5, 0.5, 0.5]\nior = -1.5\n",
            "materials.g.ior",
            "> 0",
        ),
        ("kr = [0.5, -0.5, 0.5]\n", "materials.g.kr", "negative"),
        (
            "kt = [0.5, 0.5, -1.0]\nior = 1.5\n",
            "materials.g.kt",
            "negative",
        ),
    ];
    for (extra, key, what) in cases {
        let e =
            Scene::parse(&format!("{base}{extra}"), std::path::Path::new("bad.toml")).unwrap_err();
        let m = e.to_string();
        assert!(
            m.starts_with("bad.toml:") && m.contains(key) && m.contains(what),
            "{m}"
        );
        assert!(e.line().is_some_and(|l| l >= 7), "{m}");
    }
    for (top, key) in [
        ("max_depth = 17\n", "max_depth"),
        ("max_depth = -1\n", "max_depth"),
        ("min_weight = -0.5\n", "min_weight"),
    ] {
        let e =
            Scene::parse(&format!("{top}{base}"), std::path::Path::new("bad.toml")).unwrap_err();
        let m = e.to_string();
        assert!(m.starts_with("bad.toml:1:") && m.contains(key), "{m}");
    }
    let good = Scene::parse(
        &format!("max_depth = 16\nmin_weight = 0.0\n{base}kr = [0.5, 0.5, 0.5]\nkt = [0.5, 0.5, 0.5]\nior = 1.5\nfresnel = true\n"),
        std::path::Path::new("good.toml"),
    )
    .unwrap();
    assert_eq!(good.max_depth, 16);
    assert!(good.materials[0].optics.fresnel);
}

/// A smooth mirror whose vertex normals lean far from its plane: a ray that grazes it
/// would reflect, about the shading normal, under the surface; glint mirrors that
/// direction about the geometric plane, so it leaves above. The twin: the reflection about
/// the shading normal alone does dip under (the case is real), and a flat copy of the same
/// mirror reflects about the plane as usual.
#[test]
fn smooth_mirrors_never_reflect_under_the_surface() {
    let d = common::Scratch::new("whitted-smooth");
    // The plane y = 0 (geometric normal +y), vertex normals leaning 60° towards −x.
    let (s, c) = 60f32.to_radians().sin_cos();
    std::fs::write(
        d.join("tilt.obj"),
        format!(
            "v -5 0 -5\nv 5 0 -5\nv 0 0 5\nvn {:?} {c:?} 0\nvn {:?} {c:?} 0\nvn {:?} {c:?} 0\nf 1//1 3//3 2//2\n",
            -s, -s, -s
        ),
    )
    .unwrap();
    let scene = |smooth: bool| {
        let path = d.join(format!("s{smooth}.toml"));
        std::fs::write(
            &path,
            format!(
                "max_depth = 1\nmin_weight = 0.0\n[camera]\neye = [0.0, 3.0, 9.0]\nlook_at = [0.0, 0.0, 0.0]\n\
                 fov = 40.0\nwidth = 8\nheight = 8\n[materials.m]\nmodel = \"ambient\"\nka = [0.1, 0.1, 0.1]\n\
                 kr = [1.0, 1.0, 1.0]\n[[meshes]]\nfile = \"tilt.obj\"\nmaterial = \"m\"\nsmooth = {smooth}\n"
            ),
        )
        .unwrap();
        Scene::load(&path).unwrap()
    };
    // Grazing from +x, going −x and slightly down: about the tilted normal it turns under.
    let (from, dir) = ([6.0f32, 0.3, 0.0], [-1.0f32, -0.05, 0.0]);
    let smooth = scene(true);
    let (buf, spec) = buffers(&smooth, 8, 8, TriangleAlgorithm::Watertight);
    assert!(spec.smooth && spec.whitted);
    let out = glint::cpu::secondary_rays_f32(&buf, spec, from, dir);
    assert_eq!(out.len(), 1);
    assert!(
        out[0].1[1] > 0.0,
        "the reflected ray must leave above: {:?}",
        out[0].1
    );
    assert!(out[0].0[1] > 0.0, "from above the surface: {:?}", out[0].0);
    // The twin: about the shading normal alone it would go under.
    let len = (dir[0] * dir[0] + dir[1] * dir[1]).sqrt();
    let dn = [dir[0] / len, dir[1] / len];
    let cos_i = -(dn[0] * -s + dn[1] * c);
    let raw_y = dn[1] + c * 2.0 * cos_i;
    assert!(raw_y < 0.0, "the case must exercise the rule: {raw_y}");
    let flat = scene(false);
    let (fbuf, fspec) = buffers(&flat, 8, 8, TriangleAlgorithm::Watertight);
    let f = glint::cpu::secondary_rays_f32(&fbuf, fspec, from, dir);
    assert!(
        (f[0].1[1] - 0.05 / len).abs() < 1e-6,
        "a flat mirror reflects about its plane: {:?}",
        f[0].1
    );
}
