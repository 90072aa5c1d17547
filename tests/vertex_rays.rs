//! Vertices on pixel rays: a height field whose shared vertices lie on the tracer's own
//! camera rays (to an ulp), near and far from the origin, with every triangle algorithm.
//! The GPU image equals the CPU mirror's in every bit, hit distance included, on lavapipe.

mod common;

gpu_sentinel!();

use std::path::Path;

use common::{check_agreement, render_gpu, vertex_grid_scene};
use glint::buffers::{SceneBuffers, Specialisation};
use glint::scene::Scene;

#[test]
fn vertex_grid_gpu_equals_cpu() {
    let gpu = common::gpu();
    for eye in [
        [0.0, 0.0, 0.0],
        [0.25, -0.5, 0.75],
        [1000.0, -2000.0, 500.0],
    ] {
        for algo in ["naive", "moller-trumbore", "watertight"] {
            let src = vertex_grid_scene(eye, algo, 192, 160, 4);
            let scene = Scene::parse(&src, Path::new("vertex-grid.toml")).unwrap();
            let buf = SceneBuffers::new(&scene, 192, 160, scene.triangle);
            let spec = Specialisation::for_scene(&buf);
            let cpu = glint::cpu::render_f32(&buf, spec);
            assert!(
                cpu.hit_count() > 20_000,
                "{algo} at {eye:?}: the grid must fill the frame"
            );
            if let Some(gpu) = gpu {
                let g = render_gpu(gpu, &buf, spec);
                let d = check_agreement(&g, &cpu, common::bit_exact_expected(gpu))
                    .unwrap_or_else(|e| panic!("{algo} at {eye:?}: {e}"));
                eprintln!("{algo} at {eye:?}: {d:?}");
            }
        }
    }
}
