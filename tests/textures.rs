//! Image textures: a textured quad shows its texture upright with each texel's linear
//! colour at its centre; `map_ka` colours the ambient term apart; the same textured mesh
//! as OBJ, ASCII and binary PLY and `.glb` renders equal in every bit; GPU, packet tracer
//! and mirror agree on the textured scene (every bit on lavapipe); untextured scenes are
//! untouched; bad textures and coordinates give errors naming file, line and key; a texture
//! over the budget is downscaled with a warning.

mod common;

gpu_sentinel!();

use std::path::Path;

use common::{Scratch, buffers, check_agreement, render_gpu};
use glint::buffers::Specialisation;
use glint::image::Image;
use glint::scene::{Scene, SceneError, TriangleAlgorithm};

/// The sRGB decoding of an 8-bit value, written out here apart from the library's.
fn linear(c: u8) -> f64 {
    let x = c as f64 / 255.0;
    if x <= 0.04045 {
        x / 12.92
    } else {
        ((x + 0.055) / 1.055).powf(2.4)
    }
}

/// A 4×2 texture, top row first: every texel a colour of its own.
const TEX: [[[u8; 3]; 4]; 2] = [
    [[255, 0, 0], [0, 255, 0], [0, 0, 255], [255, 255, 0]],
    [[0, 255, 255], [255, 0, 255], [128, 128, 128], [32, 64, 200]],
];

fn write_png(path: &Path, w: u32, h: u32, f: impl Fn(u32, u32) -> [u8; 3]) {
    image::RgbImage::from_fn(w, h, |x, y| image::Rgb(f(x, y)))
        .save(path)
        .unwrap();
}

/// The quad x ∈ [−2, 2], y ∈ [−1, 1] at z = 0, (u, v) from (0, 0) at its bottom-left to
/// (1, 1), seen from z = 1 with a 90° field of view at 4×2 pixels: each pixel centre lies
/// on a texel centre. Ambient light 1 on an ambient material with ka = 1, so a pixel is its
/// texel's colour. `material` is the material's texture keys.
fn quad(dir: &Path, material: &str) -> Result<Scene, SceneError> {
    let src = format!(
        r#"ambient = [1.0, 1.0, 1.0]
[camera]
eye = [0.0, 0.0, 1.0]
look_at = [0.0, 0.0, 0.0]
fov = 90.0
width = 4
height = 2
[materials.m]
model = "ambient"
ka = [1.0, 1.0, 1.0]
{material}
[[triangles]]
vertices = [[-2.0, -1.0, 0.0], [2.0, -1.0, 0.0], [2.0, 1.0, 0.0]]
uvs = [[0.0, 0.0], [1.0, 0.0], [1.0, 1.0]]
material = "m"
[[triangles]]
vertices = [[-2.0, -1.0, 0.0], [2.0, 1.0, 0.0], [-2.0, 1.0, 0.0]]
uvs = [[0.0, 0.0], [1.0, 1.0], [0.0, 1.0]]
material = "m"
"#
    );
    let path = dir.join("quad.toml");
    std::fs::write(&path, &src).unwrap();
    Scene::load(&path)
}

fn render_both(scene: &Scene) -> (Image, Image) {
    let (w, h) = scene.size();
    let (buf, spec) = buffers(scene, w, h, scene.triangle);
    (
        glint::cpu::render_f32(&buf, spec),
        glint::cpu::render_f64(scene, &buf, spec),
    )
}

/// Whether every pixel of `img` is the linear colour of texel (i, j) of `tex` (top row
/// first) within 1e-5: what "upright at the texel centres" means.
fn shows(img: &Image, tex: &[[[u8; 3]; 4]; 2]) -> Result<(), String> {
    for j in 0..2u32 {
        for i in 0..4u32 {
            let got = img.pixels[(j * 4 + i) as usize];
            let want = tex[j as usize][i as usize].map(linear);
            for c in 0..3 {
                if (got[c] as f64 - want[c]).abs() > 1e-5 {
                    return Err(format!("pixel ({i}, {j}): {got:?} against {want:?}"));
                }
            }
        }
    }
    Ok(())
}

