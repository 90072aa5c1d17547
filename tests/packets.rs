//! The CPU's packet tracer (`src/cpu/packet/`, what `render_f32` runs)
//! against the mirror it must equal: every f32 bit of every pixel the same as
//! `render_f32_mirror` (one `trace_pixel` per pixel), on the seed scenes and random scenes
//! both through the BVH and testing every primitive, on real meshes with each triangle
//! algorithm, with and without shadows, and on image sizes that cut packets at the right
//! and bottom edges; for every build of the packet tracer this CPU can run (AVX-512, AVX2
//! and the baseline build a CPU without either runs).

mod common;

use std::path::Path;

use common::{Rng, random_scene, same_bits, seed_scene};
use glint::buffers::{SceneBuffers, Specialisation};
use glint::cpu::packet::Simd;
use glint::image::Image;
use glint::scene::{Scene, TriangleAlgorithm};

const ALGOS: [TriangleAlgorithm; 3] = [
    TriangleAlgorithm::Naive,
    TriangleAlgorithm::MollerTrumbore,
    TriangleAlgorithm::Watertight,
];

/// Both CPU f32 renders of `buf` through the BVH, compared; Err names `what`.
fn check(what: &str, buf: &SceneBuffers, spec: Specialisation) -> Result<usize, String> {
    check_as(what, buf, spec.with_bvh(true))
}

/// Both CPU f32 renders of `buf` as `spec` says (BVH or every primitive), compared.
/// Every build of the packet tracer is checked (AVX-512, AVX2 and the baseline, as far as
/// the CPU has them).
fn check_as(what: &str, buf: &SceneBuffers, spec: Specialisation) -> Result<usize, String> {
    let mirror = glint::cpu::render_f32_mirror(buf, spec);
    for simd in Simd::ALL {
        let packets = glint::cpu::render_f32_simd(buf, spec, simd);
        same_bits(&packets, &mirror).map_err(|e| {
            let build = simd.name();
            format!("{what} (BVH: {}, {build} build): {e}", spec.use_bvh)
        })?;
    }
    Ok(mirror.hit_count())
}

/// `scene` at `w`×`h` compared both ways (through the BVH and testing every primitive)
/// with every triangle algorithm; each comparison must hit more than `min_hits` pixels.
fn check_every_way(what: &str, scene: &Scene, w: u32, h: u32, min_hits: usize) {
    for algo in ALGOS {
        let buf = SceneBuffers::new(scene, w, h, algo);
        for bvh in [true, false] {
            let spec = Specialisation::for_scene(&buf).with_bvh(bvh);
            let hits =
                check_as(&format!("{what} {algo:?}"), &buf, spec).unwrap_or_else(|e| panic!("{e}"));
            assert!(
                hits > min_hits,
                "{what} {algo:?}: only {hits} pixels hit, the test would prove little"
            );
        }
    }
}

#[test]
fn seed_scenes_equal_the_mirror_with_and_without_the_bvh() {
    for name in common::SEED_SCENES {
        // 37×23: neither side a multiple of the 4×4 packet.
        check_every_way(name, &seed_scene(name), 37, 23, 0);
    }
}

/// `render_f32` itself, which sends scenes of more than `PACKET_BRUTE_FORCE_MAX`
/// primitives through the BVH even where the shader (and so the mirror) tests every
/// primitive: the seed scenes, with and without shadows, equal the mirror as the shader
/// is specialised for them.
#[test]
fn the_packet_tracers_own_choice_of_search_equals_the_mirror() {
    let mut through_bvh_only_in_packets = 0;
    for name in common::SEED_SCENES {
        for shadows in [false, true] {
            let mut scene = seed_scene(name);
            scene.shadows = shadows;
            let buf = SceneBuffers::new(&scene, 37, 23, TriangleAlgorithm::Watertight);
            let spec = Specialisation::for_scene(&buf);
            let n = buf.spheres.len() + buf.triangles.len();
            if !spec.use_bvh && n > glint::cpu::PACKET_BRUTE_FORCE_MAX {
                through_bvh_only_in_packets += 1;
            }
            let mirror = glint::cpu::render_f32_mirror(&buf, spec);
            same_bits(&glint::cpu::render_f32(&buf, spec), &mirror)
                .unwrap_or_else(|e| panic!("{name} (shadows {shadows}): {e}"));
        }
    }
    assert!(
        through_bvh_only_in_packets >= 4,
        "{through_bvh_only_in_packets}"
    );
}

