//! Scene text (any bytes) through the parser and validator: an error or a scene, never a
//! panic; a scene that validates also flattens into buffers and builds its BVH.
#![no_main]

use std::path::Path;

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let Ok(src) = std::str::from_utf8(data) else {
        return;
    };
    // Mesh files named by the input are served empty from memory, never read from disk.
    let no_files = |_: &Path| -> Result<Vec<u8>, String> { Err("no files while fuzzing".into()) };
    if let Ok(scene) = glint::scene::Scene::parse_with(src, Path::new("fuzz.toml"), &no_files) {
        let (w, h) = scene.size();
        let buf = glint::buffers::SceneBuffers::new(&scene, w.min(4), h.min(4), scene.triangle);
        let _ = glint::cpu::render_f32(&buf, glint::buffers::Specialisation::for_scene(&buf));
    }
});