/// The quad shows the texture upright, each pixel its texel's linear colour, in f32 and
/// f64 (on the GPU too, in every bit on lavapipe). The twins: the texture upside down, or
/// mirrored, does not pass the same check.
#[test]
fn a_textured_quad_shows_its_texture_upright_at_the_texel_centres() {
    let dir = Scratch::new("tex-quad");
    write_png(&dir.join("t.png"), 4, 2, |x, y| TEX[y as usize][x as usize]);
    let scene = quad(&dir, "map_kd = \"t.png\"").unwrap_or_else(|e| panic!("{e}"));
    assert!(scene.warnings.is_empty(), "{:?}", scene.warnings);
    let (c, r) = render_both(&scene);
    shows(&c, &TEX).unwrap();
    shows(&r, &TEX).unwrap();
    if let Some(gpu) = common::gpu() {
        let (buf, spec) = buffers(&scene, 4, 2, scene.triangle);
        assert!(spec.textures);
        check_agreement(
            &render_gpu(gpu, &buf, spec),
            &c,
            common::bit_exact_expected(gpu),
        )
        .unwrap();
    }
    let upside_down = [TEX[1], TEX[0]];
    assert!(shows(&c, &upside_down).is_err(), "the twin: flipped rows");
    let mirrored = TEX.map(|mut row| {
        row.reverse();
        row
    });
    assert!(shows(&c, &mirrored).is_err(), "the twin: mirrored columns");
}

/// `map_ka` colours the ambient term in place of `map_kd`; without it, `map_kd` colours
/// both. The twin: the same scene with `map_kd` alone shows `map_kd`'s texture.
#[test]
fn map_ka_colours_the_ambient_term_apart() {
    let dir = Scratch::new("tex-ka");
    write_png(&dir.join("t.png"), 4, 2, |x, y| TEX[y as usize][x as usize]);
    let other = [TEX[1], TEX[0]];
    write_png(&dir.join("o.png"), 4, 2, |x, y| {
        other[y as usize][x as usize]
    });
    let both = quad(&dir, "map_kd = \"t.png\"\nmap_ka = \"o.png\"").unwrap();
    assert_eq!(both.textures.len(), 2);
    let (c, _) = render_both(&both);
    shows(&c, &other).unwrap();
    let kd_only = quad(&dir, "map_kd = \"t.png\"").unwrap();
    let (c, _) = render_both(&kd_only);
    assert!(shows(&c, &other).is_err());
}

/// A face's corners, a quad per face with its own corners (so that a PLY's per-vertex
/// coordinates can differ between faces sharing a position), and (u, v) in multiples of
/// 1/4, exact under glTF's v-flip.
struct Mesh {
    v: Vec<[f32; 3]>,
    uv: Vec<[f32; 2]>,
    quads: Vec<[u32; 4]>,
}

/// A unit cube's six faces, each textured over a different quarter-range.
fn cube() -> Mesh {
    let c = |x: i32, y: i32, z: i32| [x as f32 * 0.5, y as f32 * 0.5, z as f32 * 0.5];
    let faces = [
        [c(-1, -1, 1), c(1, -1, 1), c(1, 1, 1), c(-1, 1, 1)],
        [c(1, -1, -1), c(-1, -1, -1), c(-1, 1, -1), c(1, 1, -1)],
        [c(1, -1, 1), c(1, -1, -1), c(1, 1, -1), c(1, 1, 1)],
        [c(-1, -1, -1), c(-1, -1, 1), c(-1, 1, 1), c(-1, 1, -1)],
        [c(-1, 1, 1), c(1, 1, 1), c(1, 1, -1), c(-1, 1, -1)],
        [c(-1, -1, -1), c(1, -1, -1), c(1, -1, 1), c(-1, -1, 1)],
    ];
    let mut m = Mesh {
        v: Vec::new(),
        uv: Vec::new(),
        quads: Vec::new(),
    };
    for (k, f) in faces.iter().enumerate() {
        let base = m.v.len() as u32;
        let (u0, v0) = ((k % 2) as f32 * 0.25, (k / 2) as f32 * 0.25);
        m.v.extend(f);
        m.uv.extend([
            [u0, v0],
            [u0 + 1.25, v0],
            [u0 + 1.25, v0 + 0.75],
            [u0, v0 + 0.75],
        ]);
        m.quads.push([base, base + 1, base + 2, base + 3]);
    }
    m
}

