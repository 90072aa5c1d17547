//! Hostile files in the newer formats: a PLY whose header claims 2^40 vertices, a glTF
//! whose `data:` buffer claims 2 GiB, GLBs whose chunk lengths lie, PNG and JPEG textures claiming 65535×65535 pixels,
//! and a texture reached through a symbolic link out of the scene's folder under
//! `--confine`. Each is refused quickly, with an error naming the file and the place, by a
//! `glint check` whose address space is capped at 1 GiB: a reader that believed the claim
//! and reserved the memory would die instead of answering.

mod common;

use std::path::Path;
use std::time::{Duration, Instant};

const HEAD: &str = "ambient = [0.1, 0.1, 0.1]\n[camera]\neye = [0.0, 0.0, 5.0]\n\
                    look_at = [0.0, 0.0, 0.0]\nfov = 40.0\nwidth = 8\nheight = 6\n\
                    [[lights]]\nposition = [0.0, 0.0, 5.0]\ncolor = [1.0, 1.0, 1.0]\n";

/// `glint check SCENE [extra]` with at most 1 GiB of address space: its exit status and text,
/// and the time it took.
fn check_capped(scene: &Path, extra: &[&str]) -> (Option<i32>, String, Duration) {
    let exe = env!("CARGO_BIN_EXE_glint");
    let mut c = std::process::Command::new("bash");
    c.arg("-c")
        .arg("ulimit -v 1048576 && exec \"$0\" check \"$1\" \"${@:2}\"")
        .arg(exe)
        .arg(scene)
        .args(extra);
    let t0 = Instant::now();
    let o = c.output().unwrap();
    let (code, text) = common::status_and_text(&o);
    (code, text, t0.elapsed())
}

fn refused(scene: &Path, extra: &[&str], wants: &[&str]) {
    let (code, text, took) = check_capped(scene, extra);
    assert_eq!(code, Some(1), "{}: {text}", scene.display());
    for w in wants {
        assert!(
            text.contains(w),
            "{}: wants {w:?} in {text}",
            scene.display()
        );
    }
    assert!(!text.contains("panicked"), "{text}");
    assert!(
        took < Duration::from_secs(10),
        "{}: {took:?}",
        scene.display()
    );
}

fn mesh_scene(d: &Path, name: &str, file: &str) -> std::path::PathBuf {
    let p = d.join(format!("{name}.toml"));
    let text = format!(
        "{HEAD}[materials.m]\nmodel = \"diffuse\"\nka = [0.1, 0.1, 0.1]\nkd = [0.8, 0.8, 0.8]\n\
         [[meshes]]\nfile = \"{file}\"\nmaterial = \"m\"\n"
    );
    std::fs::write(&p, text).unwrap();
    p
}

/// A PLY claiming 2^40 vertices (binary and ASCII) is refused at its element, in bounded
/// memory. The twin: the same file claiming its true count loads.
#[test]
fn a_ply_claiming_two_to_the_forty_vertices_is_refused() {
    let d = common::Scratch::new("hostile-ply");
    let body = |n: &str| {
        let mut b = format!(
            "ply\nformat binary_little_endian 1.0\nelement vertex {n}\nproperty float x\n\
             property float y\nproperty float z\nelement face 1\n\
             property list uchar int vertex_indices\nend_header\n"
        )
        .into_bytes();
        for v in [[0f32, 0., 0.], [1., 0., 0.], [0., 1., 0.]] {
            for x in v {
                b.extend_from_slice(&x.to_le_bytes());
            }
        }
        b.push(3);
        for i in [0i32, 1, 2] {
            b.extend_from_slice(&i.to_le_bytes());
        }
        b
    };
    std::fs::write(d.join("huge.ply"), body("1099511627776")).unwrap();
    refused(
        &mesh_scene(&d, "huge", "huge.ply"),
        &[],
        &["huge.ply", "PLY element vertex", "1099511627776"],
    );
    let ascii = "ply\nformat ascii 1.0\nelement vertex 1099511627776\nproperty float x\n\
                 property float y\nproperty float z\nelement face 0\n\
                 property list uchar int vertex_indices\nend_header\n0 0 0\n";
    std::fs::write(d.join("huge_ascii.ply"), ascii).unwrap();
    refused(
        &mesh_scene(&d, "huge_ascii", "huge_ascii.ply"),
        &[],
        &["huge_ascii.ply", "PLY element vertex"],
    );
    std::fs::write(d.join("true.ply"), body("3")).unwrap();
    let (code, text, _) = check_capped(&mesh_scene(&d, "true", "true.ply"), &[]);
    assert_eq!(code, Some(0), "{text}");
}

