//! Every input the fuzzers (`fuzz/`, cargo-fuzz) found, kept as a regression test: each
//! must give a clear error or a scene, never a panic. Files: `tests/data/fuzz/TARGET-*.bin`.

use std::path::Path;

use glint::fuzzing::{dict_load, gltf_load, obj_load, ply_load, scene_parse, texture_load};

/// A fuzz target's harness.
type Harness = fn(&[u8]) -> Result<(), String>;

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
        let harness: Harness = match name.split('-').next().unwrap_or_default() {
            "obj_load" => obj_load,
            "ply_load" => ply_load,
            "gltf_load" => gltf_load,
            "texture_load" => texture_load,
            "dict_load" => dict_load,
            _ => scene_parse,
        };
        let r = harness(&data);
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

/// A glTF primitive whose POSITION names an accessor the file lacks made the `gltf` crate's
/// validation index past its list (gltf-json 1.4.1; the fuzzer's finding is in
/// tests/data/fuzz/); glint refuses it naming the mesh, the primitive and the accessor.
/// The twin: the seed it was made from, with its accessors, loads.
#[test]
fn a_position_accessor_past_the_list_is_an_error_naming_it() {
    let seed = std::fs::read(
        Path::new(env!("CARGO_MANIFEST_DIR")).join("fuzz/seeds/gltf_load/triangle-data-uri"),
    )
    .unwrap();
    let text = String::from_utf8(seed.clone()).expect("the seed is text");
    assert!(text.contains("\"accessors\":"));
    let without = text.replace("\"accessors\":", "\"unknown\":");
    let e = gltf_load(without.as_bytes()).unwrap_err();
    assert!(
        e.contains("glTF mesh 0 primitive 0") && e.contains("POSITION: accessor 0 is missing"),
        "{e}"
    );
    gltf_load(&seed).expect("the twin: the seed loads");
}

/// A glTF primitive whose indices are signed shorts (the fuzzer's finding, in
/// tests/data/fuzz/) reached the `gltf` crate's unreachable code (gltf 1.4.1); glint
/// refuses it naming the primitive and the accessor. The twin: the same file with unsigned
/// shorts is not refused for its indices' type.
#[test]
fn signed_indices_are_an_error_naming_the_accessor() {
    let data = std::fs::read(
        Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/fuzz/gltf_load-signed-indices.bin"),
    )
    .unwrap();
    let e = gltf_load(&data).unwrap_err();
    assert!(
        e.contains("glTF mesh 0 primitive 0")
            && e.contains("indices: accessor 1 is not a Scalar of"),
        "{e}"
    );
    let (from, to) = (b"\"componentType\": 5122", b"\"componentType\": 5123");
    let at = data.windows(from.len()).position(|w| w == from).unwrap();
    let mut unsigned = data.clone();
    unsigned[at..at + to.len()].copy_from_slice(to);
    if let Err(e) = gltf_load(&unsigned) {
        assert!(!e.contains("indices: accessor"), "the twin: {e}");
    }
}

/// The mesh and texture harnesses on their seed corpora (`fuzz/seeds/TARGET/`, made from
/// small valid files): each seed is accepted (and checked: finite vertices, indices in
/// range), and every cut of it (its first k bytes, k over a spread of lengths) is accepted
/// or refused naming the scene file and a line, never a panic. The harnesses check those
/// invariants themselves and panic where one fails.
#[test]
fn the_mesh_and_texture_harnesses_take_their_seeds_and_every_cut_of_them() {
    let targets: [(&str, Harness); 3] = [
        ("ply_load", ply_load),
        ("gltf_load", gltf_load),
        ("texture_load", texture_load),
    ];
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("fuzz/seeds");
    for (target, harness) in targets {
        let mut seeds = 0;
        for entry in std::fs::read_dir(root.join(target)).unwrap() {
            let path = entry.unwrap().path();
            let data = std::fs::read(&path).unwrap();
            harness(&data).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
            let mut refused = 0;
            for k in (0..data.len()).step_by((data.len() / 97).max(1)) {
                refused += harness(&data[..k]).is_err() as usize;
            }
            assert!(refused > 0, "{}: no cut was refused", path.display());
            seeds += 1;
        }
        assert!(seeds >= 1, "{target}: no seeds");
    }
}

/// The twin of the harnesses' own checks: a refusal that names no line is caught.
#[test]
#[should_panic(expected = "names no line")]
fn a_refusal_without_a_line_is_a_finding() {
    glint::fuzzing::check_refused("fuzz.toml: meshes[0].file: bad");
}

/// `scene_parse`, then `dict_load`, on the same bytes.
fn scene_and_dict(data: &[u8]) -> Result<(), String> {
    let _ = scene_parse(data);
    dict_load(data)
}

