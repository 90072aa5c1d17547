//! The README's seed-scene images are what the code renders now: each PNG in `docs/images/`
//! equals, byte for byte after decoding, the CPU tracer's image of its scene (the GPU's on
//! lavapipe, which `tests/gpu_vs_cpu.rs` proves equal). Regenerate them with
//! `cargo run --release -- render scenes/NAME.toml -o docs/images/NAME.png --backend cpu`
//! (each in its scene's `[output] encoding`: the textured scene's is sRGB).

mod common;

use glint::buffers::{SceneBuffers, Specialisation};

fn rendered(name: &str) -> (u32, u32, Vec<u8>) {
    let scene = common::seed_scene(name);
    let (w, h) = scene.size();
    let buf = SceneBuffers::new(&scene, w, h, scene.triangle);
    let img = glint::cpu::render_f32(&buf, Specialisation::for_scene(&buf));
    (w, h, img.to_rgb8_encoded(scene.encoding))
}

fn committed(name: &str) -> (u32, u32, Vec<u8>) {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("docs/images")
        .join(format!("{name}.png"));
    let png = image::open(&path)
        .unwrap_or_else(|e| panic!("{}: {e}", path.display()))
        .to_rgb8();
    (png.width(), png.height(), png.into_raw())
}

fn differing(a: &(u32, u32, Vec<u8>), b: &(u32, u32, Vec<u8>)) -> usize {
    assert_eq!((a.0, a.1), (b.0, b.1), "image sizes differ");
    a.2.chunks(3)
        .zip(b.2.chunks(3))
        .filter(|(x, y)| x != y)
        .count()
}

#[test]
fn readme_images_are_what_the_code_renders() {
    for name in common::SHIPPED_SCENES {
        let n = differing(&rendered(name), &committed(name));
        assert_eq!(
            n, 0,
            "docs/images/{name}.png: {n} pixels differ from a render now"
        );
    }
}

/// The twin: one pixel changed by one step in one channel is seen.
#[test]
fn a_changed_pixel_is_seen() {
    let a = rendered("sphere");
    let mut b = a.clone();
    b.2[3 * 1000] ^= 1;
    assert_eq!(differing(&a, &b), 1);
}
