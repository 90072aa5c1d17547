//! Hard shadows: no self-shadowing on a huge floor, contact shadows without gaps, thin
//! occluders that cast, several lights, and GPU = CPU bit for bit with shadows on.

mod common;

gpu_sentinel!();

use common::{buffers, check_agreement, render_gpu};
use glint::buffers::PRIM_NONE;
use glint::cpu::prims;
use glint::cpu::real::V3;
use glint::cpu::trace::{self, Camera, Globals, Ray};
use glint::scene::{Scene, TriangleAlgorithm};

fn scene(body: &str, shadows: bool) -> Scene {
    let src = format!("ambient = [0.1, 0.1, 0.1]\nshadows = {shadows}\n{body}");
    Scene::parse(&src, "shadows.toml".as_ref()).unwrap_or_else(|e| panic!("{e}"))
}

const FLOOR: &str = r#"
[camera]
eye = [3.3, 7.1, 5.7]
look_at = [0.0, 0.0, 0.0]
fov = 60.0
width = 320
height = 240
[[lights]]
position = [1.7, 50.3, 2.9]
color = [1.0, 1.0, 1.0]
[materials.floor]
model = "diffuse"
ka = [1.0, 1.0, 1.0]
kd = [0.8, 0.8, 0.8]
[[triangles]]
vertices = [[-2e4, 0.0, -2e4], [0.0, 0.0, 2e4], [2e4, 0.0, -2e4]]
material = "floor"
"#;

/// A square over the floor, between it and the light, for the floor test's twin.
const BLOCKER: &str = r#"
[[triangles]]
vertices = [[-2.0, 20.0, -2.0], [2.0, 20.0, -2.0], [0.0, 20.0, 2.0]]
material = "floor"
"#;

/// The self-shadowed pixel rate of each offset scheme on the floor: glint's (0 required)
/// and the simpler ones it replaced (reported).
#[test]
fn huge_floor_casts_no_shadow_on_itself() {
    let s = scene(FLOOR, true);
    for algo in TriangleAlgorithm::ALL {
        let (buf, spec) = buffers(&s, 320, 240, algo);
        let g = Globals {
            cam: Camera::from_params(&buf.params),
            buf: &buf,
            spec,
            count: glint::cpu::count::NoCount,
        };
        let light = V3::from_f32(buf.lights[0].position);
        let mut counts = [0usize; 4];
        let mut floor = 0;
        for j in 0..240 {
            for i in 0..320 {
                let ray = trace::camera_ray(&g, i, j, 0.5, 0.5);
                let hit = trace::closest_hit(&g, ray, 0.0, f32::MAX);
                if hit.prim == PRIM_NONE {
                    continue;
                }
                floor += 1;
                let p = ray.origin + ray.dir * hit.t;
                let mut n = prims::prim_normal(&g, &hit, p);
                if n.dot(ray.dir) > 0.0 {
                    n = -n;
                }
                // (origin, t_min, skip): glint's, then the simpler schemes it replaced.
                let schemes: [(V3<f32>, f32, u32); 4] = [
                    (trace::shadow_origin(p, n), 0.0, hit.prim), // glint: skip self + offset along n
                    (p + n * 1e-4, 0.0, PRIM_NONE),              // fixed epsilon along the normal
                    (trace::shadow_origin(p, n), 0.0, PRIM_NONE), // along n, scaled by |p|, no skip
                    (p, 1e-4, PRIM_NONE),                        // fixed t_min along the ray
                ];
                for (k, (o, t_min, skip)) in schemes.into_iter().enumerate() {
                    let d = light - o;
                    counts[k] += trace::occluded(&g, Ray { origin: o, dir: d }, t_min, 1.0, skip, 0)
                        as usize;
                }
            }
        }
        let rate = |c: usize| 100.0 * c as f64 / floor as f64;
        eprintln!(
            "{algo}: self-shadowed floor pixels of {floor}: glint {} ({:.3}%), fixed 1e-4 along n {} ({:.3}%), \
             64ε·|p| along n without skip {} ({:.3}%), t_min 1e-4 {} ({:.3}%)",
            counts[0],
            rate(counts[0]),
            counts[1],
            rate(counts[1]),
            counts[2],
            rate(counts[2]),
            counts[3],
            rate(counts[3])
        );
        assert!(floor > 30_000, "the floor fills too little of the frame");
        // The twin: the same scheme with a blocker between the floor and the light shadows
        // the floor under it (a shadow test that never blocks would fail here).
        let blocked = {
            let s2 = scene(&format!("{FLOOR}{BLOCKER}"), true);
            let (buf2, spec2) = buffers(&s2, 320, 240, algo);
            let lit = glint::cpu::render_f32(&buf2, spec2);
            lit.pixels
                .iter()
                .filter(|p| p[3] >= 0.0 && p[0] < 0.15)
                .count()
        };
        assert!(
            blocked > 1000,
            "{algo}: a blocker casts no shadow ({blocked} pixels)"
        );
        assert_eq!(
            counts[0], 0,
            "{algo}: glint's offset self-shadows the floor"
        );
        // The shadowed render equals the unshadowed one: nothing on the floor is shadowed.
        let img_on = glint::cpu::render_f32(&buf, spec);
        let (buf_off, spec_off) = buffers(&scene(FLOOR, false), 320, 240, algo);
        assert_eq!(
            img_on,
            glint::cpu::render_f32(&buf_off, spec_off),
            "{algo}: shadows changed the lit floor"
        );
    }
}

