//! PLY meshes: the same mesh as OBJ, ASCII PLY, binary little- and big-endian PLY (float
//! or double positions, any integer width for counts and indices) and gzipped PLY gives
//! the same triangles in the same order, so the same image in every bit; smooth normals
//! from `nx ny nz` equal the OBJ's `vn`; a malformed file names the element and its index.

mod common;

use std::fmt::Write as _;
use std::path::Path;

use glint::buffers::{SceneBuffers, Specialisation};
use glint::scene::{MeshError, Scene, SceneError};

/// A mesh: vertices (with the OBJ's text of each coordinate), normals, polygons.
struct Mesh {
    text: Vec<[String; 3]>,
    normals: Vec<[f32; 3]>,
    faces: Vec<Vec<u32>>,
}

impl Mesh {
    fn v(&self) -> Vec<[f32; 3]> {
        self.text
            .iter()
            .map(|t| t.clone().map(|s| s.parse().unwrap()))
            .collect()
    }
}

/// `tests/data/meshes/NAME.obj`'s `v` and `f` lines (triangles there).
fn obj_mesh(name: &str) -> Mesh {
    let text = std::fs::read_to_string(
        Path::new(env!("CARGO_MANIFEST_DIR")).join(format!("tests/data/meshes/{name}.obj")),
    )
    .unwrap();
    let mut m = Mesh {
        text: Vec::new(),
        normals: Vec::new(),
        faces: Vec::new(),
    };
    for line in text.lines() {
        let w: Vec<&str> = line.split_whitespace().collect();
        match w.first() {
            Some(&"v") => m.text.push([w[1].into(), w[2].into(), w[3].into()]),
            Some(&"f") => m.faces.push(
                w[1..]
                    .iter()
                    .map(|c| c.split('/').next().unwrap().parse::<u32>().unwrap() - 1)
                    .collect(),
            ),
            _ => {}
        }
    }
    m
}

/// A bumpy grid of quads and pentagons with per-vertex normals: polygons to fan.
fn polygon_mesh() -> Mesh {
    let mut rng = common::Rng::new(7);
    let n = 12;
    let mut m = Mesh {
        text: Vec::new(),
        normals: Vec::new(),
        faces: Vec::new(),
    };
    for j in 0..=n {
        for i in 0..=n {
            let (x, y) = (
                i as f32 / n as f32 * 2.0 - 1.0,
                j as f32 / n as f32 * 2.0 - 1.0,
            );
            let z = rng.range(-0.1, 0.1);
            m.text.push([x, y, z].map(|c| format!("{c:?}")));
            let nn = [rng.range(-0.3, 0.3), rng.range(-0.3, 0.3), 1.0];
            m.normals.push(nn);
        }
    }
    let at = |i: u32, j: u32| j * (n + 1) + i;
    for j in 0..n {
        for i in 0..n {
            if i + 1 < n && (i + j) % 5 == 0 {
                // A pentagon over two cells' worth of corners.
                m.faces.push(vec![
                    at(i, j),
                    at(i + 1, j),
                    at(i + 2, j),
                    at(i + 1, j + 1),
                    at(i, j + 1),
                ]);
            } else {
                m.faces
                    .push(vec![at(i, j), at(i + 1, j), at(i + 1, j + 1), at(i, j + 1)]);
            }
        }
    }
    m
}

fn write_obj(m: &Mesh, normals: bool) -> Vec<u8> {
    let mut s = String::new();
    for t in &m.text {
        writeln!(s, "v {} {} {}", t[0], t[1], t[2]).unwrap();
    }
    if normals {
        for n in &m.normals {
            writeln!(s, "vn {:?} {:?} {:?}", n[0], n[1], n[2]).unwrap();
        }
    }
    for f in &m.faces {
        let c: Vec<String> = f
            .iter()
            .map(|k| {
                if normals {
                    format!("{}//{}", k + 1, k + 1)
                } else {
                    format!("{}", k + 1)
                }
            })
            .collect();
        writeln!(s, "f {}", c.join(" ")).unwrap();
    }
    s.into_bytes()
}

/// How a PLY is written.
#[derive(Clone, Copy, Debug)]
enum Ply {
    Ascii,
    Little,
    Big,
    /// Little-endian, double positions, ushort counts, short indices, and extra properties
    /// and an extra element to read past.
    LittleOdd,
}