/// The triangles of the quads as tobj fans them: (0, 1, 2), (0, 2, 3).
fn triangles(m: &Mesh) -> Vec<[u32; 3]> {
    m.quads
        .iter()
        .flat_map(|q| [[q[0], q[1], q[2]], [q[0], q[2], q[3]]])
        .collect()
}

fn write_obj(m: &Mesh) -> String {
    let mut s = String::from("mtllib m.mtl\n");
    for p in &m.v {
        s += &format!("v {:?} {:?} {:?}\n", p[0], p[1], p[2]);
    }
    for t in &m.uv {
        s += &format!("vt {:?} {:?}\n", t[0], t[1]);
    }
    s += "usemtl tex\n";
    for q in &m.quads {
        s += &format!(
            "f {0}/{0} {1}/{1} {2}/{2} {3}/{3}\n",
            q[0] + 1,
            q[1] + 1,
            q[2] + 1,
            q[3] + 1
        );
    }
    s
}

fn write_ply(m: &Mesh, binary: bool) -> Vec<u8> {
    let mut s = format!(
        "ply\nformat {} 1.0\nelement vertex {}\nproperty float x\nproperty float y\nproperty float z\nproperty float u\nproperty float v\nelement face {}\nproperty list uchar int vertex_indices\nend_header\n",
        if binary {
            "binary_little_endian"
        } else {
            "ascii"
        },
        m.v.len(),
        m.quads.len()
    )
    .into_bytes();
    for (p, t) in m.v.iter().zip(&m.uv) {
        if binary {
            for x in p.iter().chain(t) {
                s.extend(x.to_le_bytes());
            }
        } else {
            s.extend(format!("{:?} {:?} {:?} {:?} {:?}\n", p[0], p[1], p[2], t[0], t[1]).bytes());
        }
    }
    for q in &m.quads {
        if binary {
            s.push(4);
            for k in q {
                s.extend((*k as i32).to_le_bytes());
            }
        } else {
            s.extend(format!("4 {} {} {} {}\n", q[0], q[1], q[2], q[3]).bytes());
        }
    }
    s
}