/// The shipped scenes and OBJ/MTL pairs seed `scene_parse` and `obj_load` (`cargo fuzz run
/// scene_parse corpus/scene_parse ../scenes`): each scene that names no file is accepted and
/// the others refused at the key that names one (the harness reads no file), each OBJ with its
/// MTL after a 0xFF byte is accepted (refused at its texture where the MTL names one: the
/// harness has no image to give), and every cut of them is taken without a panic. Each
/// scene and cut also goes through `dict_load`: as a dict's table it gets the file's
/// verdict and picture. The
/// twin: a cut that ends inside a table's header is refused.
#[test]
fn the_shipped_scenes_seed_scene_parse_and_obj_load() {
    let scenes = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes");
    let (mut tomls, mut objs) = (0, 0);
    let mut paths: Vec<_> = std::fs::read_dir(&scenes)
        .unwrap()
        .map(|e| e.unwrap().path())
        .collect();
    paths.sort();
    for path in paths {
        let ext = path
            .extension()
            .and_then(|e| e.to_str())
            .unwrap_or_default();
        let (harness, data): (Harness, Vec<u8>) = match ext {
            "toml" => {
                let data = std::fs::read(&path).unwrap();
                let text = String::from_utf8_lossy(&data);
                let names_a_file = text.contains("file = ") || text.contains("map_");
                match scene_parse(&data) {
                    Ok(()) => assert!(!names_a_file, "{}", path.display()),
                    Err(e) => assert!(
                        names_a_file && e.starts_with("fuzz.toml:") && e.contains("no files"),
                        "{}: {e}",
                        path.display()
                    ),
                }
                // The same scene as a dict's table: the same verdict and picture.
                assert_eq!(
                    dict_load(&data).is_ok(),
                    !names_a_file,
                    "{}",
                    path.display()
                );
                tomls += 1;
                (scene_and_dict, data)
            }
            "obj" => {
                let mut data = std::fs::read(&path).unwrap();
                data.push(0xFF);
                let mtl = std::fs::read(path.with_extension("mtl")).unwrap_or_default();
                data.extend(&mtl);
                // The harness hands the MTL's bytes for every other file, a texture too.
                match obj_load(&data) {
                    Ok(()) => {}
                    Err(e) if String::from_utf8_lossy(&mtl).contains("map_") => {
                        assert!(e.contains("texture"), "{}: {e}", path.display())
                    }
                    Err(e) => panic!("{}: {e}", path.display()),
                }
                objs += 1;
                (obj_load, data)
            }
            _ => continue,
        };
        for k in (0..data.len()).step_by((data.len() / 61).max(1)) {
            let _ = harness(&data[..k]);
        }
    }
    assert!(tomls >= 5 && objs >= 1, "{tomls} scenes, {objs} OBJs");
    let bb8 = std::fs::read_to_string(scenes.join("bb8.toml")).unwrap();
    let cut = bb8.find("[camera]").unwrap() + 4;
    assert!(scene_parse(&bb8.as_bytes()[..cut]).is_err(), "the twin");
}

/// The twin of `dict_load`'s check: a table that is not the file's (bb8 with its light's
/// red changed) is seen, and panics as a finding would.
#[test]
#[should_panic(expected = "render differently")]
fn a_table_that_is_not_the_files_is_a_finding() {
    let scenes = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes");
    let bb8 = std::fs::read_to_string(scenes.join("bb8.toml")).unwrap();
    let at = bb8.find("color = [").expect("bb8 has a coloured light") + "color = [".len();
    let end = at + bb8[at..].find(',').unwrap();
    let moved = format!("{}0.123{}", &bb8[..at], &bb8[end..]);
    glint::fuzzing::file_and_dict_agree(&bb8, &bb8).expect("the file agrees with itself");
    let _ = glint::fuzzing::file_and_dict_agree(&bb8, &moved);
}

/// The fuzz smoke's finding (tests/fuzz_smoke.rs, in tests/data/fuzz/): a face's texture
/// index of -2147483649 in an OBJ that tobj reads made tobj 4 multiply an index near 2^64
/// (a panic where overflow is checked, a wrong texture coordinate where not); a normal
/// index of a flat mesh the same. glint checks both against what was defined before the
/// face and names the line. The twin: the same files with indices in range load.
#[test]
fn texture_and_normal_indices_out_of_range_are_errors_naming_the_line() {
    let obj = |corner: &str| {
        let mut d = format!(
            "mtllib a.mtl\nusemtl red\nv 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nvn 0 0 1\nf 1/1/1 2/1/1 3/{corner}\n"
        )
        .into_bytes();
        d.push(0xFF);
        d.extend(b"newmtl red\nKd 1 0 0\n");
        d
    };
    let e = obj_load(&obj("-2147483649/1")).unwrap_err();
    assert!(
        e.contains("line 8") && e.contains("face texture index -2147483649 is out of range"),
        "{e}"
    );
    let e = obj_load(&obj("1/-9223372036854775807")).unwrap_err();
    assert!(
        e.contains("line 8") && e.contains("face normal index -9223372036854775807"),
        "{e}"
    );
    let e = obj_load(&obj("0/1")).unwrap_err();
    assert!(e.contains("face texture index 0 is out of range"), "{e}");
    let e = obj_load(&obj("x/1")).unwrap_err();
    assert!(e.contains("face texture index in \"3/x/1\""), "{e}");
    obj_load(&obj("-1/-1")).expect("the twin: indices from the end, in range");
    obj_load(&obj("1/1")).expect("the twin: indices in range");
}
