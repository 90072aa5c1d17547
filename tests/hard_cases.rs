//! Numerical hard cases, every one seeded and run through the CPU f32 mirror, the shader's
//! own `query` entry point (on lavapipe bit-equal to the CPU), and the exact oracle.
//! The rates printed here are the figures quoted in `docs/robustness.md`.

mod common;

gpu_sentinel!();

use common::hard::{FAR, fan, fan_rays, leaks, ray, rays_from_inside, sub, t_error, uv_sphere};
use common::{Rng, geometry, query_both, tri};
use glint::buffers::{PRIM_NONE, RayIn, Sphere};
use glint::oracle;
use glint::scene::TriangleAlgorithm;

#[test]
fn triangle_fan_watertight_leaks_nothing() {
    let mut others = 0;
    for (where_, offset) in [("origin", [0.0; 3]), ("far", FAR)] {
        let tris = fan(offset);
        let rays = fan_rays(offset, 1);
        for algo in TriangleAlgorithm::ALL {
            let (buf, spec) = geometry(vec![], tris.clone(), algo);
            let hits = query_both(&buf, spec, &rays, &format!("fan {where_} {algo}"));
            let n = leaks(&tris, &rays, &hits);
            let (p50, p99) = t_error(&buf, &rays, &hits);
            eprintln!(
                "fan at {where_}, {algo}: {n} leaks of {} rays ({:.4}%), t rel. error p50 {p50:.2e} p99 {p99:.2e}",
                rays.len(),
                100.0 * n as f64 / rays.len() as f64
            );
            if algo == TriangleAlgorithm::Watertight {
                assert_eq!(n, 0, "watertight leaked through the fan at {where_}");
            } else {
                others += n;
            }
        }
    }
    // The twin: the leak count can be non-zero; the non-watertight tests do leak here.
    assert!(
        others > 0,
        "naive and Möller–Trumbore never leaked: the leak count is suspect"
    );
}

#[test]
fn closed_sphere_mesh_holds_every_ray() {
    let mut others = 0;
    for (where_, c) in [("origin", [0.0; 3]), ("far", FAR)] {
        let tris = uv_sphere(c, 2.0, 50);
        let mut rng = Rng::new(2);
        let rays = rays_from_inside(c, &mut rng, 100_000);
        for algo in TriangleAlgorithm::ALL {
            let (buf, spec) = geometry(vec![], tris.clone(), algo);
            assert!(spec.use_bvh, "the closed mesh is traced through the BVH");
            let hits = query_both(&buf, spec, &rays, &format!("closed sphere {where_} {algo}"));
            let escaped = hits.iter().filter(|h| h.prim == PRIM_NONE).count();
            eprintln!(
                "closed sphere at {where_}, {algo}: {escaped} of {} rays escaped",
                rays.len()
            );
            if algo == TriangleAlgorithm::Watertight {
                assert_eq!(
                    escaped, 0,
                    "rays escaped the closed mesh at {where_} with watertight"
                );
            } else {
                others += escaped;
            }
        }
    }
    eprintln!("closed sphere: naive + Möller–Trumbore escapes: {others}");
    // The naive test's known weakness far from the origin (docs/robustness.md): its
    // plane-then-barycentric test lets about 2 % of these rays through. Asserted, so the
    // figure the docs quote is what the code does.
    assert!(
        (1000..5000).contains(&others),
        "naive + Möller–Trumbore escapes changed: {others}"
    );
}