/// A `.glb` of the mesh: POSITION, TEXCOORD_0 (v flipped to glTF's v-down), 32-bit
/// indices, and a material whose base colour texture is `png`, held in a buffer view.
fn write_glb(m: &Mesh, png: &[u8]) -> Vec<u8> {
    let tris = triangles(m);
    let mut bin = Vec::new();
    for p in &m.v {
        p.iter().for_each(|x| bin.extend(x.to_le_bytes()));
    }
    let uv_at = bin.len();
    for t in &m.uv {
        bin.extend(t[0].to_le_bytes());
        bin.extend((1.0 - t[1]).to_le_bytes());
    }
    let ix_at = bin.len();
    for t in &tris {
        t.iter().for_each(|k| bin.extend(k.to_le_bytes()));
    }
    let png_at = bin.len();
    bin.extend(png);
    while !bin.len().is_multiple_of(4) {
        bin.push(0);
    }
    let n = m.v.len();
    let json = format!(
        r#"{{"asset":{{"version":"2.0"}},"scene":0,"scenes":[{{"nodes":[0]}}],"nodes":[{{"mesh":0}}],
"meshes":[{{"primitives":[{{"attributes":{{"POSITION":0,"TEXCOORD_0":1}},"indices":2,"material":0}}]}}],
"materials":[{{"name":"tex","pbrMetallicRoughness":{{"baseColorTexture":{{"index":0}}}}}}],
"textures":[{{"source":0}}],"images":[{{"bufferView":3,"mimeType":"image/png"}}],
"accessors":[{{"bufferView":0,"componentType":5126,"count":{n},"type":"VEC3","min":[-0.5,-0.5,-0.5],"max":[0.5,0.5,0.5]}},
{{"bufferView":1,"componentType":5126,"count":{n},"type":"VEC2"}},
{{"bufferView":2,"componentType":5125,"count":{},"type":"SCALAR"}}],
"bufferViews":[{{"buffer":0,"byteOffset":0,"byteLength":{uv_at}}},{{"buffer":0,"byteOffset":{uv_at},"byteLength":{}}},
{{"buffer":0,"byteOffset":{ix_at},"byteLength":{}}},{{"buffer":0,"byteOffset":{png_at},"byteLength":{}}}],
"buffers":[{{"byteLength":{}}}]}}"#,
        tris.len() * 3,
        ix_at - uv_at,
        png_at - ix_at,
        png.len(),
        bin.len()
    );
    common::glb(&json, &bin)
}

/// A scene of the mesh `file`, lit, at 64×48; `material` names a scene material (the
/// textured `m`), else the file's own.
fn mesh_scene(dir: &Path, file: &str, material: bool) -> Scene {
    let src = format!(
        r#"ambient = [0.3, 0.3, 0.3]
[camera]
eye = [1.2, 1.0, 1.6]
look_at = [0.0, 0.0, 0.0]
fov = 50.0
width = 64
height = 48
[[lights]]
position = [2.0, 3.0, 4.0]
color = [1.0, 1.0, 1.0]
[materials.m]
model = "diffuse"
ka = [1.0, 1.0, 1.0]
kd = [1.0, 1.0, 1.0]
map_kd = "t.png"
[[meshes]]
file = "{file}"
{}
"#,
        if material { "material = \"m\"" } else { "" }
    );
    let path = dir.join(format!("{file}.toml"));
    std::fs::write(&path, src).unwrap();
    Scene::load(&path).unwrap_or_else(|e| panic!("{file}: {e}"))
}

fn bits(scene: &Scene) -> Vec<u32> {
    let (buf, spec) = buffers(scene, 64, 48, TriangleAlgorithm::Watertight);
    assert!(spec.textures);
    glint::cpu::render_f32(&buf, spec)
        .pixels
        .iter()
        .flatten()
        .map(|x| x.to_bits())
        .collect()
}