/// A scene of one of the small test meshes with two lights, shadows on or off.
fn mesh_scene(mesh: &str, shadows: bool) -> Scene {
    mesh_scene_n(mesh, shadows, 20.0)
}

/// `mesh_scene` with Phong exponent `n`.
fn mesh_scene_n(mesh: &str, shadows: bool, n: f32) -> Scene {
    // The dragon is about 0.2 units tall where the others are about 2.
    let place = if mesh == "dragon_res4" {
        "scale = [12.0, 12.0, 12.0]\ntranslate = [0.0, -1.3, 0.0]"
    } else {
        ""
    };
    let src = format!(
        r#"
ambient = [0.2, 0.2, 0.2]
shadows = {shadows}
[camera]
eye = [0.3, 0.4, 4.0]
look_at = [0.0, 0.0, 0.0]
up = [0.0, 1.0, 0.0]
fov = 40.0
width = 64
height = 48
[[lights]]
position = [-3.0, 4.0, 5.0]
color = [0.7, 0.7, 0.6]
[[lights]]
position = [4.0, 1.0, 2.0]
color = [0.3, 0.3, 0.4]
[materials.m]
model = "phong"
ka = [0.3, 0.2, 0.1]
kd = [0.6, 0.5, 0.4]
ks = [0.5, 0.5, 0.5]
n = {n:?}
[[meshes]]
file = "{mesh}.obj"
material = "m"
{place}
"#
    );
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/meshes");
    Scene::parse(&src, &dir.join(format!("{mesh}.toml"))).unwrap_or_else(|e| panic!("{e}"))
}

#[test]
fn meshes_equal_the_mirror_with_every_triangle_algorithm() {
    for mesh in ["teapot_npm", "bunny_npm", "suzanne", "dragon_res4"] {
        for shadows in [false, true] {
            let scene = mesh_scene(mesh, shadows);
            for algo in ALGOS {
                let buf = SceneBuffers::new(&scene, 61, 45, algo);
                let what = format!("{mesh} {algo:?} shadows={shadows}");
                let hits = check(&what, &buf, Specialisation::for_scene(&buf))
                    .unwrap_or_else(|e| panic!("{e}"));
                assert!(hits > 100, "{what}: only {hits} pixels hit");
            }
        }
    }
}

#[test]
fn random_scenes_equal_the_mirror() {
    let mut rng = Rng::new(0x9ac4e7);
    let mut tested = 0;
    while tested < 40 {
        let src = random_scene(&mut rng);
        let Ok(scene) = Scene::parse(&src, Path::new("random.toml")) else {
            continue;
        };
        tested += 1;
        let buf = SceneBuffers::new(&scene, 45, 31, scene.triangle);
        for bvh in [true, false] {
            let spec = Specialisation::for_scene(&buf).with_bvh(bvh);
            check_as(&format!("random scene #{tested}:\n{src}"), &buf, spec)
                .unwrap_or_else(|e| panic!("{e}"));
        }
    }
}

#[test]
fn packets_cut_by_the_image_edges_equal_the_mirror() {
    let scene = mesh_scene("suzanne", false);
    for (w, h) in [(1, 1), (3, 1), (1, 3), (5, 3), (4, 2), (9, 7)] {
        let buf = SceneBuffers::new(&scene, w, h, TriangleAlgorithm::Watertight);
        check(&format!("{w}x{h}"), &buf, Specialisation::for_scene(&buf))
            .unwrap_or_else(|e| panic!("{e}"));
    }
}

