//! The fuzz targets' harnesses (`fuzz/fuzz_targets/`), here so that the regression tests
//! (`tests/fuzz_regressions.rs`) run exactly what the fuzzers ran. Each takes any bytes and
//! returns the scene error as text, or `Ok` once a valid scene has also been flattened,
//! had its BVH built and been rendered at 4×4 at most; it must never panic. The mesh and
//! texture harnesses (`ply_load`, `gltf_load`, `texture_load`) also check what they got:
//! an accepted scene has finite vertices and indices in range, a refusal names the scene
//! file and a line.

use std::path::Path;

use crate::buffers::{SceneBuffers, Specialisation};
use crate::scene::{ReadError, ReadFile, Scene};

/// A valid scene is flattened, its BVH built, and rendered small on the CPU mirror.
fn render_small(scene: &Scene) -> crate::image::Image {
    let (w, h) = scene.size();
    let buf = SceneBuffers::new(scene, w.min(4), h.min(4), scene.triangle);
    crate::cpu::render_f32(&buf, Specialisation::for_scene(&buf))
}

/// The one mesh the scene harnesses can read, [`FUZZ_MESH`]: a tetrahedron and a quad, so
/// that mutated scenes reach meshes, named meshes and instances.
pub const FUZZ_MESH_OBJ: &str = "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nv 2 2 0\nv 3 2 0\nv 3 3 0\nv 2 3 0\n\
f 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\nf 5 6 7 8\n";

/// The file name [`FUZZ_MESH_OBJ`] is served under, in any folder.
pub const FUZZ_MESH: &str = "fuzz-mesh.obj";

/// A reader that touches no disk: [`FUZZ_MESH`] is served from memory, every other file is
/// refused.
fn no_files(path: &Path) -> Result<Vec<u8>, ReadError> {
    if path.file_name().is_some_and(|n| n == FUZZ_MESH) {
        return Ok(FUZZ_MESH_OBJ.as_bytes().to_vec());
    }
    Err(ReadError::Other("no files while fuzzing".into()))
}

/// Target `scene_parse`: the bytes as a scene file. Mesh files it names are refused
/// without touching the disk, but for [`FUZZ_MESH`].
pub fn scene_parse(data: &[u8]) -> Result<(), String> {
    let src = std::str::from_utf8(data).map_err(|e| e.to_string())?;
    let scene =
        Scene::parse_with(src, Path::new("fuzz.toml"), &no_files).map_err(|e| e.to_string())?;
    render_small(&scene);
    Ok(())
}

/// Target `dict_load`: the bytes as a scene file, and the same scene as `Scene.from_dict`
/// reads it: the file's table written out by `toml` (what the Python package does with
/// the table a dict becomes) and read back as `<dict>`. The file and its table must agree:
/// both refused, or both valid with the same 4×4 picture in every bit; the harness panics
/// (a finding) where they do not. Returns the file's own verdict.
pub fn dict_load(data: &[u8]) -> Result<(), String> {
    let src = std::str::from_utf8(data).map_err(|e| e.to_string())?;
    let table: toml::Table = toml::from_str(src).map_err(|e| e.to_string())?;
    let text = toml::to_string(&table).map_err(|e| e.to_string())?;
    file_and_dict_agree(src, &text)
}

