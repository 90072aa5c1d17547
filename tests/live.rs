//! The library's live view (`glint::render::Live`, what `glint view` draws with): the
//! CPU refinement converges to the full render in every bit, and the GPU's frames equal it
//! (every bit on lavapipe); a moved camera renders as a scene with that camera does; a
//! reloaded scene keeps its BVH exactly when its primitives are unchanged, and its buffers
//! are then those of a fresh load.

mod common;

gpu_sentinel!();

use common::{buffers, check_agreement};
use glint::buffers::SceneBuffers;
use glint::render::{Live, Rebuilt};
use glint::scene::Scene;
use glint::{Backend, Renderer};

fn bits(pixels: &[[f32; 4]]) -> Vec<u32> {
    pixels.iter().flatten().map(|x| x.to_bits()).collect()
}

/// bb8-aa at 96×72 (4×4 samples): after its 16 CPU steps the picture is `render_f32`'s in
/// every bit; after 15 it is not (the twin). The GPU's one step equals it too.
#[test]
fn refinement_converges_to_the_render() {
    let scene = common::seed_scene("bb8-aa");
    let (buf, spec) = buffers(&scene, 96, 72, scene.triangle);
    let want = glint::cpu::render_f32(&buf, spec);
    let cpu = Renderer::new(Backend::Cpu).unwrap();
    let mut live = Live::new(scene.clone(), 96, 72);
    assert_eq!(live.samples(), (0, 16));
    for k in 1..=16 {
        live.step(&cpu).unwrap();
        assert_eq!(live.samples(), (k, 16));
        let same = bits(&live.image().pixels) == bits(&want.pixels);
        assert_eq!(same, k == 16, "after {k} of 16 sample positions");
    }
    assert!(live.converged());
    if let Some(gpu) = common::gpu() {
        let r = Renderer::from_gpu(
            Backend::Gpu,
            glint::gpu::Gpu::from_device(gpu.info.clone(), gpu.device.clone(), gpu.queue.clone())
                .unwrap(),
        )
        .unwrap();
        let mut live = Live::new(scene, 96, 72);
        live.step(&r).unwrap();
        assert!(live.converged());
        check_agreement(live.image(), &want, common::is_lavapipe(gpu)).unwrap();
    }
}

/// An orbit, a pan, a zoom and a fly later, the picture is the render of the scene with
/// the camera `camera_toml` prints. The twin: the scene's own camera renders otherwise.
#[test]
fn a_moved_camera_renders_as_its_scene_file_does() {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/bb8.toml");
    let text = std::fs::read_to_string(&path).unwrap();
    let scene = Scene::parse(&text, &path).unwrap();
    let cpu = Renderer::new(Backend::Cpu).unwrap();
    let mut live = Live::new(scene.clone(), 800, 600);
    assert!(live.orbit(25.0, -10.0));
    assert!(live.pan(0.05, 0.02));
    assert!(live.zoom(0.8));
    assert!(live.fly(0.1, -0.05, 0.02));
    live.step(&cpu).unwrap();
    let start = text.find("[camera]").unwrap();
    let end = start + text[start..].find("\n[[").unwrap() + 1;
    let moved = format!("{}{}\n{}", &text[..start], live.camera_toml(), &text[end..]);
    let moved = Scene::parse(&moved, &path).unwrap();
    let want = cpu.render(&moved, &Default::default()).unwrap();
    assert!(bits(&live.image().pixels) == bits(&want.pixels));
    let home = cpu.render(&scene, &Default::default()).unwrap();
    assert!(bits(&live.image().pixels) != bits(&home.pixels), "the twin");
    // R: back to the scene's camera, and its picture.
    live.reset_camera();
    live.step(&cpu).unwrap();
    assert!(bits(&live.image().pixels) == bits(&home.pixels));
}

/// A scene with another light colour keeps the BVH (and its buffers equal a fresh
/// load's); one with a sphere moved gets a new one. The twin of the equality: the moved
/// scene's buffers differ from the old ones.
#[test]
fn a_reload_keeps_the_bvh_only_for_the_same_primitives() {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/bb8.toml");
    let text = std::fs::read_to_string(&path).unwrap();
    let scene = Scene::parse(&text, &path).unwrap();
    let recolored = Scene::parse(
        &text.replacen("color = [1.0, 0.8, 0.1]", "color = [0.2, 0.9, 0.3]", 1),
        &path,
    )
    .unwrap();
    let mut moved = scene.clone();
    moved.spheres[0].center[0] += 0.25;
    let old = || SceneBuffers::new(&scene, 80, 60, scene.triangle);
    let (kept, same) = SceneBuffers::new_reusing(&recolored, 80, 60, recolored.triangle, old());
    assert!(same);
    assert_eq!(
        kept,
        SceneBuffers::new(&recolored, 80, 60, recolored.triangle)
    );
    let (fresh, same) = SceneBuffers::new_reusing(&moved, 80, 60, moved.triangle, old());
    assert!(!same);
    assert_eq!(fresh, SceneBuffers::new(&moved, 80, 60, moved.triangle));
    assert_ne!(fresh.nodes, old().nodes, "the twin: a new BVH");
    let cpu = Renderer::new(Backend::Cpu).unwrap();
    let mut live = Live::new(scene, 80, 60);
    live.step(&cpu).unwrap();
    assert_eq!(live.replace_scene(recolored), Rebuilt::Shading);
    assert_eq!(live.replace_scene(moved), Rebuilt::Geometry);
}