fn write_ply(m: &Mesh, how: Ply, normals: bool) -> Vec<u8> {
    let format = match how {
        Ply::Ascii => "ascii",
        Ply::Little | Ply::LittleOdd => "binary_little_endian",
        Ply::Big => "binary_big_endian",
    };
    let odd = matches!(how, Ply::LittleOdd);
    let pos = if odd { "double" } else { "float" };
    let mut h = format!("ply\nformat {format} 1.0\ncomment made by tests/ply.rs\n");
    if odd {
        h += "element camera 1\nproperty float view_px\n";
    }
    writeln!(h, "element vertex {}", m.text.len()).unwrap();
    if odd {
        h += "property uchar red\n";
    }
    write!(h, "property {pos} x\nproperty {pos} y\nproperty {pos} z\n").unwrap();
    if normals {
        h += "property float nx\nproperty float ny\nproperty float nz\n";
    }
    if odd {
        h += "property list uchar float texcoord\n";
    }
    writeln!(h, "element face {}", m.faces.len()).unwrap();
    if odd {
        h += "property list ushort short vertex_indices\nproperty int flags\n";
    } else {
        h += "property list uchar int vertex_indices\n";
    }
    h += "end_header\n";
    let mut out = h.into_bytes();
    let big = matches!(how, Ply::Big);
    let f32b = |x: f32| {
        if big {
            x.to_be_bytes()
        } else {
            x.to_le_bytes()
        }
    };
    let i32b = |x: i32| {
        if big {
            x.to_be_bytes()
        } else {
            x.to_le_bytes()
        }
    };
    let v = m.v();
    if odd {
        out.extend(1.5f32.to_le_bytes());
    }
    for (k, p) in v.iter().enumerate() {
        match how {
            Ply::Ascii => {
                let t = &m.text[k];
                let mut line = format!("{} {} {}", t[0], t[1], t[2]);
                if normals {
                    let n = m.normals[k];
                    write!(line, " {:?} {:?} {:?}", n[0], n[1], n[2]).unwrap();
                }
                out.extend(line.as_bytes());
                out.push(b'\n');
            }
            _ => {
                if odd {
                    out.push(200);
                    for c in p {
                        out.extend((*c as f64).to_le_bytes());
                    }
                } else {
                    for c in p {
                        out.extend(f32b(*c));
                    }
                }
                if normals {
                    for c in m.normals[k] {
                        out.extend(f32b(c));
                    }
                }
                if odd {
                    out.push(2);
                    out.extend(0.25f32.to_le_bytes());
                    out.extend(0.75f32.to_le_bytes());
                }
            }
        }
    }
    for f in &m.faces {
        match how {
            Ply::Ascii => {
                let c: Vec<String> = f.iter().map(|k| k.to_string()).collect();
                out.extend(format!("{} {}\n", f.len(), c.join(" ")).as_bytes());
            }
            Ply::LittleOdd => {
                out.extend((f.len() as u16).to_le_bytes());
                for &k in f {
                    out.extend((k as i16).to_le_bytes());
                }
                out.extend(7i32.to_le_bytes());
            }
            _ => {
                out.push(f.len() as u8);
                for &k in f {
                    out.extend(i32b(k as i32));
                }
            }
        }
    }
    out
}

fn scene_text(file: &str, smooth: bool) -> String {
    format!(
        r#"ambient = [0.2, 0.2, 0.2]
shadows = true
[camera]
eye = [0.4, 0.5, 3.0]
look_at = [0.0, 0.0, 0.0]
fov = 50.0
width = 96
height = 72
[[lights]]
position = [2.0, 3.0, 4.0]
color = [1.0, 1.0, 1.0]
[materials.m]
model = "phong"
ka = [0.3, 0.2, 0.1]
kd = [0.6, 0.5, 0.4]
ks = [0.5, 0.5, 0.5]
n = 20.0
[[meshes]]
file = "{file}"
material = "m"
smooth = {smooth}
rotate = [10.0, 20.0, 0.0]
"#
    )
}

fn load(dir: &Path, file: &str, bytes: &[u8], smooth: bool) -> Result<Scene, SceneError> {
    std::fs::write(dir.join(file), bytes).unwrap();
    let toml = dir.join(format!("{file}.toml"));
    std::fs::write(&toml, scene_text(file, smooth)).unwrap();
    Scene::load(&toml)
}

fn image_bits(scene: &Scene) -> Vec<u32> {
    let buf = SceneBuffers::new(scene, 96, 72, scene.triangle);
    let img = glint::cpu::render_f32(&buf, Specialisation::for_scene(&buf));
    img.pixels.iter().flatten().map(|x| x.to_bits()).collect()
}

fn gz(bytes: &[u8]) -> Vec<u8> {
    use std::io::Write;
    let mut e = flate2::write::GzEncoder::new(Vec::new(), flate2::Compression::fast());
    e.write_all(bytes).unwrap();
    e.finish().unwrap()
}

