//! Every input the fuzzers (`fuzz/`, cargo-fuzz) found, kept as a regression test: each
//! must give a clear error or a scene, never a panic. Files: `tests/data/fuzz/TARGET-*.bin`.

use std::path::Path;

use glint::fuzzing::{obj_load, scene_parse};

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