/// The twin of the closed-mesh test: the same sphere with one triangle taken out lets the
/// rays aimed at the hole escape, and the escape count sees them.
#[test]
fn sphere_mesh_with_a_hole_lets_rays_escape() {
    let mut tris = uv_sphere([0.0; 3], 2.0, 50);
    let gone = tris.remove(tris.len() / 2 + 25);
    let aim = [0, 1, 2].map(|k| (gone.a[k] + gone.b[k] + gone.c[k]) / 3.0);
    let mut rng = Rng::new(3);
    let rays: Vec<RayIn> = (0..1000)
        .map(|_| {
            let o = [0, 1, 2].map(|_| rng.range(-0.01, 0.01));
            ray(o, sub(aim, o))
        })
        .collect();
    let (buf, spec) = geometry(vec![], tris, TriangleAlgorithm::Watertight);
    let hits = query_both(&buf, spec, &rays, "sphere with a hole");
    let escaped = hits.iter().filter(|h| h.prim == PRIM_NONE).count();
    assert!(
        escaped > 900,
        "only {escaped} of 1000 rays escaped through the hole"
    );
}

#[test]
fn tiny_collinear_and_zero_area_triangles() {
    let tiny = tri([0.0, 0.0, 0.0], [1e-4, 0.0, 0.0], [0.0, 1e-4, 0.0]);
    let collinear = tri([0.0, 0.0, 0.0], [1.0, 1.0, 0.0], [2.0, 2.0, 0.0]);
    let point = tri([0.5, 0.5, 0.0], [0.5, 0.5, 0.0], [0.5, 0.5, 0.0]);
    let inside = ray([2.5e-5, 2.5e-5, 1.0], [0.0, 0.0, -1.0]);
    let mut rng = Rng::new(3);
    let many: Vec<RayIn> = (0..2000)
        .map(|_| {
            ray(
                [rng.range(-1.0, 3.0), rng.range(-1.0, 3.0), 1.0],
                [rng.range(-0.1, 0.1), rng.range(-0.1, 0.1), -1.0],
            )
        })
        .chain([
            ray([1.0, 1.0, 1.0], [0.0, 0.0, -1.0]),
            ray([0.5, 0.5, 1.0], [0.0, 0.0, -1.0]),
        ])
        .collect();
    for algo in TriangleAlgorithm::ALL {
        let (buf, spec) = geometry(vec![], vec![tiny], algo);
        let h = query_both(&buf, spec, &[inside], "tiny");
        assert_eq!(
            h[0].prim & !glint::buffers::TRIANGLE_BIT,
            0,
            "{algo}: the tiny triangle was missed"
        );
        assert!((h[0].t - 1.0).abs() < 1e-6, "{algo}: t = {}", h[0].t);
        for (name, t) in [("collinear", collinear), ("zero-area", point)] {
            let (buf, spec) = geometry(vec![], vec![t], algo);
            let hs = query_both(&buf, spec, &many, name);
            for h in &hs {
                assert_eq!(h.prim, PRIM_NONE, "{algo}: the {name} triangle was hit");
                assert!(
                    !h.t.is_nan() && !h.u.is_nan() && !h.v.is_nan(),
                    "{algo}: NaN from the {name} triangle"
                );
            }
        }
    }
}

#[test]
fn rays_parallel_to_the_plane() {
    let t = tri([-1.0, -1.0, 0.0], [1.0, -1.0, 0.0], [0.0, 1.0, 0.0]);
    let mut rays = Vec::new();
    for z in [0.0f32, 1e-7, -1e-7, 1e-3, -0.0] {
        for d in [
            [1.0, 0.0, 0.0],
            [1.0, 0.3, 0.0],
            [-0.2, -1.0, 0.0],
            [0.0, 1.0, -0.0],
        ] {
            rays.push(ray([-3.0, 0.1, z], d));
            rays.push(ray([0.0, -3.0, z], d));
        }
    }
    for algo in TriangleAlgorithm::ALL {
        let (buf, spec) = geometry(vec![], vec![t], algo);
        for (r, h) in rays.iter().zip(query_both(&buf, spec, &rays, "parallel")) {
            assert_eq!(h.prim, PRIM_NONE, "{algo}: parallel ray {r:?} hit");
            assert!(!h.t.is_nan(), "{algo}: NaN");
        }
    }
}

