//! Interactive frame times of the library's live view (`glint::render::Live`, what
//! `glint view` draws with): for each scene, the first frame, then frames with the camera
//! orbiting 2° a frame (each a whole new picture, the BVH reused), median and spread.
//!
//! ```text
//! cargo run --release --example live_frames -- [--backend cpu|gpu|auto] [--frames N] SCENE...
//! ```

use std::time::Instant;

use glint::render::Live;
use glint::scene::Scene;
use glint::{Backend, Renderer};

fn main() -> anyhow::Result<()> {
    let mut args = std::env::args().skip(1);
    let (mut backend, mut frames, mut scenes) = (Backend::Cpu, 30usize, Vec::new());
    while let Some(a) = args.next() {
        match a.as_str() {
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
        let t0 = Instant::now();
        while !live.converged() {
            live.step(&renderer)?;
        }
        let first = t0.elapsed().as_secs_f64() * 1e3;
        let mut times = Vec::new();
        for _ in 0..frames {
            live.orbit(2.0, 0.0);
            let t = Instant::now();
            live.step(&renderer)?;
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
