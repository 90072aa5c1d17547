//! OBJ bytes (and an MTL, the input's second half) through the mesh loader, as a scene's
//! `[[meshes]]` entry reads them: an error or triangles, never a panic.
#![no_main]

use std::path::Path;

use libfuzzer_sys::fuzz_target;

const SCENE: &str = r#"
[camera]
eye = [0.0, 0.0, 5.0]
look_at = [0.0, 0.0, 0.0]
up = [0.0, 1.0, 0.0]
fov = 45.0
width = 4
height = 4
[[meshes]]
file = "fuzz.obj"
scale = [2.0, 2.0, 2.0]
rotate = [10.0, 20.0, 30.0]
"#;

fuzz_target!(|data: &[u8]| {
    // Split at the first 0xFF byte: before it the OBJ, after it any MTL it names.
    let (obj, mtl) = match data.iter().position(|&b| b == 0xff) {
        Some(k) => (&data[..k], &data[k + 1..]),
        None => (data, &[][..]),
    };
    let files = |p: &Path| -> Result<Vec<u8>, String> {
        if p.extension().is_some_and(|e| e == "obj") {
            Ok(obj.to_vec())
        } else {
            Ok(mtl.to_vec())
        }
    };
    if let Ok(scene) = glint::scene::Scene::parse_with(SCENE, Path::new("fuzz.toml"), &files) {
        let buf = glint::buffers::SceneBuffers::new(&scene, 4, 4, scene.triangle);
        let _ = glint::cpu::render_f32(&buf, glint::buffers::Specialisation::for_scene(&buf));
    }
});