/// The same textured mesh as an OBJ (its MTL's `map_Kd`, or the scene's textured
/// material), ASCII and binary PLY and `.glb` renders equal in every f32 bit, and the
/// `.glb` with its own texture renders so on the GPU too (every bit on lavapipe). The
/// twin: one texture coordinate changed in the PLY changes the image.
#[test]
fn the_same_textured_mesh_in_every_format_renders_the_same() {
    let dir = Scratch::new("tex-formats");
    write_png(&dir.join("t.png"), 4, 2, |x, y| TEX[y as usize][x as usize]);
    let m = cube();
    std::fs::write(dir.join("c.obj"), write_obj(&m)).unwrap();
    std::fs::write(
        dir.join("m.mtl"),
        "newmtl tex\nKa 1 1 1\nKd 1 1 1\nmap_Kd t.png\n",
    )
    .unwrap();
    std::fs::write(dir.join("a.ply"), write_ply(&m, false)).unwrap();
    std::fs::write(dir.join("b.ply"), write_ply(&m, true)).unwrap();
    let png = std::fs::read(dir.join("t.png")).unwrap();
    std::fs::write(dir.join("c.glb"), write_glb(&m, &png)).unwrap();
    let want = bits(&mesh_scene(&dir, "c.obj", false));
    for (file, material) in [
        ("c.obj", true),
        ("a.ply", true),
        ("b.ply", true),
        ("c.glb", false),
        ("c.glb", true),
    ] {
        let s = mesh_scene(&dir, file, material);
        assert!(s.warnings.is_empty(), "{file}: {:?}", s.warnings);
        assert!(bits(&s) == want, "{file} (scene material: {material})");
    }
    // The glTF with its own baseColorTexture on the GPU: every bit on lavapipe.
    if let Some(gpu) = common::gpu() {
        let (buf, spec) = buffers(
            &mesh_scene(&dir, "c.glb", false),
            64,
            48,
            TriangleAlgorithm::Watertight,
        );
        check_agreement(
            &render_gpu(gpu, &buf, spec),
            &glint::cpu::render_f32(&buf, spec),
            common::bit_exact_expected(gpu),
        )
        .unwrap_or_else(|e| panic!("c.glb: {e}"));
    }
    let mut moved = cube();
    moved.uv[0][0] += 0.125;
    std::fs::write(dir.join("d.ply"), write_ply(&moved, true)).unwrap();
    assert!(bits(&mesh_scene(&dir, "d.ply", true)) != want, "the twin");
}

/// The GPU (in every bit on lavapipe), the packet tracer and the mirror agree on the
/// shipped textured scene with each triangle algorithm. The twin: the scene without its
/// floor texture renders otherwise.
#[test]
fn gpu_packet_and_mirror_agree_on_textures() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/textured.toml");
    let scene = Scene::load(&path).unwrap();
    assert!(scene.warnings.is_empty(), "{:?}", scene.warnings);
    let gpu = common::gpu();
    for algo in TriangleAlgorithm::ALL {
        let (buf, spec) = buffers(&scene, 160, 120, algo);
        assert!(spec.textures);
        let c = glint::cpu::render_f32(&buf, spec);
        let m = glint::cpu::render_f32_mirror(&buf, spec);
        assert!(glint::compare::diff(&c, &m).bit_exact(), "{algo}");
        if let Some(gpu) = gpu {
            check_agreement(
                &render_gpu(gpu, &buf, spec),
                &c,
                common::bit_exact_expected(gpu),
            )
            .unwrap_or_else(|e| panic!("{algo}: {e}"));
        }
    }
    let plain = Scene::parse(
        &std::fs::read_to_string(&path).unwrap().replacen(
            "map_kd = \"textures/checker.png\"\n",
            "",
            1,
        ),
        &path,
    )
    .unwrap();
    let (a, sa) = buffers(&scene, 160, 120, scene.triangle);
    let (b, sb) = buffers(&plain, 160, 120, plain.triangle);
    assert!(
        !glint::compare::diff(
            &glint::cpu::render_f32(&a, sa),
            &glint::cpu::render_f32(&b, sb)
        )
        .bit_exact()
    );
}

/// A scene without textures compiled with `TEXTURES` gives the image it gives without,
/// in every bit, on the CPU and the GPU (and such scenes compile none of it).
#[test]
fn untextured_scenes_are_untouched() {
    for name in ["bb8-shadows", "mitsubishi-shadows", "whitted", "spot"] {
        let scene = common::seed_scene(name);
        let (buf, spec) = buffers(&scene, 96, 72, scene.triangle);
        assert!(!spec.textures, "{name}");
        let on = Specialisation {
            textures: true,
            ..spec
        };
        let today = glint::cpu::render_f32(&buf, spec);
        assert!(
            glint::compare::diff(&today, &glint::cpu::render_f32_mirror(&buf, on)).bit_exact(),
            "{name}"
        );
        if let Some(gpu) = common::gpu() {
            assert!(
                glint::compare::diff(&render_gpu(gpu, &buf, spec), &render_gpu(gpu, &buf, on))
                    .bit_exact(),
                "{name} on the GPU"
            );
        }
    }
}

