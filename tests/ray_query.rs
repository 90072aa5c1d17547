//! The ray-query tracer (`--backend gpu-rq`): the driver's acceleration structure and
//! triangle test, measured. Its hits are not glint's, so the tests assert only what the
//! Vulkan specification guarantees (a hit's t lies in its interval; a closed mesh seen from
//! outside is hit) and that it agrees with the f64 reference on all but a reported handful
//! of pixels; every other figure (leaks through shared edges and vertices, t error) is
//! printed beside glint's three triangle tests, for `docs/robustness.md`.
//!
//! Where the adapter has no ray queries (Mesa 22.3), the tracer must be a clear error and
//! these measurements are skipped with a loud line; `GLINT_EXPECT_RAY_QUERY=1` (set by
//! `.ci/test.sh` on its Mesa ≥ 25 pass) makes a missing feature a failure instead.

mod common;

gpu_sentinel!();

use std::path::Path;

use common::hard::{FAR, add, fan, fan_rays, leaks, ray, rays_from_inside, t_error, uv_sphere};
use common::{Rng, geometry, seed_scene, vertex_grid_scene};
use glint::buffers::{HitOut, PRIM_NONE, RayIn, SceneBuffers, Specialisation};
use glint::compare::diff;
use glint::gpu::{Gpu, Kernel};
use glint::scene::{Scene, TriangleAlgorithm};

/// The ray-query kernel; or, where the adapter has none, None after checking that this
/// driver's answer is the documented error, with a loud line that the measurement did not
/// run (and a failure when `GLINT_EXPECT_RAY_QUERY=1`).
fn rq(gpu: &Gpu) -> Option<&Kernel> {
    match gpu.ray_query_kernel() {
        Ok(k) => Some(k),
        Err(e) => {
            assert!(
                std::env::var("GLINT_EXPECT_RAY_QUERY").as_deref() != Ok("1"),
                "GLINT_EXPECT_RAY_QUERY=1 but {e}"
            );
            assert!(
                matches!(e, glint::gpu::GpuError::NoRayQuery { .. })
                    && e.to_string().contains("has no ray queries"),
                "{e}"
            );
            eprintln!(
                "\n*** no ray queries on {}: this ray-query check did NOT run ***\n",
                gpu.describe()
            );
            None
        }
    }
}

fn render_rq(
    gpu: &Gpu,
    k: &Kernel,
    buf: &SceneBuffers,
    spec: Specialisation,
) -> glint::image::Image {
    k.render(&gpu.device, &gpu.queue, buf, spec, &mut |_, _| {})
        .expect("ray-query render")
        .0
}

fn query_rq(
    gpu: &Gpu,
    k: &Kernel,
    buf: &SceneBuffers,
    spec: Specialisation,
    rays: &[RayIn],
) -> Vec<HitOut> {
    let hits = k
        .query(&gpu.device, &gpu.queue, buf, spec, rays)
        .expect("ray-query query");
    // The specification's guarantee: a committed hit lies in the ray's interval.
    for (r, h) in rays.iter().zip(&hits) {
        if h.prim != PRIM_NONE {
            assert!(
                h.t >= r.t_min && h.t <= r.t_max.min(f32::MAX),
                "a hit outside its interval: {r:?} {h:?}"
            );
        }
    }
    hits
}

/// Asked for where the adapter has no ray queries, the tracer is a clear error naming the
/// adapter and what would have it; `Auto` never picks it.
#[test]
fn offered_only_where_the_feature_exists() {
    let Some(gpu) = common::gpu() else { return };
    let adapter = std::env::var("GLINT_ADAPTER").ok();
    let r = glint::Renderer::with_adapter(glint::Backend::GpuRq, adapter.as_deref());
    match (gpu.has_ray_query(), r) {
        (true, Ok(r)) => assert!(r.describe().starts_with("gpu-rq: "), "{}", r.describe()),
        (false, Err(e)) => {
            let m = e.to_string();
            assert!(
                m.contains("has no ray queries") && m.contains("Mesa ≥ 24.1"),
                "{m}"
            );
            assert!(m.contains(&gpu.info.name), "{m}");
        }
        (have, r) => panic!(
            "ray queries {} but the renderer {}",
            if have { "present" } else { "absent" },
            if r.is_ok() { "was made" } else { "failed" }
        ),
    }
    let _ = rq(gpu);
    let auto = glint::Renderer::new(glint::Backend::Auto).unwrap();
    assert!(!matches!(auto.tracer(), glint::Tracer::GpuRq(_)));
}

