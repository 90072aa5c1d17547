//! Real meshes through the BVH: the same nearest hit (primitive id and t, bit for bit) as
//! testing every triangle, on the CPU and through the shader's `query` entry point; and a
//! mesh scene rendered on the GPU equal to the CPU mirror.
//!
//! The four small meshes live in `tests/data/meshes/` (sources and licences in its README).

mod common;

gpu_sentinel!();

use std::path::{Path, PathBuf};

use common::{Rng, check_agreement, query_both, render_gpu};
use glint::buffers::{PRIM_NONE, RayIn, SceneBuffers, Specialisation};
use glint::scene::{Scene, TriangleAlgorithm};

const MESHES: [&str; 4] = ["teapot_npm", "bunny_npm", "suzanne", "dragon_res4"];

fn mesh_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/meshes")
}

/// A scene of one mesh (and whatever `extra` adds), as if written beside the mesh.
fn mesh_scene(mesh: &str, extra: &str) -> Scene {
    let src = format!(
        r#"
ambient = [0.2, 0.2, 0.2]
[camera]
eye = [0.0, 0.0, 5.0]
look_at = [0.0, 0.0, 0.0]
up = [0.0, 1.0, 0.0]
fov = 45.0
width = 64
height = 48
[materials.m]
model = "phong"
ka = [0.3, 0.2, 0.1]
kd = [0.6, 0.5, 0.4]
ks = [0.5, 0.5, 0.5]
n = 20.0
[[meshes]]
file = "{mesh}.obj"
material = "m"
{extra}
"#
    );
    Scene::parse(&src, &mesh_dir().join(format!("{mesh}.toml"))).unwrap_or_else(|e| panic!("{e}"))
}

/// Bounds of the scene's triangles.
fn bounds(buf: &SceneBuffers) -> ([f32; 3], [f32; 3]) {
    let mut lo = [f32::MAX; 3];
    let mut hi = [f32::MIN; 3];
    for t in &buf.triangles {
        for p in [t.a, t.b, t.c] {
            for k in 0..3 {
                lo[k] = lo[k].min(p[k]);
                hi[k] = hi[k].max(p[k]);
            }
        }
    }
    (lo, hi)
}

/// Rays from outside the mesh's box aimed at points inside it, and rays from inside the
/// box in every direction.
fn rays_at(buf: &SceneBuffers, n: usize, seed: u64) -> Vec<RayIn> {
    let (lo, hi) = bounds(buf);
    let size = (0..3).map(|k| hi[k] - lo[k]).fold(0.0, f32::max);
    let mut rng = Rng::new(seed);
    let inside = |rng: &mut Rng| [0, 1, 2].map(|k| rng.range(lo[k], hi[k]));
    (0..n)
        .map(|i| {
            let target = inside(&mut rng);
            let (origin, dir) = if i % 4 == 3 {
                let d = [0, 1, 2].map(|_| rng.range(-1.0, 1.0));
                (target, d)
            } else {
                let d = [0, 1, 2].map(|_| rng.range(-1.0, 1.0));
                let o = [0, 1, 2].map(|k| target[k] - d[k] * 3.0 * size);
                (o, [0, 1, 2].map(|k| target[k] - o[k]))
            };
            RayIn {
                origin,
                t_min: 0.0,
                dir,
                t_max: f32::MAX,
            }
        })
        .collect()
}

#[test]
fn bvh_gives_the_brute_force_nearest_hit_on_real_meshes() {
    for (m, mesh) in MESHES.iter().enumerate() {
        let scene = mesh_scene(mesh, "");
        for algo in TriangleAlgorithm::ALL {
            let buf = SceneBuffers::new(&scene, 64, 48, algo);
            let spec = Specialisation::for_scene(&buf);
            assert!(spec.use_bvh, "{mesh}: the BVH must be in use");
            let rays = rays_at(&buf, 8_000, m as u64 + 1);
            // query_both: BVH == every triangle (CPU), and GPU == CPU bit for bit on lavapipe.
            let hits = query_both(&buf, spec, &rays, &format!("{mesh} {algo}"));
            let n_hit = hits.iter().filter(|h| h.prim != PRIM_NONE).count();
            eprintln!(
                "{mesh} ({} triangles, {} nodes) {algo}: {n_hit} of {} rays hit",
                buf.triangles.len(),
                buf.nodes.len(),
                rays.len()
            );
            assert!(n_hit > rays.len() / 4, "{mesh}: too few hits to mean much");
        }
    }
}

/// The twin: a BVH whose box was shrunk (a node that no longer holds its primitives)
/// gives different nearest hits, and the comparison sees it.
#[test]
fn a_broken_bvh_is_caught() {
    let scene = mesh_scene("suzanne", "");
    let mut buf = SceneBuffers::new(&scene, 64, 48, TriangleAlgorithm::Watertight);
    let spec = Specialisation::for_scene(&buf);
    let rays = rays_at(&buf, 4_000, 9);
    let good = glint::cpu::query_f32(&buf, spec, &rays);
    // Shrink the root's first child to a point: its whole subtree disappears.
    let c = &mut buf.nodes[1];
    c.hi = c.lo;
    let broken = glint::cpu::query_f32(&buf, spec, &rays);
    let brute = glint::cpu::query_f32(&buf, spec.with_bvh(false), &rays);
    let differ = |a: &[glint::buffers::HitOut], b: &[glint::buffers::HitOut]| {
        a.iter()
            .zip(b)
            .filter(|(x, y)| bytemuck::bytes_of(*x) != bytemuck::bytes_of(*y))
            .count()
    };
    assert_eq!(differ(&good, &brute), 0);
    assert!(
        differ(&broken, &brute) > 100,
        "a broken BVH must differ from brute force"
    );
}

#[test]
fn mesh_scene_with_shadows_gpu_equals_cpu() {
    let extra = r#"
[[meshes]]
file = "teapot_npm.obj"
material = "m"
scale = [0.05, 0.05, 0.05]
translate = [1.2, -0.6, 0.5]
[[spheres]]
center = [-1.4, 0.6, -0.5]
radius = 0.5
material = "m"
[[lights]]
position = [3.0, 4.0, 5.0]
color = [0.8, 0.8, 0.8]
[[lights]]
position = [-4.0, 1.0, 3.0]
color = [0.3, 0.3, 0.4]
"#;
    let mut scene = mesh_scene("suzanne", extra);
    scene.shadows = true;
    for algo in TriangleAlgorithm::ALL {
        let buf = SceneBuffers::new(&scene, 160, 120, algo);
        let spec = Specialisation::for_scene(&buf);
        assert!(spec.use_bvh);
        let cpu = glint::cpu::render_f32(&buf, spec);
        let brute = glint::cpu::render_f32(&buf, spec.with_bvh(false));
        assert!(
            cpu.hit_count() > 3000,
            "{algo}: the mesh must fill the frame"
        );
        let d = glint::compare::diff(&cpu, &brute);
        assert!(
            d.bit_exact(),
            "{algo}: BVH and brute-force images differ: {d:?}"
        );
        let Some(gpu) = common::gpu() else { continue };
        let g = render_gpu(gpu, &buf, spec);
        let d = check_agreement(&g, &cpu, common::bit_exact_expected(gpu))
            .unwrap_or_else(|e| panic!("{algo}: {e}"));
        eprintln!(
            "suzanne + teapot + sphere, shadows, {algo}: GPU vs CPU {} differing pixels, {} hit/miss",
            d.differing_pixels, d.hit_miss
        );
    }
}
