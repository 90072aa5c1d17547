//! `glint stats` (`glint::traversal_stats`): the counts of the mirror's traversal. Counting
//! changes no bit of what the tracer computes; the counts are right where they can be
//! worked out by hand; each ray kind is counted as what it is.

mod common;

use glint::buffers::{SceneBuffers, Specialisation};
use glint::cpu::count::{Counter, RayKind};
use glint::cpu::trace::{Camera, Globals, trace_pixel};
use glint::scene::Scene;
use glint::traversal_stats::{KindStats, traversal_stats};
use std::path::Path;

fn buffers(name: &str, w: u32, h: u32) -> SceneBuffers {
    let s = Scene::load(Path::new("scenes").join(name)).unwrap();
    SceneBuffers::new(&s, w, h, s.triangle)
}

fn kind(stats: &glint::traversal_stats::TraversalStats, k: RayKind) -> &KindStats {
    &stats.kinds.iter().find(|(x, _)| *x == k).unwrap().1
}

/// Every pixel traced with a counter is the pixel traced without, in every bit, on a
/// scene with shadows, reflections and refractions. The twin: another pixel differs.
#[test]
fn counting_changes_no_bit() {
    let buf = buffers("whitted.toml", 48, 36);
    let spec = Specialisation::for_scene(&buf);
    let plain = Globals {
        cam: Camera::from_params(&buf.params),
        buf: &buf,
        spec,
        count: glint::cpu::count::NoCount,
    };
    let counted = Globals {
        cam: Camera::from_params(&buf.params),
        buf: &buf,
        spec,
        count: Counter::new(),
    };
    let bits = |p: [f32; 4]| p.map(f32::to_bits);
    let mut differ = 0;
    for j in 0..36 {
        for i in 0..48 {
            let a = trace_pixel(&plain, i, j);
            assert_eq!(bits(a), bits(trace_pixel(&counted, i, j)), "pixel {i},{j}");
            differ += (bits(a) != bits(trace_pixel(&plain, 47 - i, 35 - j))) as u32;
        }
    }
    assert!(differ > 0);
    assert!(!counted.count.take().is_empty());
}

/// Without a BVH (a scene of 16 primitives or fewer, as the shader's specialisation has
/// it) every camera ray tests every primitive and reads no node: one sphere is 1 test and
/// 32 bytes a ray. With the BVH forced on, a ray reads the root (32 bytes) and then tests
/// the sphere or not.
#[test]
fn counts_are_right_where_they_are_known() {
    let buf = buffers("sphere.toml", 40, 30);
    let spec = Specialisation::for_scene(&buf);
    assert!(!spec.use_bvh && buf.spheres.len() == 1 && buf.triangles.is_empty());
    let stats = traversal_stats(&buf, spec);
    let cam = kind(&stats, RayKind::Camera);
    assert_eq!(cam.rays, 40 * 30);
    assert_eq!((cam.prims.p50, cam.prims.max, cam.prims.mean), (1, 1, 1.0));
    assert_eq!((cam.bytes.max, cam.nodes.max, cam.leaves.max), (32, 0, 0));
    assert_eq!(cam.warp_spread, 0.0, "no nodes, no spread");
    let bvh = traversal_stats(&buf, spec.with_bvh(true));
    let cam = kind(&bvh, RayKind::Camera);
    assert_eq!(cam.rays, 40 * 30);
    // One node, a leaf: a ray that hits the root box reads it twice (the box, then the
    // node) and tests the sphere; one that misses reads the box only.
    assert_eq!(cam.nodes.max, 0);
    assert_eq!(cam.leaves.max, 1);
    assert_eq!(cam.bytes.max, 32 + 32 + 32);
    assert!(
        cam.bytes.p50 == 32 || cam.bytes.p50 == 96,
        "{:?}",
        cam.bytes
    );
    // The twin: the counts differ between the two specialisations.
    assert_ne!(
        kind(&stats, RayKind::Camera).bytes,
        kind(&bvh, RayKind::Camera).bytes
    );
}

/// Each kind is counted as what it is: whitted.toml (one light, shadows, a mirror sphere
/// and a glass one) has shadow, reflected and refracted rays; bb8 without shadows or
/// mirrors has camera rays only. A pixel's shadow rays are at most one per light per hit.
#[test]
fn ray_kinds_are_counted_apart() {
    let buf = buffers("whitted.toml", 64, 48);
    let stats = traversal_stats(&buf, Specialisation::for_scene(&buf));
    for k in RayKind::ALL {
        assert!(kind(&stats, k).rays > 0, "{k:?}: {:?}", kind(&stats, k));
    }
    let camera = kind(&stats, RayKind::Camera).rays;
    assert_eq!(camera, 64 * 48);
    let secondary = kind(&stats, RayKind::Reflected).rays + kind(&stats, RayKind::Refracted).rays;
    assert!(kind(&stats, RayKind::Shadow).rays <= camera + secondary);
    let json = stats.to_json();
    for key in [
        "\"camera\":{\"rays\":3072",
        "\"shadow\"",
        "\"reflected\"",
        "\"refracted\"",
    ] {
        assert!(json.contains(key), "{key}: {json}");
    }
    for key in [
        "\"nodes\"",
        "\"leaves\"",
        "\"prims\"",
        "\"stack\"",
        "\"bytes\"",
        "\"warp_spread\"",
    ] {
        assert!(json.contains(key), "{key}");
    }
    // The twin: bb8 traces camera rays only.
    let plain = buffers("bb8.toml", 64, 48);
    let stats = traversal_stats(&plain, Specialisation::for_scene(&plain));
    assert!(kind(&stats, RayKind::Camera).rays > 0);
    for k in [RayKind::Shadow, RayKind::Reflected, RayKind::Refracted] {
        assert_eq!(kind(&stats, k).rays, 0, "{k:?}");
    }
}

/// `glint stats --json` prints the object; a missing scene is an error naming it.
#[test]
fn the_command_prints_json_and_names_a_missing_scene() {
    let out = common::glint_command()
        .args([
            "stats",
            "scenes/bb8-shadows.toml",
            "--size",
            "32x24",
            "--json",
        ])
        .output()
        .unwrap();
    let (code, text) = common::status_and_text(&out);
    assert_eq!(code, Some(0), "{text}");
    assert!(text.starts_with("{\"camera\":{\"rays\":768,"), "{text}");
    let out = common::glint_command()
        .args(["stats", "scenes/absent.toml"])
        .output()
        .unwrap();
    let (code, text) = common::status_and_text(&out);
    assert_ne!(code, Some(0));
    assert!(text.contains("absent.toml"), "{text}");
}