/// `dict_load`'s check: the scene file `src` and the text `dict` (its table as the Python
/// package writes it) give the same verdict and, where valid, the same 4×4 picture in
/// every bit; a panic where they do not. Returns the file's own verdict.
pub fn file_and_dict_agree(src: &str, dict: &str) -> Result<(), String> {
    let file = Scene::parse_with(src, Path::new("fuzz.toml"), &no_files);
    let from_dict = Scene::parse_with(dict, Path::new("<dict>"), &no_files);
    match (&file, &from_dict) {
        (Ok(a), Ok(b)) => {
            let (a, b) = (render_small(a), render_small(b));
            let bits = |i: &crate::image::Image| -> Vec<u32> {
                i.pixels.iter().flatten().map(|x| x.to_bits()).collect()
            };
            assert!(
                bits(&a) == bits(&b),
                "the file and its table render differently:\n{src}\n---\n{dict}"
            );
        }
        (Err(_), Err(_)) => {}
        (a, b) => panic!(
            "the file and its table disagree: {:?} against {:?}\n{src}\n---\n{dict}",
            a.as_ref().err().map(|e| e.to_string()),
            b.as_ref().err().map(|e| e.to_string())
        ),
    }
    file.map(|_| ()).map_err(|e| e.to_string())
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
    let (obj, mtl) = split_ff(data);
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

/// What every accepted scene must hold, whatever its input: finite vertices, material
/// indices in range, normals and texture coordinates for triangles that exist. Panics (a
/// fuzzer's finding) where it does not.
fn check_accepted(scene: &Scene) {
    let materials = scene.materials.len() as u32;
    for (i, t) in scene.triangles.iter().enumerate() {
        assert!(
            t.vertices.iter().flatten().all(|x| x.is_finite()),
            "triangle {i}: a vertex is not finite: {:?}",
            t.vertices
        );
        assert!(
            t.material < materials,
            "triangle {i}: material {}",
            t.material
        );
    }
    for s in &scene.smooth {
        assert!(
            s.first + s.normals.len() <= scene.triangles.len(),
            "smooth normals"
        );
        assert!(s.normals.iter().flatten().flatten().all(|x| x.is_finite()));
    }
    for u in &scene.uvs {
        assert!(u.first <= scene.triangles.len(), "texture coordinates");
    }
}

/// What every refusal must hold: it names the scene file and a line (`fuzz.toml:N:`), and
/// the mesh, texture or key at fault after it. Panics where it does not (public for the
/// test that proves it can fail).
pub fn check_refused(message: &str) {
    let rest = message
        .strip_prefix("fuzz.toml:")
        .unwrap_or_else(|| panic!("a refusal that does not name the scene file: {message:?}"));
    let line: String = rest.chars().take_while(char::is_ascii_digit).collect();
    assert!(
        !line.is_empty() && rest[line.len()..].starts_with(": "),
        "a refusal that names no line: {message:?}"
    );
}

/// Reads `scene` with every other file served from `files`, then checks the outcome both
/// ways and renders an accepted scene small.
fn load_checked(scene: &str, files: &ReadFile<'_>) -> Result<(), String> {
    match Scene::parse_with(scene, Path::new("fuzz.toml"), files) {
        Ok(s) => {
            check_accepted(&s);
            render_small(&s);
            Ok(())
        }
        Err(e) => {
            let message = e.to_string();
            check_refused(&message);
            Err(message)
        }
    }
}

/// The camera of the mesh and texture harnesses' scenes: 4×4 pixels looking down −z.
const SMALL_CAMERA: &str = "[camera]\neye = [0.0, 0.0, 5.0]\nlook_at = [0.0, 0.0, 0.0]\n\
    fov = 45.0\nwidth = 4\nheight = 4\n";

/// The bytes up to the first 0xFF, and those after it (empty without one).
fn split_ff(data: &[u8]) -> (&[u8], &[u8]) {
    match data.iter().position(|&b| b == 0xff) {
        Some(k) => (&data[..k], &data[k + 1..]),
        None => (data, &[]),
    }
}

/// Target `ply_load`: the bytes after the first as a PLY mesh (ASCII or binary, as its
/// header says), gzipped (`fuzz.ply.gz`) when the first byte is odd, smooth when its
/// second bit is set, read as a scene's `[[meshes]]` entry reads it.
pub fn ply_load(data: &[u8]) -> Result<(), String> {
    let Some((&mode, body)) = data.split_first() else {
        return Err("empty".into());
    };
    let name = if mode & 1 == 1 {
        "fuzz.ply.gz"
    } else {
        "fuzz.ply"
    };
    let scene = format!(
        "{SMALL_CAMERA}[materials.m]\nmodel = \"diffuse\"\nka = [0.1, 0.1, 0.1]\n\
         kd = [0.8, 0.8, 0.8]\n[[lights]]\nposition = [1.0, 1.0, 5.0]\ncolor = [1.0, 1.0, 1.0]\n\
         [[meshes]]\nfile = \"{name}\"\nmaterial = \"m\"\nsmooth = {}\nrotate = [10.0, 20.0, 30.0]\n",
        mode & 2 == 2
    );
    let body = body.to_vec();
    load_checked(&scene, &move |_: &Path| Ok(body.clone()))
}

/// Target `gltf_load`: a glTF (`.gltf` when the first byte is even, `.glb` when odd) of
/// the bytes after it up to the first 0xFF, and the bytes after that as every other file
/// it names (an external buffer, an image), read as a `[[meshes]]` entry without a
/// material (the file's own).
pub fn gltf_load(data: &[u8]) -> Result<(), String> {
    let Some((&mode, rest)) = data.split_first() else {
        return Err("empty".into());
    };
    let name = if mode & 1 == 1 {
        "fuzz.glb"
    } else {
        "fuzz.gltf"
    };
    let (main, other) = split_ff(rest);
    let scene = format!(
        "{SMALL_CAMERA}[[lights]]\nposition = [1.0, 1.0, 5.0]\ncolor = [1.0, 1.0, 1.0]\n\
         [[meshes]]\nfile = \"{name}\"\nsmooth = {}\n",
        mode & 2 == 2
    );
    let (main, other) = (main.to_vec(), other.to_vec());
    let name = name.to_owned();
    load_checked(&scene, &move |p: &Path| {
        Ok(if p.file_name().is_some_and(|f| f == name.as_str()) {
            main.clone()
        } else {
            other.clone()
        })
    })
}

/// Target `texture_load`: the bytes after the first as a material's `map_kd` (named
/// `.png` when the first byte is even, `.jpg` when odd) on a triangle with texture
/// coordinates, decoded through glint's loader and its limits.
pub fn texture_load(data: &[u8]) -> Result<(), String> {
    let Some((&mode, body)) = data.split_first() else {
        return Err("empty".into());
    };
    let name = if mode & 1 == 1 {
        "fuzz.jpg"
    } else {
        "fuzz.png"
    };
    let scene = format!(
        "{SMALL_CAMERA}[materials.t]\nmodel = \"ambient\"\nka = [1.0, 1.0, 1.0]\n\
         map_kd = \"{name}\"\n[[triangles]]\n\
         vertices = [[-1.0, -1.0, 0.0], [1.0, -1.0, 0.0], [0.0, 1.0, 0.0]]\n\
         material = \"t\"\nuvs = [[0.0, 0.0], [1.0, 0.0], [0.5, 1.0]]\n"
    );
    let body = body.to_vec();
    load_checked(&scene, &move |_: &Path| Ok(body.clone()))
}