const SPHERE_ON_FLOOR: &str = r#"
[camera]
eye = [0.0, 3.0, 7.0]
look_at = [0.0, 0.5, 0.0]
fov = 40.0
width = 320
height = 240
[[lights]]
position = [4.0, 8.0, 2.0]
color = [1.0, 1.0, 1.0]
[materials.m]
model = "diffuse"
ka = [1.0, 1.0, 1.0]
kd = [0.8, 0.8, 0.8]
[[spheres]]
center = [0.0, 1.0, 0.0]
radius = 1.0
material = "m"
[[triangles]]
vertices = [[-50.0, 0.0, -50.0], [0.0, 0.0, 50.0], [50.0, 0.0, -50.0]]
material = "m"
"#;

/// Floor pixels the tracer calls lit where the exact f64 test says the sphere blocks the
/// light: a lit gap in the contact shadow. At most the pixels the boundary runs through.
#[test]
fn contact_shadow_has_no_lit_gap() {
    let s = scene(SPHERE_ON_FLOOR, true);
    let (buf, spec) = buffers(&s, 320, 240, TriangleAlgorithm::Watertight);
    let g = Globals {
        cam: Camera::from_params(&buf.params),
        buf: &buf,
        spec,
        count: glint::cpu::count::NoCount,
    };
    let img = glint::cpu::render_f32(&buf, spec);
    let light = [4.0f64, 8.0, 2.0];
    let (mut leaks, mut shadowed) = (0, 0);
    for j in 0..240u32 {
        for i in 0..320u32 {
            let ray = trace::camera_ray(&g, i, j, 0.5, 0.5);
            let hit = trace::closest_hit(&g, ray, 0.0, f32::MAX);
            if hit.prim != glint::buffers::TRIANGLE_BIT {
                continue;
            }
            let p = ray.origin + ray.dir * hit.t;
            let p = [p.x as f64, 0.0, p.z as f64];
            // Exact enough: distance from the centre (0,1,0) to the segment p → light, in f64.
            let d = [light[0] - p[0], light[1] - p[1], light[2] - p[2]];
            let f = [p[0], p[1] - 1.0, p[2]];
            let t = (-(f[0] * d[0] + f[1] * d[1] + f[2] * d[2])
                / (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]))
                .clamp(0.0, 1.0);
            let q = [f[0] + d[0] * t, f[1] + d[1] * t, f[2] + d[2] * t];
            let dist = (q[0] * q[0] + q[1] * q[1] + q[2] * q[2]).sqrt();
            let lit = img.pixels[(j * 320 + i) as usize][0] > 0.1 + 1e-6;
            if dist < 1.0 - 1e-3 {
                shadowed += 1;
                leaks += lit as usize;
            }
        }
    }
    eprintln!("contact shadow: {shadowed} shadowed floor pixels, {leaks} lit by mistake");
    assert!(shadowed > 500, "no shadow to test");
    assert_eq!(leaks, 0, "light leaks into the contact shadow");
}

