//! One scene rendered again and again by a kept `Renderer`, each render's wall time printed
//! in milliseconds: the Rust side of `benches/python_overhead.py`.
//!
//! `cargo run --release --example render_loop -- scenes/bb8.toml cpu 30 [WxH]`

use std::time::Instant;

use glint::{Backend, RenderOptions, Renderer, scene::Scene};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let scene = Scene::load(args.first().map_or("scenes/bb8.toml", String::as_str))?;
    let backend: Backend = args.get(1).map_or("cpu", String::as_str).parse()?;
    let reps: usize = args.get(2).map_or(Ok(30), |s| s.parse())?;
    let size = match args.get(3) {
        Some(s) => {
            let (w, h) = s.split_once('x').ok_or("size: WIDTHxHEIGHT")?;
            Some((w.parse()?, h.parse()?))
        }
        None => None,
    };
    let renderer = Renderer::new(backend)?;
    let options = RenderOptions {
        size,
        ..RenderOptions::default()
    };
    for _ in 0..reps {
        let t = Instant::now();
        let image = renderer.render(&scene, &options)?;
        let ms = t.elapsed().as_secs_f64() * 1e3;
        std::hint::black_box(image);
        println!("{ms:.4}");
    }
    Ok(())
}