/// Every shipped scene and four real meshes render through the driver, and agree with the
/// f64 reference on all but a reported handful of pixels (hit/miss at most 0.01 %).
#[test]
fn scenes_render_and_agree_with_f64() {
    let Some(gpu) = common::gpu() else { return };
    let Some(k) = rq(gpu) else { return };
    let mut scenes: Vec<(String, Scene)> = common::SHIPPED_SCENES
        .iter()
        .map(|n| (n.to_string(), seed_scene(n)))
        .collect();
    let dir = common::Scratch::new("rq");
    for mesh in ["teapot_npm", "bunny_npm", "suzanne", "dragon_res4"] {
        let path = dir.join(format!("{mesh}.toml"));
        let obj =
            Path::new(env!("CARGO_MANIFEST_DIR")).join(format!("tests/data/meshes/{mesh}.obj"));
        // Scaled and moved to fill the frame: its box's longest side 2, its centre at 0.
        let (mut lo, mut hi) = ([f32::MAX; 3], [f32::MIN; 3]);
        for l in std::fs::read_to_string(&obj).unwrap().lines() {
            if let Some(rest) = l.strip_prefix("v ") {
                for (k, x) in rest.split_whitespace().take(3).enumerate() {
                    let x: f32 = x.parse().unwrap();
                    lo[k] = lo[k].min(x);
                    hi[k] = hi[k].max(x);
                }
            }
        }
        let size = (0..3).map(|k| hi[k] - lo[k]).fold(0.0, f32::max);
        let sc = 2.0 / size;
        let tr: [f32; 3] = std::array::from_fn(|k| -(lo[k] + hi[k]) / 2.0 * sc);
        std::fs::write(
            &path,
            format!(
                "ambient = [0.2, 0.2, 0.2]\nshadows = true\n[camera]\neye = [0.3, 0.4, 3.0]\nlook_at = [0.0, 0.0, 0.0]\n\
                 fov = 45.0\nwidth = 320\nheight = 240\n[[lights]]\nposition = [3.0, 4.0, 5.0]\ncolor = [0.9, 0.9, 0.9]\n\
                 [materials.m]\nmodel = \"phong\"\nka = [0.3, 0.3, 0.3]\nkd = [0.6, 0.5, 0.4]\nks = [0.4, 0.4, 0.4]\nn = 20.0\n\
                 [[meshes]]\nfile = {:?}\nmaterial = \"m\"\nsmooth = true\nscale = [{sc}, {sc}, {sc}]\ntranslate = {tr:?}\n",
                obj.display().to_string()
            ),
        )
        .unwrap();
        scenes.push((mesh.to_string(), Scene::load(&path).unwrap()));
    }
    for (name, scene) in &scenes {
        let (w, h) = scene.size();
        let (w, h) = (w.min(400), h.min(300));
        let (buf, spec) = common::buffers(scene, w, h, scene.triangle);
        let img = render_rq(gpu, k, &buf, spec);
        let truth = glint::cpu::render_f64(scene, &buf, spec);
        let compute = glint::cpu::render_f32(&buf, spec);
        let d = diff(&img, &truth);
        let c = diff(&compute, &truth);
        eprintln!(
            "{name}: gpu-rq vs f64: {} hit/miss, {} px off in 8 bits, largest {:.2e}, rms {:.2e} \
             (compute tracer: {} hit/miss, {} px, largest {:.2e})",
            d.hit_miss,
            d.differing_pixels,
            d.max_abs,
            d.rms,
            c.hit_miss,
            c.differing_pixels,
            c.max_abs
        );
        assert!(img.hit_count() > 1000, "{name}: blank");
        assert!(
            d.hit_miss * 10_000 <= d.pixels,
            "{name}: {} hit/miss disagreements with f64",
            d.hit_miss
        );
    }
    // The twin: a scene with a triangle taken out disagrees on many pixels, and the count
    // sees it.
    let scene = seed_scene("mitsubishi");
    let (mut buf, spec) = common::buffers(&scene, 320, 240, scene.triangle);
    let truth = glint::cpu::render_f64(&scene, &buf, spec);
    let big = (0..buf.triangles.len())
        .max_by_key(|&k| {
            let t = &buf.triangles[k];
            let e1: [f32; 3] = std::array::from_fn(|i| t.b[i] - t.a[i]);
            let e2: [f32; 3] = std::array::from_fn(|i| t.c[i] - t.a[i]);
            let c = [
                e1[1] * e2[2] - e1[2] * e2[1],
                e1[2] * e2[0] - e1[0] * e2[2],
                e1[0] * e2[1] - e1[1] * e2[0],
            ];
            ((c[0] * c[0] + c[1] * c[1] + c[2] * c[2]) * 1e6) as u64
        })
        .unwrap();
    buf.triangles[big].a = [f32::NAN; 3];
    let holed = render_rq(gpu, k, &buf, spec);
    let d = diff(&holed, &truth);
    assert!(d.hit_miss * 10_000 > d.pixels, "the twin: {big} {d:?}");
}