/// A slab of two triangles 1e-3 apart casts a shadow, and its lit top does not shadow itself.
#[test]
fn thin_slab_casts_a_shadow() {
    let body = r#"
[camera]
eye = [0.0, 6.0, 6.0]
look_at = [0.0, 0.0, 0.0]
fov = 45.0
width = 160
height = 120
[[lights]]
position = [0.0, 20.0, 0.0]
color = [1.0, 1.0, 1.0]
[[lights]]
position = [30.0, 20.0, 0.0]
color = [0.5, 0.5, 0.5]
[materials.m]
model = "diffuse"
ka = [1.0, 1.0, 1.0]
kd = [0.8, 0.8, 0.8]
[[triangles]]
vertices = [[-20.0, 0.0, -20.0], [0.0, 0.0, 20.0], [20.0, 0.0, -20.0]]
material = "m"
[[triangles]]
vertices = [[-1.0, 1.0, -1.0], [1.0, 1.0, -1.0], [0.0, 1.0, 1.0]]
material = "m"
[[triangles]]
vertices = [[-1.0, 1.001, -1.0], [1.0, 1.001, -1.0], [0.0, 1.001, 1.0]]
material = "m"
"#;
    let on = scene(body, true);
    let off = scene(body, false);
    for algo in TriangleAlgorithm::ALL {
        let (b1, s1) = buffers(&on, 160, 120, algo);
        let (b0, s0) = buffers(&off, 160, 120, algo);
        let (a, b) = (
            glint::cpu::render_f32(&b1, s1),
            glint::cpu::render_f32(&b0, s0),
        );
        let changed = a
            .pixels
            .iter()
            .zip(&b.pixels)
            .filter(|(x, y)| x != y)
            .count();
        // The pixels whose primary ray hits the slab's top (triangle 2): they face both
        // lights and must be unchanged by shadows.
        let g = Globals {
            cam: Camera::from_params(&b1.params),
            buf: &b1,
            spec: s1,
            count: glint::cpu::count::NoCount,
        };
        let top: Vec<bool> = (0..120u32)
            .flat_map(|j| (0..160u32).map(move |i| (i, j)))
            .map(|(i, j)| {
                let hit =
                    trace::closest_hit(&g, trace::camera_ray(&g, i, j, 0.5, 0.5), 0.0, f32::MAX);
                hit.prim == glint::buffers::TRIANGLE_BIT | 2
            })
            .collect();
        let top_pixels = top.iter().filter(|&&t| t).count();
        let self_shadowed = |a: &glint::image::Image| {
            a.pixels
                .iter()
                .zip(&b.pixels)
                .zip(&top)
                .filter(|((x, y), t)| **t && x != y)
                .count()
        };
        let top_changed = self_shadowed(&a);
        eprintln!(
            "{algo}: thin slab shadows {changed} pixels; top: {top_pixels} pixels, self-shadowed: {top_changed}"
        );
        assert!(changed > 200, "{algo}: the slab casts no shadow");
        assert!(top_pixels > 300, "{algo}: the slab's top is not in view");
        assert_eq!(top_changed, 0, "{algo}: the slab shadows its own lit face");
        // The twin: the top's pixels darkened (as a self-shadow would) fail the check.
        let mut dark = a.clone();
        for (p, t) in dark.pixels.iter_mut().zip(&top) {
            if *t {
                p[0] *= 0.5;
            }
        }
        assert_eq!(self_shadowed(&dark), top_pixels);
        if let Some(gpu) = common::gpu() {
            check_agreement(
                &render_gpu(gpu, &b1, s1),
                &a,
                common::bit_exact_expected(gpu),
            )
            .unwrap();
        }
    }
}

/// The shadowed seed variants agree bit for bit between GPU and CPU.
#[test]
fn shadow_scenes_agree_gpu_cpu() {
    let Some(gpu) = common::gpu() else { return };
    for name in ["bb8-shadows", "mitsubishi-shadows"] {
        let s = common::seed_scene(name);
        assert!(s.shadows);
        for algo in TriangleAlgorithm::ALL {
            let (buf, spec) = buffers(&s, 320, 240, algo);
            let g = render_gpu(gpu, &buf, spec);
            let c = glint::cpu::render_f32(&buf, spec);
            assert!(!g.is_blank());
            check_agreement(&g, &c, common::bit_exact_expected(gpu))
                .unwrap_or_else(|e| panic!("{name}/{algo}: {e}"));
        }
    }
}