/// A non-integer exponent goes through `pow` lane by lane, an exponent of 0 gives 1.
#[test]
fn other_exponents_equal_the_mirror() {
    for n in [12.5, 0.0, 1.0, 255.0] {
        for shadows in [false, true] {
            let scene = mesh_scene_n("teapot_npm", shadows, n);
            let buf = SceneBuffers::new(&scene, 33, 27, TriangleAlgorithm::Watertight);
            check(&format!("n = {n}"), &buf, Specialisation::for_scene(&buf))
                .unwrap_or_else(|e| panic!("{e}"));
        }
    }
}

/// The twin: the comparison fails when one bit of one channel of one pixel changes.
#[test]
fn a_one_bit_change_fails_the_comparison() {
    let scene = mesh_scene("suzanne", false);
    let buf = SceneBuffers::new(&scene, 61, 45, TriangleAlgorithm::Watertight);
    let spec = Specialisation::for_scene(&buf).with_bvh(true);
    let mirror = glint::cpu::render_f32_mirror(&buf, spec);
    let mut packets = glint::cpu::render_f32(&buf, spec);
    assert!(same_bits(&packets, &mirror).is_ok());
    let k = packets.pixels.len() / 2 + 7;
    packets.pixels[k][1] = f32::from_bits(packets.pixels[k][1].to_bits() ^ 1);
    let err = same_bits(&packets, &mirror).expect_err("a flipped bit must fail");
    assert!(err.contains("1 pixels differ"), "{err}");
}

/// Hard cases for every triangle algorithm's lane loops: triangles that are degenerate
/// (a repeated corner, collinear corners), a sliver, one edge-on to the camera (its plane
/// holds the eye: every ray is parallel to it), a fan whose triangles share edges and a
/// vertex, a tiny far triangle and a huge near one; with shadows (shadow rays from
/// origins on those shared edges) and without.
#[test]
fn hard_triangles_equal_the_mirror_with_every_algorithm() {
    let mut src = String::from(
        "ambient = [0.1, 0.1, 0.1]\n[camera]\neye = [0.0, 0.0, 6.0]\nlook_at = [0.0, 0.0, 0.0]\n\
         up = [0.0, 1.0, 0.0]\nfov = 50.0\nwidth = 8\nheight = 8\n\
         [[lights]]\nposition = [2.0, 3.0, 5.0]\ncolor = [1.0, 1.0, 1.0]\n\
         [materials.m]\nmodel = \"phong\"\nka = [0.2, 0.2, 0.2]\nkd = [0.7, 0.5, 0.3]\n\
         ks = [0.5, 0.5, 0.5]\nn = 20.0\n",
    );
    let mut tri = |a: [f32; 3], b: [f32; 3], c: [f32; 3]| {
        src += &format!("[[triangles]]\nvertices = [{a:?}, {b:?}, {c:?}]\nmaterial = \"m\"\n");
    };
    tri([0.0, 0.0, 0.0], [0.0, 0.0, 0.0], [1.0, 1.0, 0.0]); // a repeated corner
    tri([-2.0, -2.0, 0.0], [0.0, 0.0, 0.0], [2.0, 2.0, 0.0]); // collinear
    tri([-2.0, 1.0, 0.5], [2.0, 1.0, 0.5], [0.0, 1.0 + 1e-6, 0.5]); // a sliver
    tri([0.0, -3.0, 6.0], [0.0, 3.0, 0.0], [0.0, -3.0, 0.0]); // edge-on: its plane holds the eye
    let fan_at = [-1.0f32, -0.5, 0.0];
    for k in 0..6 {
        let ang = |k: i32| (k as f32) * std::f32::consts::PI / 3.0;
        let p = |k: i32| [fan_at[0] + ang(k).cos(), fan_at[1] + ang(k).sin(), 0.2];
        tri([fan_at[0], fan_at[1], 0.2], p(k), p(k + 1));
    }
    tri(
        [1.5, -1.5, -40.0],
        [1.5001, -1.5, -40.0],
        [1.5, -1.4999, -40.0],
    ); // tiny and far
    tri([-1e4, -1e4, 5.5], [1e4, -1e4, 5.5], [0.0, 1e4, -5.5]); // huge and near
    for shadows in [false, true] {
        let text = format!("shadows = {shadows}\n{src}");
        let scene = Scene::parse(&text, Path::new("hard.toml")).unwrap();
        // Odd sizes: packets cut at both edges.
        check_every_way(&format!("shadows={shadows}"), &scene, 53, 41, 100);
    }
}

