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
        check_agreement(live.image(), &want, common::bit_exact_expected(gpu)).unwrap();
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

/// The pixels of an `Rgba8Unorm` texture, packed as `pack_rgba8` packs them.
fn read_texture(gpu: &glint::gpu::Gpu, t: &wgpu::Texture) -> Vec<u32> {
    let (w, h) = (t.width(), t.height());
    let row =
        (4 * w).div_ceil(wgpu::COPY_BYTES_PER_ROW_ALIGNMENT) * wgpu::COPY_BYTES_PER_ROW_ALIGNMENT;
    let buffer = gpu.device.create_buffer(&wgpu::BufferDescriptor {
        label: None,
        size: row as u64 * h as u64,
        usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
        mapped_at_creation: false,
    });
    let mut enc = gpu.device.create_command_encoder(&Default::default());
    enc.copy_texture_to_buffer(
        t.as_image_copy(),
        wgpu::TexelCopyBufferInfo {
            buffer: &buffer,
            layout: wgpu::TexelCopyBufferLayout {
                offset: 0,
                bytes_per_row: Some(row),
                rows_per_image: Some(h),
            },
        },
        t.size(),
    );
    gpu.queue.submit([enc.finish()]);
    buffer
        .slice(..)
        .map_async(wgpu::MapMode::Read, |r| r.unwrap());
    gpu.device
        .poll(wgpu::PollType::wait_indefinitely())
        .unwrap();
    let data = buffer.slice(..).get_mapped_range().unwrap();
    (0..h as usize)
        .flat_map(|y| {
            data[y * row as usize..y * row as usize + 4 * w as usize]
                .chunks_exact(4)
                .map(|p| u32::from_le_bytes([p[0], p[1], p[2], p[3]]))
                .collect::<Vec<_>>()
        })
        .collect()
}

/// On a GPU, frames traced straight into a texture (the scene kept on the device, only the
/// parameters written for a moved camera) hold the packed pixels of the CPU mirror's
/// render of the same camera, in every byte on lavapipe; at a width whose rows are not a
/// multiple of the copy alignment too (row-by-row copies). The twin: the first frame's
/// pixels are not the moved camera's.
#[test]
fn frames_traced_into_a_texture_are_the_renders() {
    let Some(g) = common::gpu() else { return };
    let renderer = Renderer::from_gpu(
        Backend::Gpu,
        glint::gpu::Gpu::from_device(g.info.clone(), g.device.clone(), g.queue.clone()).unwrap(),
    )
    .unwrap();
    let glint::Tracer::Gpu(gpu) = renderer.tracer() else {
        panic!("a GPU renderer")
    };
    for (name, (w, h)) in [("bb8", (128, 96)), ("textured", (100, 75))] {
        let scene = common::seed_scene(name);
        let texture = gpu.device.create_texture(&wgpu::TextureDescriptor {
            label: None,
            size: wgpu::Extent3d {
                width: w,
                height: h,
                depth_or_array_layers: 1,
            },
            mip_level_count: 1,
            sample_count: 1,
            dimension: wgpu::TextureDimension::D2,
            format: wgpu::TextureFormat::Rgba8Unorm,
            usage: wgpu::TextureUsages::COPY_DST | wgpu::TextureUsages::COPY_SRC,
            view_formats: &[],
        });
        let mut live = Live::new(scene.clone(), w, h);
        let want = |s: &Scene| -> Vec<u32> {
            let (buf, spec) = buffers(s, w, h, s.triangle);
            glint::cpu::render_f32(&buf, spec)
                .pixels
                .iter()
                .map(|p| glint::shared::real::pack_rgba8(*p))
                .collect()
        };
        assert!(live.step_to_texture(&renderer, &texture).unwrap());
        let first = read_texture(gpu, &texture);
        let lavapipe = common::bit_exact_expected(g);
        let same = |a: &[u32], b: &[u32]| {
            let off = a.iter().zip(b).filter(|(x, y)| x != y).count();
            if lavapipe {
                off == 0
            } else {
                off * 1000 <= a.len()
            }
        };
        assert!(same(&first, &want(&scene)), "{name}: first frame");
        assert!(live.orbit(20.0, 5.0));
        assert!(live.step_to_texture(&renderer, &texture).unwrap());
        let moved = read_texture(gpu, &texture);
        let mut s = scene.clone();
        s.camera = live.camera().clone();
        assert!(same(&moved, &want(&s)), "{name}: moved camera");
        assert!(!same(&moved, &first), "{name}: the twin");
    }
}