/// Rays aimed at points (1 ± δ)·r from the centre of a unit sphere at distance D, δ in
/// [2e-3, 5e-2]: clear of the tangent by more than f32 can blur at D = 1e4.
#[test]
fn far_sphere_silhouettes_agree_with_the_oracle() {
    for dist in [1e2f32, 1e3, 1e4] {
        let s = Sphere {
            center: [0.0, 0.0, -dist],
            radius: 1.0,
            ..Default::default()
        };
        let mut rng = Rng::new(4);
        let rays: Vec<RayIn> = (0..20_000)
            .map(|_| {
                let a = rng.unit() * std::f64::consts::TAU;
                let delta = 2e-3 + (5e-2 - 2e-3) * rng.unit();
                let rr = if rng.unit() < 0.5 {
                    1.0 - delta
                } else {
                    1.0 + delta
                };
                let target = [(rr * a.cos()) as f32, (rr * a.sin()) as f32, -dist];
                ray([0.0, 0.0, 0.0], target)
            })
            .collect();
        let (buf, spec) = geometry(vec![s], vec![], TriangleAlgorithm::MollerTrumbore);
        let hits = query_both(&buf, spec, &rays, "far sphere");
        // The exact (interval) answer: every ray here is far enough from the tangent for
        // it to be certain, and the sphere lies ahead, so a line hit is a ray hit.
        let oracle: Vec<bool> = rays
            .iter()
            .map(|r| oracle::sphere_line_hit(r, &s).expect("the oracle is certain here"))
            .collect();
        let formula_f64 = rays
            .iter()
            .zip(&oracle)
            .filter(|(r, o)| oracle::hit_sphere(r, &s).is_some() != **o)
            .count();
        assert_eq!(
            formula_f64, 0,
            "the f64 formula disagrees with the exact test"
        );
        let stable = hits
            .iter()
            .zip(&oracle)
            .filter(|(h, o)| (h.prim != PRIM_NONE) != **o)
            .count();
        let textbook = rays
            .iter()
            .zip(&oracle)
            .filter(|(r, o)| {
                let rr = glint::cpu::trace::Ray {
                    origin: r.origin.into(),
                    dir: r.dir.into(),
                };
                (glint::cpu::prims::hit_sphere_textbook::<f32>(rr, &s, 0.0, f32::MAX) < f32::MAX)
                    != **o
            })
            .count();
        let hit_count = oracle.iter().filter(|&&o| o).count();
        eprintln!(
            "unit sphere at {dist:e}: stable {stable}, textbook {textbook} hit/miss disagreements of {} rays ({hit_count} hits)",
            rays.len()
        );
        assert!(
            hit_count > 5000 && hit_count < 15_000,
            "the rays do not straddle the silhouette"
        );
        assert_eq!(
            stable, 0,
            "stable sphere test disagrees with the oracle at {dist}"
        );
    }
}

/// The sphere oracle's known answers: a ray exactly tangent is "unsure", one f32 step
/// outside is a miss, one step inside a hit.
#[test]
fn sphere_oracle_known_answers() {
    let s = Sphere {
        center: [0.0, 0.0, -10.0],
        radius: 1.0,
        ..Default::default()
    };
    let at = |y: f32| oracle::sphere_line_hit(&ray([0.0, y, 0.0], [0.0, 0.0, -1.0]), &s);
    assert_eq!(at(1.0), None);
    assert_eq!(at(1.0f32.next_up()), Some(false));
    assert_eq!(at(1.0f32.next_down()), Some(true));
    assert_eq!(at(0.0), Some(true));
    assert_eq!(at(2.0), Some(false));
}

