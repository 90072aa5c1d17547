//! Interactive frame times of the library's live view (`glint::render::Live`, what
//! `glint view` draws with): for each scene, the first frame, then frames with the camera
//! orbiting 2° a frame (each a whole new picture, the BVH reused), median and spread.
//! `--to-texture` (GPU backends): frames traced straight into a texture with the scene kept
//! on the device (`Live::step_to_texture`, what `glint view` does on a GPU) instead of
//! uploaded and read back each frame (`Live::step`).
//!
//! ```text
//! cargo run --release --example live_frames -- [--backend cpu|gpu|auto] [--frames N] [--to-texture] SCENE...
//! ```

use std::time::Instant;

use glint::render::Live;
use glint::scene::Scene;
use glint::{Backend, Renderer};

fn main() -> anyhow::Result<()> {
    let mut args = std::env::args().skip(1);
    let (mut backend, mut frames, mut scenes) = (Backend::Cpu, 30usize, Vec::new());
    let mut to_texture = false;
    while let Some(a) = args.next() {
        match a.as_str() {
            "--to-texture" => to_texture = true,
            "--backend" => backend = args.next().unwrap_or_default().parse()?,
            "--frames" => frames = args.next().unwrap_or_default().parse()?,
            _ => scenes.push(a),
        }
    }
    let renderer = Renderer::new(backend)?;
    println!("tracer: {}", renderer.describe());
    println!("| scene | size | samples | first frame ms | orbit frame ms (median) | min | max |");
    println!("|---|---|---|---|---|---|---|");
    for path in scenes {
        let scene = Scene::load(&path)?;
        let (w, h) = scene.size();
        let mut live = Live::new(scene, w, h);
        let texture = match (to_texture, renderer.tracer()) {
            (true, glint::Tracer::Gpu(g) | glint::Tracer::GpuRq(g)) => {
                Some(g.device.create_texture(&wgpu::TextureDescriptor {
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
                    usage: wgpu::TextureUsages::COPY_DST,
                    view_formats: &[],
                }))
            }
            (true, _) => anyhow::bail!("--to-texture needs a GPU backend"),
            _ => None,
        };
        let step = |live: &mut Live| -> anyhow::Result<()> {
            match &texture {
                Some(t) => live.step_to_texture(&renderer, t).map(|_| ())?,
                None => live.step(&renderer)?,
            }
            Ok(())
        };
        let t0 = Instant::now();
        while !live.converged() {
            step(&mut live)?;
        }
        let first = t0.elapsed().as_secs_f64() * 1e3;
        let mut times = Vec::new();
        for _ in 0..frames {
            live.orbit(2.0, 0.0);
            let t = Instant::now();
            step(&mut live)?;
            times.push(t.elapsed().as_secs_f64() * 1e3);
        }
        times.sort_by(f64::total_cmp);
        println!(
            "| {path} | {w}x{h} | {} | {first:.1} | {:.1} | {:.1} | {:.1} |",
            live.samples().1,
            times[times.len() / 2],
            times[0],
            times[times.len() - 1]
        );
    }
    Ok(())
}