/// The hard cases through the driver, beside glint's three triangle tests: the fan at the
/// origin and far away (leaks through shared edges and the apex), the closed sphere from
/// inside (escapes) and from outside (the specification's guarantee: every ray aimed at it
/// hits), with the t error against the oracle.
#[test]
fn hard_cases_measured_beside_glints_tests() {
    let Some(gpu) = common::gpu() else { return };
    let Some(k) = rq(gpu) else { return };
    for (where_, offset) in [("origin", [0.0; 3]), ("far", FAR)] {
        let tris = fan(offset);
        let rays = fan_rays(offset, 1);
        for algo in TriangleAlgorithm::ALL {
            let (buf, spec) = geometry(vec![], tris.clone(), algo);
            let ours = glint::cpu::query_f32(&buf, spec, &rays);
            let n = leaks(&tris, &rays, &ours);
            eprintln!("fan at {where_}, {algo}: {n} leaks of {}", rays.len());
        }
        let (buf, spec) = geometry(vec![], tris.clone(), TriangleAlgorithm::Watertight);
        let hits = query_rq(gpu, k, &buf, spec, &rays);
        let n = leaks(&tris, &rays, &hits);
        let (p50, p99) = t_error(&buf, &rays, &hits);
        eprintln!(
            "fan at {where_}, gpu-rq ({}): {n} leaks of {} ({:.4}%), t rel. error p50 {p50:.2e} p99 {p99:.2e}",
            gpu.info.driver_info,
            rays.len(),
            100.0 * n as f64 / rays.len() as f64
        );
    }
    for (where_, c) in [("origin", [0.0; 3]), ("far", FAR)] {
        let tris = uv_sphere(c, 2.0, 50);
        let mut rng = Rng::new(2);
        let inside = rays_from_inside(c, &mut rng, 100_000);
        // From outside, aimed at points well inside the silhouette (radius ≤ 1.5 of 2).
        let outside: Vec<RayIn> = (0..20_000)
            .map(|_| {
                let o = add([rng.range(-1.0, 1.0), rng.range(-1.0, 1.0), 8.0], c);
                let target = add([rng.range(-1.0, 1.0), rng.range(-1.0, 1.0), 0.0], c);
                ray(o, common::hard::sub(target, o))
            })
            .collect();
        let (buf, spec) = geometry(vec![], tris.clone(), TriangleAlgorithm::Watertight);
        let escaped = query_rq(gpu, k, &buf, spec, &inside)
            .iter()
            .filter(|h| h.prim == PRIM_NONE)
            .count();
        let (p50, p99) = t_error(&buf, &inside, &query_rq(gpu, k, &buf, spec, &inside));
        eprintln!(
            "closed sphere at {where_}, gpu-rq: {escaped} of {} rays from inside escaped; t rel. error p50 {p50:.2e} p99 {p99:.2e}",
            inside.len()
        );
        let missed = query_rq(gpu, k, &buf, spec, &outside)
            .iter()
            .filter(|h| h.prim == PRIM_NONE)
            .count();
        assert_eq!(
            missed, 0,
            "closed sphere at {where_}: rays from outside missed it"
        );
    }
}

/// Shared vertices on pixel rays (the height field of `tests/vertex_rays.rs`): hit/miss
/// disagreements with the f64 reference (either way: the grid's own silhouette edges
/// carry vertices too, where f64 is no oracle), beside glint's three tests' counts.
#[test]
fn vertices_on_pixel_rays_measured() {
    let Some(gpu) = common::gpu() else { return };
    let Some(k) = rq(gpu) else { return };
    for eye in [[0.0, 0.0, 0.0], [1000.0, -2000.0, 500.0]] {
        let mut line = format!("vertex grid at {eye:?}, hit/miss disagreements with f64:");
        for algo in ["naive", "moller-trumbore", "watertight"] {
            let src = vertex_grid_scene(eye, algo, 192, 160, 4);
            let scene = Scene::parse(&src, Path::new("vertex-grid.toml")).unwrap();
            let (buf, spec) = common::buffers(&scene, 192, 160, scene.triangle);
            let truth = glint::cpu::render_f64(&scene, &buf, spec);
            let leaks = |img: &glint::image::Image| {
                img.pixels
                    .iter()
                    .zip(&truth.pixels)
                    .filter(|(a, t)| (a[3] < 0.0) != (t[3] < 0.0))
                    .count()
            };
            line += &format!(" {algo} {}", leaks(&glint::cpu::render_f32(&buf, spec)));
            if algo == "watertight" {
                let img = render_rq(gpu, k, &buf, spec);
                assert!(img.hit_count() > 20_000, "the grid must fill the frame");
                line += &format!(", gpu-rq {}", leaks(&img));
            }
        }
        eprintln!("{line}");
    }
}