fn error(dir: &Path, material: &str) -> String {
    match quad(dir, material) {
        Ok(_) => panic!("{material}: no error"),
        Err(e) => e.to_string(),
    }
}

/// Errors name the file, the line and the key (and the texture): a missing texture, a
/// file that is not an image, one whose header claims a size past the limit, coordinates
/// that are not finite, an MTL's missing `map_Kd`. Warnings: coordinates without a texture, a texture without coordinates. The
/// twin: the good quad loads without a warning.
#[test]
fn bad_textures_and_coordinates_are_named() {
    let dir = Scratch::new("tex-errors");
    write_png(&dir.join("t.png"), 4, 2, |x, y| TEX[y as usize][x as usize]);
    std::fs::write(dir.join("junk.png"), b"not an image at all").unwrap();
    assert!(
        quad(&dir, "map_kd = \"t.png\"")
            .unwrap()
            .warnings
            .is_empty()
    );
    let e = error(&dir, "map_kd = \"gone.png\"");
    assert!(
        e.contains("quad.toml:11: materials.m.map_kd: ") && e.contains("gone.png: cannot read"),
        "{e}"
    );
    let e = error(&dir, "map_ka = \"junk.png\"");
    assert!(
        e.contains("materials.m.map_ka") && e.contains("junk.png: cannot decode"),
        "{e}"
    );
    // A PNG whose header claims 100000×100000 texels (30 GB decoded): refused from the
    // header, before any allocation.
    let mut png = b"\x89PNG\r\n\x1a\n".to_vec();
    let mut ihdr = b"IHDR".to_vec();
    ihdr.extend(100_000u32.to_be_bytes());
    ihdr.extend(100_000u32.to_be_bytes());
    ihdr.extend([8, 2, 0, 0, 0]);
    png.extend(13u32.to_be_bytes());
    png.extend(&ihdr);
    png.extend(common::crc32(&ihdr).to_be_bytes());
    std::fs::write(dir.join("huge.png"), &png).unwrap();
    let e = error(&dir, "map_kd = \"huge.png\"");
    assert!(
        e.contains("materials.m.map_kd") && e.contains("huge.png: cannot decode"),
        "{e}"
    );
    // Coordinates that are not finite (TOML's nan), in the good quad.
    quad(&dir, "map_kd = \"t.png\"").unwrap();
    let path = dir.join("nan.toml");
    let text = std::fs::read_to_string(dir.join("quad.toml"))
        .unwrap()
        .replacen(
            "uvs = [[0.0, 0.0], [1.0, 0.0]",
            "uvs = [[nan, 0.0], [1.0, 0.0]",
            1,
        );
    std::fs::write(&path, text).unwrap();
    let e = Scene::load(&path).unwrap_err().to_string();
    assert!(
        e.contains("triangles[0].uvs") && e.contains("not finite"),
        "{e}"
    );
    // Coordinates on an untextured material, and a textured one without coordinates.
    let text = std::fs::read_to_string(dir.join("quad.toml")).unwrap();
    let plain = text.replacen("map_kd = \"t.png\"", "", 1);
    let s = Scene::parse(&plain, &dir.join("p.toml")).unwrap();
    assert!(
        s.warnings.iter().any(
            |w| w.contains("triangles[0].uvs") && w.contains("has no map_kd or map_ka: unused")
        ),
        "{:?}",
        s.warnings
    );
    let bare = text.replacen("uvs = [[0.0, 0.0], [1.0, 1.0], [0.0, 1.0]]\n", "", 1);
    let s = Scene::parse(&bare, &dir.join("quad.toml")).unwrap();
    assert!(
        s.warnings
            .iter()
            .any(|w| w.contains("triangles[1]") && w.contains("no uvs: untextured")),
        "{:?}",
        s.warnings
    );
    // An MTL naming a texture that is not there.
    let m = cube();
    std::fs::write(dir.join("c.obj"), write_obj(&m)).unwrap();
    std::fs::write(
        dir.join("m.mtl"),
        "newmtl tex\nKd 1 1 1\nmap_Kd nowhere.png\n",
    )
    .unwrap();
    let src = "[camera]\neye = [0.0, 0.0, 3.0]\nlook_at = [0.0, 0.0, 0.0]\nfov = 40.0\nwidth = 8\nheight = 8\n[[meshes]]\nfile = \"c.obj\"\n";
    let e = Scene::parse(src, &dir.join("s.toml"))
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("meshes[0].file") && e.contains("texture ") && e.contains("nowhere.png"),
        "{e}"
    );
}