/// Every PLY form of a mesh gives the OBJ's triangles, in its order, and its image in
/// every bit. The twin: one vertex moved by one ulp in the PLY changes the triangles.
#[test]
fn ply_in_every_form_is_the_obj() {
    let dir = common::Scratch::new("ply-forms");
    for (name, mesh) in [
        ("suzanne", obj_mesh("suzanne")),
        ("bunny", obj_mesh("bunny_npm")),
        ("polygons", polygon_mesh()),
    ] {
        let obj = load(
            &dir,
            &format!("{name}.obj"),
            &write_obj(&mesh, false),
            false,
        )
        .unwrap();
        let want = image_bits(&obj);
        for how in [Ply::Ascii, Ply::Little, Ply::Big, Ply::LittleOdd] {
            let file = format!("{name}-{how:?}.ply");
            let ply = load(&dir, &file, &write_ply(&mesh, how, false), false)
                .unwrap_or_else(|e| panic!("{file}: {e}"));
            assert_eq!(ply.triangles, obj.triangles, "{file}");
            assert_eq!(image_bits(&ply), want, "{file}");
        }
        let file = format!("{name}.ply.gz");
        let ply = load(
            &dir,
            &file,
            &gz(&write_ply(&mesh, Ply::Little, false)),
            false,
        )
        .unwrap();
        assert_eq!(ply.triangles, obj.triangles, "{file}");
    }
    let mut moved = polygon_mesh();
    let x: f32 = moved.text[20][0].parse().unwrap();
    moved.text[20][0] = format!("{:?}", f32::from_bits(x.to_bits() + 1));
    let obj = load(&dir, "p.obj", &write_obj(&polygon_mesh(), false), false).unwrap();
    let ply = load(
        &dir,
        "moved.ply",
        &write_ply(&moved, Ply::Little, false),
        false,
    )
    .unwrap();
    assert_ne!(ply.triangles, obj.triangles, "the twin must differ");
}

/// A smooth PLY's `nx ny nz` shade as the OBJ's `vn` do, in every bit; without them the
/// normals are computed as the OBJ's are. The twin: the file's normals are not the
/// computed ones.
#[test]
fn ply_normals_are_the_objs() {
    let dir = common::Scratch::new("ply-normals");
    let mesh = polygon_mesh();
    let obj = load(&dir, "n.obj", &write_obj(&mesh, true), true).unwrap();
    for how in [Ply::Ascii, Ply::Little, Ply::Big] {
        let ply = load(
            &dir,
            &format!("n-{how:?}.ply"),
            &write_ply(&mesh, how, true),
            true,
        )
        .unwrap();
        assert_eq!(ply.smooth, obj.smooth, "{how:?}");
        assert_eq!(image_bits(&ply), image_bits(&obj), "{how:?}");
    }
    let flat_obj = load(&dir, "c.obj", &write_obj(&mesh, false), true).unwrap();
    let flat_ply = load(&dir, "c.ply", &write_ply(&mesh, Ply::Little, false), true).unwrap();
    assert_eq!(flat_ply.smooth, flat_obj.smooth);
    assert_ne!(
        flat_ply.smooth, obj.smooth,
        "the twin: computed normals differ from the file's"
    );
}

/// The PLY error of loading `bytes`, as the scene reports it.
fn ply_error(dir: &Path, bytes: &[u8]) -> String {
    let e = load(dir, "bad.ply", bytes, true).expect_err("accepted");
    match &e {
        SceneError::Mesh {
            error, key, line, ..
        } => {
            assert_eq!((key.as_str(), *line), ("meshes[0].file", 19), "{e}");
            assert!(matches!(**error, MeshError::Ply(_)), "{e}");
        }
        other => panic!("not a mesh error: {other}"),
    }
    let text = e.to_string();
    assert!(
        text.contains("bad.ply.toml:19: meshes[0].file: mesh "),
        "{text}"
    );
    text
}