/// A glTF whose `data:` buffer claims 2 GiB (its byteLength) but holds 36 bytes is refused
/// naming the buffer; the twin with the true length loads.
#[test]
fn a_gltf_data_buffer_claiming_two_gib_is_refused() {
    use base64::Engine;
    let d = common::Scratch::new("hostile-gltf");
    let mut bin = Vec::new();
    for v in [[0f32, 0., 0.], [1., 0., 0.], [0., 1., 0.]] {
        for x in v {
            bin.extend_from_slice(&x.to_le_bytes());
        }
    }
    let uri = format!(
        "data:application/octet-stream;base64,{}",
        base64::engine::general_purpose::STANDARD.encode(&bin)
    );
    let doc = |len: u64| {
        format!(
            r#"{{"asset":{{"version":"2.0"}},"scene":0,"scenes":[{{"nodes":[0]}}],"nodes":[{{"mesh":0}}],
"meshes":[{{"primitives":[{{"attributes":{{"POSITION":0}}}}]}}],
"accessors":[{{"bufferView":0,"componentType":5126,"count":3,"type":"VEC3","min":[0,0,0],"max":[1,1,0]}}],
"bufferViews":[{{"buffer":0,"byteLength":36}}],
"buffers":[{{"byteLength":{len},"uri":"{uri}"}}]}}"#
        )
    };
    std::fs::write(d.join("huge.gltf"), doc(2 << 30)).unwrap();
    refused(
        &mesh_scene(&d, "huge", "huge.gltf"),
        &[],
        &["huge.gltf", "buffer"],
    );
    std::fs::write(d.join("true.gltf"), doc(36)).unwrap();
    let (code, text, _) = check_capped(&mesh_scene(&d, "true", "true.gltf"), &[]);
    assert_eq!(code, Some(0), "{text}");
}

/// A GLB (binary glTF) of one triangle, with the 4 bytes at each offset of `lies`
/// replaced by its value.
fn glb(lies: &[(usize, u32)]) -> Vec<u8> {
    let json = r#"{"asset":{"version":"2.0"},"scene":0,"scenes":[{"nodes":[0]}],"nodes":[{"mesh":0}],"meshes":[{"primitives":[{"attributes":{"POSITION":0}}]}],"accessors":[{"bufferView":0,"componentType":5126,"count":3,"type":"VEC3","min":[0,0,0],"max":[1,1,0]}],"bufferViews":[{"buffer":0,"byteLength":36}],"buffers":[{"byteLength":36}]}"#;
    let bin: Vec<u8> = [0f32, 0., 0., 1., 0., 0., 0., 1., 0.]
        .iter()
        .flat_map(|x| x.to_le_bytes())
        .collect();
    let mut out = common::glb(json, &bin);
    for &(at, value) in lies {
        out[at..at + 4].copy_from_slice(&value.to_le_bytes());
    }
    out
}

/// GLBs whose lengths lie (the header's total, the JSON chunk's, the BIN chunk's, each
/// claiming up to 4 GiB, or less than the file holds) are refused naming the file, in
/// bounded memory. The twin: the same GLB with its true lengths loads.
#[test]
fn glbs_whose_chunk_lengths_lie_are_refused() {
    let d = common::Scratch::new("hostile-glb");
    let bin_at = 20 + u32::from_le_bytes(glb(&[])[12..16].try_into().unwrap()) as usize;
    let lies = [
        ("total-huge", (8, u32::MAX)),
        ("total-short", (8, 40)),
        ("total-tiny", (8, 4)),
        ("json-huge", (12, u32::MAX - 3)),
        ("json-short", (12, 8)),
        ("bin-huge", (bin_at, u32::MAX - 3)),
    ];
    for (name, lie) in lies {
        let file = format!("{name}.glb");
        std::fs::write(d.join(&file), glb(&[lie])).unwrap();
        refused(&mesh_scene(&d, name, &file), &[], &[&file]);
    }
    std::fs::write(d.join("true.glb"), glb(&[])).unwrap();
    let (code, text, _) = check_capped(&mesh_scene(&d, "true", "true.glb"), &[]);
    assert_eq!(code, Some(0), "{text}");
}