/// Coordinates far outside [0, 1], negative ones and huge ones wrap (repeat) without
/// failing: u + k for whole k reads what u reads when both are exact; 1e30 wraps to 0.
#[test]
fn coordinates_wrap_around() {
    let dir = Scratch::new("tex-wrap");
    write_png(&dir.join("t.png"), 4, 2, |x, y| TEX[y as usize][x as usize]);
    let base = quad(&dir, "map_kd = \"t.png\"").unwrap();
    let text = std::fs::read_to_string(dir.join("quad.toml")).unwrap();
    let shifted = text
        .replace(
            "[0.0, 0.0], [1.0, 0.0], [1.0, 1.0]",
            "[-3.0, 5.0], [-2.0, 5.0], [-2.0, 6.0]",
        )
        .replace(
            "[0.0, 0.0], [1.0, 1.0], [0.0, 1.0]",
            "[-3.0, 5.0], [-2.0, 6.0], [-3.0, 6.0]",
        );
    let s = Scene::parse(&shifted, &dir.join("quad.toml")).unwrap();
    let (c, _) = render_both(&s);
    let (want, _) = render_both(&base);
    // Not bit-equal (the interpolated coordinates round differently), but the same texels.
    shows(&c, &TEX).unwrap();
    shows(&want, &TEX).unwrap();
    let huge = text.replace("[1.0, 1.0]", "[1e30, 1e30]");
    let s = Scene::parse(&huge, &dir.join("quad.toml")).unwrap();
    let (c, r) = render_both(&s);
    assert!(
        c.pixels
            .iter()
            .chain(&r.pixels)
            .flatten()
            .all(|x| x.is_finite())
    );
}

/// A texture over the budget is downscaled by halving until it fits, with a warning; the
/// image's mean colour survives. The twin: one that fits is kept at its size, silently.
#[test]
fn a_texture_over_the_budget_is_downscaled_with_a_warning() {
    let dir = Scratch::new("tex-budget");
    let side = 4096; // 2^24 texels, twice the budget
    assert!(side * side > glint::scene::texture::TEXEL_BUDGET);
    write_png(&dir.join("big.png"), side as u32, side as u32, |x, y| {
        if (x + y) % 2 == 0 {
            [255, 255, 255]
        } else {
            [0, 0, 0]
        }
    });
    let s = quad(&dir, "map_kd = \"big.png\"").unwrap();
    assert_eq!((s.textures[0].width, s.textures[0].height), (2048, 2048));
    assert!(
        s.warnings.iter().any(
            |w| w.contains("big.png") && w.contains("4096×4096 texels downscaled to 2048×2048")
        ),
        "{:?}",
        s.warnings
    );
    // A 1-pixel checker averages to half of white's linear value, exactly.
    assert!(s.textures[0].texels.iter().all(|&x| x == 0.5), "mean kept");
    write_png(&dir.join("small.png"), 64, 64, |_, _| [10, 20, 30]);
    let s = quad(&dir, "map_kd = \"small.png\"").unwrap();
    assert_eq!((s.textures[0].width, s.textures[0].height), (64, 64));
    assert!(s.warnings.is_empty());
}