/// Bad PLY files: each error names the header line, or the element and its index; nothing
/// is allocated from a count the file cannot hold. The twin: the good file loads.
#[test]
fn bad_ply_files_name_the_element_and_index() {
    let dir = common::Scratch::new("ply-errors");
    let mesh = polygon_mesh();
    let good = write_ply(&mesh, Ply::Little, false);
    assert!(
        load(&dir, "bad.ply", &good, true).is_ok(),
        "the twin: the good file loads"
    );
    let at = |s: &str| {
        good.windows(s.len())
            .position(|w| w == s.as_bytes())
            .unwrap()
    };
    let body = at("end_header\n") + "end_header\n".len();
    let vsize = 12;
    let nv = mesh.text.len();
    let faces = body + nv * vsize;

    let cases: Vec<(Vec<u8>, &str)> = vec![
        (good[..good.len() - 3].to_vec(), "PLY element face 143: the file ends here"),
        (good[..faces + 30].to_vec(), "PLY element face 0: the header says 144 of them; the file cannot hold that many"),
        (b"ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\nelement face 0\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n1 0 0\n".to_vec(),
         "PLY element vertex 2: the file ends here"),
        (good[..body + 5 * vsize + 4].to_vec(), "PLY element vertex 0: the header says 169 of them; the file cannot hold that many"),
        ({
            let mut b = good.clone();
            b[faces + 1..faces + 5].copy_from_slice(&(nv as i32).to_le_bytes());
            b
        }, &*Box::leak(format!("PLY element face 0: vertex index {nv} is out of range (the file has {nv} vertices)").into_boxed_str())),
        ({
            let mut b = good.clone();
            b[faces] = 2;
            b
        }, "PLY element face 0: 2 vertices: a face needs at least 3"),
        (String::from_utf8_lossy(&good[..body]).replace(&format!("element vertex {nv}"), "element vertex 4000000000").into_bytes(),
         "PLY element vertex 0: the header says 4000000000 of them; the file cannot hold that many"),
        (b"ply\nformat binary_little_endian 2.0\nend_header\n".to_vec(), "PLY header line 2: format version 2.0"),
        (b"ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\nelement face 0\nproperty list uchar int vertex_indices\nend_header\n0 0\n".to_vec(),
         "PLY header line 3: the vertex element has no `z` property"),
        (b"ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n1 0 0\n0 one 0\n3 0 1 2\n".to_vec(),
         "PLY element vertex 2: \"one\" is not a F32 value"),
        (b"ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\nproperty float nx\nproperty float ny\nproperty float nz\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n0 0 0 0 0 1\n1 0 0 0 0 1\n0 1 0 nan 0 1\n3 0 1 2\n".to_vec(),
         "PLY element vertex 2: the normal [NaN, 0.0, 1.0] is not finite"),
        (b"ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\nproperty float z\nend_header\n0 0 0\n".to_vec(),
         "PLY header line 7: no `face` element"),
        (b"solid stl\n".to_vec(), "PLY header line 1: not a PLY file"),
    ];
    for (bytes, want) in cases {
        let text = ply_error(&dir, &bytes);
        assert!(text.contains(want), "{text}\n  wanted: {want}");
    }
    // Without `material =`: a PLY has no materials.
    std::fs::write(dir.join("nomat.ply"), &good).unwrap();
    let src = scene_text("nomat.ply", false).replace("material = \"m\"\n", "");
    let e = Scene::parse(&src, &dir.join("nomat.toml")).unwrap_err();
    assert!(
        e.to_string()
            .ends_with("a PLY file has no materials: name one with `material =`"),
        "{e}"
    );
}

/// Damaged PLY files (bytes changed, cut short, header words swapped) are refused with an
/// error or read, never a panic: 3000 of them, ASCII and binary.
#[test]
fn damaged_ply_files_never_panic() {
    let dir = common::Scratch::new("ply-damaged");
    let mesh = polygon_mesh();
    let mut rng = common::Rng::new(11);
    let (mut ok, mut refused) = (0, 0);
    for k in 0..3000 {
        let how = [Ply::Ascii, Ply::Little, Ply::Big, Ply::LittleOdd][k % 4];
        let mut b = write_ply(&mesh, how, k % 3 == 0);
        match rng.next_u64() % 3 {
            0 => {
                for _ in 0..1 + rng.next_u64() % 8 {
                    let i = (rng.next_u64() as usize) % b.len();
                    b[i] = rng.next_u64() as u8;
                }
            }
            1 => b.truncate((rng.next_u64() as usize) % b.len()),
            _ => {
                let i = (rng.next_u64() as usize) % 300.min(b.len());
                b[i] = b" 0123456789\nabcxyz-"[(rng.next_u64() % 19) as usize];
            }
        }
        std::fs::write(dir.join("d.ply"), &b).unwrap();
        let src = scene_text("d.ply", k % 3 == 0);
        match Scene::parse(&src, &dir.join("d.toml")) {
            Ok(_) => ok += 1,
            Err(e) => {
                assert!(e.to_string().contains("d.ply"), "{e}");
                refused += 1;
            }
        }
    }
    assert!(ok > 0 && refused > 0, "{ok} read, {refused} refused");
}
