//! Render a scene from Rust: `cargo run --release --example render -- scenes/bb8.toml bb8.png`.

use glint::{Backend, RenderOptions, Renderer, scene::Scene};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let mut args = std::env::args().skip(1);
    let scene_path = args.next().unwrap_or_else(|| "scenes/bb8.toml".into());
    let out = args.next().unwrap_or_else(|| "out.png".into());
    let scene = Scene::load(&scene_path)?;
    let renderer = Renderer::new(Backend::Auto)?;
    let image = renderer.render(&scene, &RenderOptions::default())?;
    image.save(out.as_ref())?;
    println!(
        "{out}: {}x{} on {}",
        image.width,
        image.height,
        renderer.describe()
    );
    Ok(())
}