/// A PNG header and a JPEG header each claiming 65535×65535 pixels (16 GiB decoded) are
/// refused naming the material's key and the file.
#[test]
fn textures_claiming_65535_squared_pixels_are_refused() {
    let d = common::Scratch::new("hostile-texture");
    // PNG: the signature and an IHDR of 65535×65535 RGB8, then an empty IDAT and IEND.
    let mut png = b"\x89PNG\r\n\x1a\n".to_vec();
    let chunk = |png: &mut Vec<u8>, kind: &[u8], data: &[u8]| {
        png.extend_from_slice(&(data.len() as u32).to_be_bytes());
        let mut c = kind.to_vec();
        c.extend_from_slice(data);
        png.extend_from_slice(&c);
        png.extend_from_slice(&common::crc32(&c).to_be_bytes());
    };
    let mut ihdr = Vec::new();
    ihdr.extend_from_slice(&65535u32.to_be_bytes());
    ihdr.extend_from_slice(&65535u32.to_be_bytes());
    ihdr.extend_from_slice(&[8, 2, 0, 0, 0]);
    chunk(&mut png, b"IHDR", &ihdr);
    chunk(&mut png, b"IDAT", &[]);
    chunk(&mut png, b"IEND", &[]);
    std::fs::write(d.join("huge.png"), &png).unwrap();
    // JPEG: SOI, a baseline SOF0 of 65535×65535 with three components, EOI.
    let mut jpg = vec![
        0xFF, 0xD8, 0xFF, 0xC0, 0x00, 0x11, 0x08, 0xFF, 0xFF, 0xFF, 0xFF, 0x03,
    ];
    for id in 1..=3u8 {
        jpg.extend_from_slice(&[id, 0x11, 0x00]);
    }
    jpg.extend_from_slice(&[0xFF, 0xD9]);
    std::fs::write(d.join("huge.jpg"), &jpg).unwrap();
    for file in ["huge.png", "huge.jpg"] {
        let p = d.join(format!("{file}.toml"));
        std::fs::write(
            &p,
            format!(
                "{HEAD}[materials.m]\nmodel = \"diffuse\"\nka = [0.1, 0.1, 0.1]\n\
                 kd = [0.8, 0.8, 0.8]\nmap_kd = \"{file}\"\n\
                 [[spheres]]\ncenter = [0.0, 0.0, 0.0]\nradius = 1.0\nmaterial = \"m\"\n"
            ),
        )
        .unwrap();
        refused(&p, &[], &["materials.m.map_kd", file]);
    }
}

/// A texture reached through a symbolic link out of the scene's folder is refused under
/// `--confine`, naming the key and the file; the twin: without `--confine` it loads.
#[test]
fn a_texture_linked_out_of_the_folder_is_refused_when_confined() {
    let d = common::Scratch::new("hostile-link");
    let sub = d.join("sub");
    std::fs::create_dir_all(&sub).unwrap();
    image::RgbImage::from_pixel(2, 2, image::Rgb([200, 100, 50]))
        .save(d.join("outside.png"))
        .unwrap();
    std::os::unix::fs::symlink("../outside.png", sub.join("tex.png")).unwrap();
    let p = sub.join("s.toml");
    std::fs::write(
        &p,
        format!(
            "{HEAD}[materials.m]\nmodel = \"diffuse\"\nka = [0.1, 0.1, 0.1]\n\
             kd = [0.8, 0.8, 0.8]\nmap_kd = \"tex.png\"\n\
             [[spheres]]\ncenter = [0.0, 0.0, 0.0]\nradius = 1.0\nmaterial = \"m\"\n"
        ),
    )
    .unwrap();
    refused(
        &p,
        &["--confine"],
        &[
            "materials.m.map_kd",
            "tex.png",
            "outside the scene's folder",
        ],
    );
    let (code, text, _) = check_capped(&p, &[]);
    assert_eq!(code, Some(0), "{text}");
}