#[test]
fn rays_from_inside_and_on_a_sphere() {
    let s = Sphere {
        center: [1.0, 2.0, 3.0],
        radius: 2.0,
        ..Default::default()
    };
    let (buf, spec) = geometry(vec![s], vec![], TriangleAlgorithm::MollerTrumbore);
    let rays = [
        ray([1.0, 2.0, 3.0], [0.0, 0.0, 1.0]),  // centre: exit at t = 2
        ray([1.5, 2.0, 3.0], [-1.0, 0.0, 0.0]), // inside: exit at t = 2.5
        ray([3.0, 2.0, 3.0], [-1.0, 0.0, 0.0]), // on the surface, inward: t = 4
        ray([3.0, 2.0, 3.0], [1.0, 0.0, 0.0]),  // on the surface, outward
    ];
    let h = query_both(&buf, spec, &rays, "inside sphere");
    assert_eq!((h[0].prim, h[0].t), (0, 2.0));
    assert_eq!((h[1].prim, h[1].t), (0, 2.5));
    assert_eq!((h[2].prim, h[2].t), (0, 4.0));
    assert!(
        h[3].prim == PRIM_NONE || h[3].t < 1e-6,
        "outward from the surface: {:?}",
        h[3]
    );
}

#[test]
fn axis_aligned_rays_and_negative_zero() {
    let t = tri([-1.0, -1.0, 0.0], [1.0, -1.0, 0.0], [0.0, 1.0, 0.0]);
    let s = Sphere {
        center: [0.0, 0.0, -5.0],
        radius: 1.0,
        ..Default::default()
    };
    let rays: Vec<RayIn> = [
        [0.0, 0.0, -1.0],
        [-0.0, 0.0, -1.0],
        [0.0, -0.0, -1.0],
        [-0.0, -0.0, -1.0],
    ]
    .iter()
    .map(|&d| ray([0.0, 0.0, 2.0], d))
    .chain([
        ray([-0.0, -0.0, 2.0], [0.0, 0.0, -1.0]),
        ray([0.0, 0.0, -2.0], [-0.0, 0.0, 1.0]),
    ])
    .collect();
    for algo in TriangleAlgorithm::ALL {
        let (buf, spec) = geometry(vec![s], vec![t], algo);
        for (r, h) in rays
            .iter()
            .zip(query_both(&buf, spec, &rays, "axis-aligned"))
        {
            assert_eq!(
                h.prim,
                glint::buffers::TRIANGLE_BIT,
                "{algo}: {r:?} missed the triangle"
            );
            assert_eq!(h.t, 2.0, "{algo}: {r:?}");
        }
        let (buf, spec) = geometry(vec![s], vec![], algo);
        let h = query_both(&buf, spec, &rays[..4], "axis-aligned sphere");
        assert!(h.iter().all(|h| h.prim == 0 && h.t == 6.0), "{algo}: {h:?}");
    }
}

#[test]
fn nan_and_infinite_rays_hit_nothing() {
    let t = tri([-1.0, -1.0, 0.0], [1.0, -1.0, 0.0], [0.0, 1.0, 0.0]);
    let s = Sphere {
        center: [0.0, 0.0, -5.0],
        radius: 1.0,
        ..Default::default()
    };
    let (nan, inf) = (f32::NAN, f32::INFINITY);
    let rays = [
        ray([nan, 0.0, 2.0], [0.0, 0.0, -1.0]),
        ray([0.0, 0.0, 2.0], [nan, nan, nan]),
        ray([inf, 0.0, 2.0], [0.0, 0.0, -1.0]),
        ray([0.0, 0.0, 2.0], [0.0, 0.0, -inf]),
        ray([0.0, 0.0, 2.0], [inf, -inf, inf]),
        ray([-inf, inf, nan], [nan, inf, 0.0]),
        ray([0.0, 0.0, 2.0], [0.0, 0.0, 0.0]),
    ];
    for algo in TriangleAlgorithm::ALL {
        let (buf, spec) = geometry(vec![s], vec![t], algo);
        for (r, h) in rays.iter().zip(query_both(&buf, spec, &rays, "nan rays")) {
            assert_eq!(h.prim, PRIM_NONE, "{algo}: {r:?} hit something: {h:?}");
        }
    }
}
