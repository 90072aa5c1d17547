//! Every input the fuzzers (`fuzz/`, cargo-fuzz) found, kept as a regression test: each
//! must give a clear error or a scene, never a panic. Files: `tests/data/fuzz/TARGET-*.bin`.

use std::path::Path;

use glint::scene::Scene;

/// The fuzz targets' own harnesses, without libFuzzer.
fn scene_parse(data: &[u8]) -> Result<(), String> {
    let src = std::str::from_utf8(data).map_err(|e| e.to_string())?;
    let no_files = |_: &Path| -> Result<Vec<u8>, String> { Err("no files".into()) };
    Scene::parse_with(src, Path::new("fuzz.toml"), &no_files)
        .map(|_| ())
        .map_err(|e| e.to_string())
}

fn obj_load(data: &[u8]) -> Result<(), String> {
    const SCENE: &str = "[camera]\neye = [0.0, 0.0, 5.0]\nlook_at = [0.0, 0.0, 0.0]\n\
        up = [0.0, 1.0, 0.0]\nfov = 45.0\nwidth = 4\nheight = 4\n\
        [[meshes]]\nfile = \"fuzz.obj\"\n";
    let (obj, mtl) = match data.iter().position(|&b| b == 0xff) {
        Some(k) => (&data[..k], &data[k + 1..]),
        None => (data, &[][..]),
    };
    let files = |p: &Path| -> Result<Vec<u8>, String> {
        Ok(if p.extension().is_some_and(|e| e == "obj") {
            obj.to_vec()
        } else {
            mtl.to_vec()
        })
    };
    Scene::parse_with(SCENE, Path::new("fuzz.toml"), &files)
        .map(|_| ())
        .map_err(|e| e.to_string())
}

#[test]
fn every_fuzz_finding_is_an_error_not_a_panic() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/fuzz");
    let mut n = 0;
    for entry in std::fs::read_dir(&dir).unwrap() {
        let path = entry.unwrap().path();
        let name = path.file_name().unwrap().to_string_lossy().into_owned();
        if !name.ends_with(".bin") {
            continue;
        }
        let data = std::fs::read(&path).unwrap();
        let r = if name.starts_with("obj_load") {
            obj_load(&data)
        } else {
            scene_parse(&data)
        };
        eprintln!("{name}: {r:?}");
        n += 1;
    }
    assert!(n >= 1, "no regression inputs found in {}", dir.display());
}

/// The first finding, spelled out: an MTL colour with two numbers made tobj 4 panic
/// (`parse_float3` unwraps); glint refuses it with the MTL line.
#[test]
fn short_mtl_colour_is_an_error_naming_the_line() {
    let e = obj_load(b"mtllib a.mtl\nusemtl red\nv 0 0 0\n\xffnewmtl red\nKa 1 0\n").unwrap_err();
    assert!(
        e.contains("a.mtl: line 2") && e.contains("three numbers"),
        "{e}"
    );
}
