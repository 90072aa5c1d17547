//! The fuzz targets' harnesses (`fuzz/fuzz_targets/`), here so that the regression tests
//! (`tests/fuzz_regressions.rs`) run exactly what the fuzzers ran. Each takes any bytes and
//! returns the scene error as text, or `Ok` once a valid scene has also been flattened,
//! had its BVH built and been rendered at 4×4 at most; it must never panic.

use std::path::Path;

use crate::buffers::{SceneBuffers, Specialisation};
use crate::scene::{ReadError, Scene};

/// A valid scene is flattened, its BVH built, and rendered small on the CPU mirror.
fn render_small(scene: &Scene) {
    let (w, h) = scene.size();
    let buf = SceneBuffers::new(scene, w.min(4), h.min(4), scene.triangle);
    let _ = crate::cpu::render_f32(&buf, Specialisation::for_scene(&buf));
}

/// Target `scene_parse`: the bytes as a scene file. Mesh files it names are refused
/// without touching the disk.
pub fn scene_parse(data: &[u8]) -> Result<(), String> {
    let src = std::str::from_utf8(data).map_err(|e| e.to_string())?;
    let no_files = |_: &Path| -> Result<Vec<u8>, ReadError> {
        Err(ReadError::Other("no files while fuzzing".into()))
    };
    let scene =
        Scene::parse_with(src, Path::new("fuzz.toml"), &no_files).map_err(|e| e.to_string())?;
    render_small(&scene);
    Ok(())
}

/// The scene that target `obj_load` reads its mesh through (with scale and rotate).
const OBJ_SCENE: &str = r#"
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

/// Target `obj_load`: the bytes up to the first 0xFF as an OBJ, the rest as any MTL it
/// names, read as a scene's `[[meshes]]` entry reads them.
pub fn obj_load(data: &[u8]) -> Result<(), String> {
    let (obj, mtl) = match data.iter().position(|&b| b == 0xff) {
        Some(k) => (&data[..k], &data[k + 1..]),
        None => (data, &[][..]),
    };
    let files = |p: &Path| -> Result<Vec<u8>, ReadError> {
        Ok(if p.extension().is_some_and(|e| e == "obj") {
            obj.to_vec()
        } else {
            mtl.to_vec()
        })
    };
    let scene =
        Scene::parse_with(OBJ_SCENE, Path::new("fuzz.toml"), &files).map_err(|e| e.to_string())?;
    render_small(&scene);
    Ok(())
}