/// `render_f32_into` over an image that held something else: a stale frame of the same
/// size (every pixel NaN, so a pixel left unwritten shows), a buffer of another size, and
/// sizes that cut packets at the edges. Each result equals the mirror in every bit.
#[test]
fn rendering_into_a_used_image_equals_the_mirror() {
    let scene = mesh_scene("suzanne", true);
    for (w, h) in [(61, 45), (64, 48), (9, 7)] {
        let buf = SceneBuffers::new(&scene, w, h, TriangleAlgorithm::Watertight);
        let spec = Specialisation::for_scene(&buf);
        let mirror = glint::cpu::render_f32_mirror(&buf, spec);
        let mut stale = Image {
            width: w,
            height: h,
            pixels: vec![[f32::NAN; 4]; (w * h) as usize],
        };
        glint::cpu::render_f32_into(&buf, spec, &mut stale);
        same_bits(&stale, &mirror).unwrap_or_else(|e| panic!("{w}x{h}, stale frame: {e}"));
        let mut other = Image {
            width: 3,
            height: 2,
            pixels: vec![[f32::NAN; 4]; 6],
        };
        glint::cpu::render_f32_into(&buf, spec, &mut other);
        same_bits(&other, &mirror).unwrap_or_else(|e| panic!("{w}x{h}, other size: {e}"));
    }
}

/// The twin: a stale frame that was not drawn over fails that comparison, and so does one
/// whose last pixel was left stale.
#[test]
fn a_stale_pixel_fails_the_comparison() {
    let scene = mesh_scene("suzanne", true);
    let buf = SceneBuffers::new(&scene, 61, 45, TriangleAlgorithm::Watertight);
    let spec = Specialisation::for_scene(&buf);
    let mirror = glint::cpu::render_f32_mirror(&buf, spec);
    let stale = Image {
        width: 61,
        height: 45,
        pixels: vec![[f32::NAN; 4]; 61 * 45],
    };
    assert!(same_bits(&stale, &mirror).is_err());
    let mut drawn = stale;
    glint::cpu::render_f32_into(&buf, spec, &mut drawn);
    assert!(same_bits(&drawn, &mirror).is_ok());
    let last = drawn.pixels.len() - 1;
    drawn.pixels[last] = [f32::NAN; 4];
    let err = same_bits(&drawn, &mirror).expect_err("a stale pixel must fail");
    assert!(err.contains("1 pixels differ"), "{err}");
}

/// Bumpy height fields whose vertices lie on pixel rays, seen from far from the origin (up
/// to 1e6), with each triangle algorithm, with and without shadows: where a triangle's
/// computed hit can fall outside its box's computed interval (the naive test far away),
/// the order in which a packet visits two children could decide which hit the bound
/// culls. The packet tracer must still give the mirror's image in every bit.
#[test]
fn far_vertex_grids_equal_the_mirror() {
    let mut rng = Rng::new(0xfa12);
    for case in 0..24 {
        let far = [1e2f32, 1e4, 1e5, 1e6][case % 4];
        let eye = [0, 1, 2].map(|_| rng.range(-far, far));
        let mut src = common::vertex_grid_scene(eye, "naive", 96, 72, 2 + case as u32 % 3);
        if case % 2 == 1 {
            src = src.replacen("ambient =", "shadows = true\nambient =", 1);
        }
        let scene = Scene::parse(&src, Path::new("grid.toml")).unwrap();
        for algo in ALGOS {
            let buf = SceneBuffers::new(&scene, 96, 72, algo);
            let spec = Specialisation::for_scene(&buf);
            let hits = check(&format!("far grid #{case} at {eye:?} {algo:?}"), &buf, spec)
                .unwrap_or_else(|e| panic!("{e}"));
            assert!(hits > 1000, "far grid #{case} {algo:?}: only {hits} hits");
        }
    }
}
