//! glTF 2.0 meshes: a `.glb`, a `.gltf` with an external buffer and one with a `data:` URI
//! give the OBJ's triangles in every bit (indices of each width); node transforms are
//! composed; `baseColorFactor` becomes the material; what is left out is warned about;
//! a malformed file names the buffer, or the mesh and primitive.

mod common;

use std::path::Path;

use glint::scene::{MeshError, Scene, SceneError};

/// `tests/data/meshes/NAME.obj`'s positions (as f32) and triangles.
fn obj_mesh(name: &str) -> (Vec<[f32; 3]>, Vec<[u32; 3]>) {
    let text = std::fs::read_to_string(
        Path::new(env!("CARGO_MANIFEST_DIR")).join(format!("tests/data/meshes/{name}.obj")),
    )
    .unwrap();
    let (mut v, mut f) = (Vec::new(), Vec::new());
    for line in text.lines() {
        let w: Vec<&str> = line.split_whitespace().collect();
        match w.first() {
            Some(&"v") => v.push([w[1], w[2], w[3]].map(|s| s.parse::<f32>().unwrap())),
            Some(&"f") => f.push([w[1], w[2], w[3]].map(|s| s.parse::<u32>().unwrap() - 1)),
            _ => {}
        }
    }
    (v, f)
}

/// Index width of a written file.
#[derive(Clone, Copy, Debug)]
enum Width {
    U16,
    U32,
    None,
}

/// A glTF document (JSON) and its one buffer, for `v`/`f`, the node given `node_extra`
/// (e.g. a translation), `materials` (base colours) assigned to halves of the triangles.
fn document(
    v: &[[f32; 3]],
    f: &[[u32; 3]],
    width: Width,
    node_extra: &str,
    materials: &[[f32; 3]],
    uri: Option<&str>,
) -> (String, Vec<u8>) {
    let mut bin: Vec<u8> = v.iter().flatten().flat_map(|x| x.to_le_bytes()).collect();
    let pos_len = bin.len();
    let (lo, hi) = v
        .iter()
        .fold(([f32::MAX; 3], [f32::MIN; 3]), |(lo, hi), p| {
            (
                [0, 1, 2].map(|k| lo[k].min(p[k])),
                [0, 1, 2].map(|k| hi[k].max(p[k])),
            )
        });
    let halves: Vec<&[[u32; 3]]> = if materials.len() == 2 {
        let (a, b) = f.split_at(f.len() / 2);
        vec![a, b]
    } else {
        vec![f]
    };
    let mut views = vec![format!(
        r#"{{"buffer":0,"byteOffset":0,"byteLength":{pos_len}}}"#
    )];
    let mut accessors = vec![format!(
        r#"{{"bufferView":0,"componentType":5126,"count":{},"type":"VEC3","min":{lo:?},"max":{hi:?}}}"#,
        v.len()
    )];
    let mut prims = Vec::new();
    for (k, part) in halves.iter().enumerate() {
        let material = if materials.is_empty() {
            String::new()
        } else {
            format!(r#","material":{k}"#)
        };
        match width {
            Width::None => {
                assert_eq!(halves.len(), 1);
                // No indices: the triangles' corners as their own vertices.
                prims.push(format!(r#"{{"attributes":{{"POSITION":0}}{material}}}"#));
            }
            _ => {
                while !bin.len().is_multiple_of(4) {
                    bin.push(0);
                }
                let start = bin.len();
                for &i in part.iter().flatten() {
                    match width {
                        Width::U16 => bin.extend((i as u16).to_le_bytes()),
                        _ => bin.extend(i.to_le_bytes()),
                    }
                }
                let ct = if matches!(width, Width::U16) {
                    5123
                } else {
                    5125
                };
                views.push(format!(
                    r#"{{"buffer":0,"byteOffset":{start},"byteLength":{}}}"#,
                    bin.len() - start
                ));
                accessors.push(format!(
                    r#"{{"bufferView":{},"componentType":{ct},"count":{},"type":"SCALAR"}}"#,
                    views.len() - 1,
                    part.len() * 3
                ));
                prims.push(format!(
                    r#"{{"attributes":{{"POSITION":0}},"indices":{}{material}}}"#,
                    accessors.len() - 1
                ));
            }
        }
    }
    while !bin.len().is_multiple_of(4) {
        bin.push(0);
    }
    let mats: Vec<String> = materials
        .iter()
        .enumerate()
        .map(|(k, c)| format!(r#"{{"name":"m{k}","pbrMetallicRoughness":{{"baseColorFactor":[{:?},{:?},{:?},1.0]}}}}"#, c[0], c[1], c[2]))
        .collect();
    let buffer = match uri {
        Some(u) => format!(r#"{{"byteLength":{},"uri":"{u}"}}"#, bin.len()),
        None => format!(r#"{{"byteLength":{}}}"#, bin.len()),
    };
    let json = format!(
        r#"{{"asset":{{"version":"2.0"}},"scene":0,"scenes":[{{"nodes":[0]}}],"nodes":[{{"name":"root","children":[1]}},{{"mesh":0{node_extra}}}],"meshes":[{{"primitives":[{}]}}],"materials":[{}],"buffers":[{buffer}],"bufferViews":[{}],"accessors":[{}]}}"#,
        prims.join(","),
        mats.join(","),
        views.join(","),
        accessors.join(",")
    );
    (json, bin)
}

fn scene(dir: &Path, file: &str, material: bool) -> Result<Scene, SceneError> {
    let src = format!(
        r#"ambient = [0.2, 0.2, 0.2]
[camera]
eye = [0.0, 0.0, 4.0]
look_at = [0.0, 0.0, 0.0]
fov = 45.0
width = 64
height = 48
[[lights]]
position = [2.0, 3.0, 4.0]
color = [1.0, 1.0, 1.0]
[materials.m]
model = "diffuse"
ka = [0.3, 0.2, 0.1]
kd = [0.6, 0.5, 0.4]
[[meshes]]
file = "{file}"
{}"#,
        if material { "material = \"m\"" } else { "" }
    );
    let toml = dir.join(format!("{file}.toml"));
    std::fs::write(&toml, src).unwrap();
    Scene::load(&toml)
}

fn b64(bytes: &[u8]) -> String {
    use base64::Engine as _;
    base64::engine::general_purpose::STANDARD.encode(bytes)
}

/// A `.glb` (16- and 32-bit indices), a `.gltf` with an external `.bin` and one with a
/// `data:` URI give the OBJ's triangles in every bit. The twin: a file with one index
/// changed gives other triangles.
#[test]
fn gltf_in_every_form_is_the_obj() {
    let dir = common::Scratch::new("gltf-forms");
    let (v, f) = obj_mesh("suzanne");
    std::fs::copy(
        Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/meshes/suzanne.obj"),
        dir.join("s.obj"),
    )
    .unwrap();
    let obj = scene(&dir, "s.obj", true).unwrap();
    for width in [Width::U16, Width::U32] {
        let (json, bin) = document(&v, &f, width, "", &[], None);
        std::fs::write(dir.join("s.glb"), common::glb(&json, &bin)).unwrap();
        let g = scene(&dir, "s.glb", true).unwrap();
        assert_eq!(g.triangles, obj.triangles, "{width:?}");
    }
    let (json, bin) = document(&v, &f, Width::U32, "", &[], Some("s.bin"));
    std::fs::write(dir.join("s.bin"), &bin).unwrap();
    std::fs::write(dir.join("s.gltf"), &json).unwrap();
    assert_eq!(
        scene(&dir, "s.gltf", true).unwrap().triangles,
        obj.triangles
    );
    let (json, bin) = document(&v, &f, Width::U16, "", &[], None);
    let json = json.replacen(
        r#""buffers":[{"byteLength""#,
        &format!(
            r#""buffers":[{{"uri":"data:application/octet-stream;base64,{}","byteLength""#,
            b64(&bin)
        ),
        1,
    );
    std::fs::write(dir.join("d.gltf"), &json).unwrap();
    assert_eq!(
        scene(&dir, "d.gltf", true).unwrap().triangles,
        obj.triangles
    );
    // No indices: corners in vertex order.
    let corners: Vec<[f32; 3]> = f.iter().flatten().map(|&k| v[k as usize]).collect();
    let (json, bin) = document(&corners, &[], Width::None, "", &[], None);
    std::fs::write(dir.join("n.glb"), common::glb(&json, &bin)).unwrap();
    assert_eq!(scene(&dir, "n.glb", true).unwrap().triangles, obj.triangles);
    // The twin.
    let mut g = f.clone();
    g[7][1] = g[7][2];
    let (json, bin) = document(&v, &g, Width::U32, "", &[], None);
    std::fs::write(dir.join("t.glb"), common::glb(&json, &bin)).unwrap();
    assert_ne!(scene(&dir, "t.glb", true).unwrap().triangles, obj.triangles);
}

/// A node's transform applies (in f64, rounded once), its parent's too; without a scene
/// material the file's base colours are the materials, ka = kd = the colour.
#[test]
fn gltf_transforms_and_materials() {
    let dir = common::Scratch::new("gltf-xf");
    let (v, f) = obj_mesh("suzanne");
    let colours = [[0.8, 0.1, 0.1], [0.1, 0.2, 0.9]];
    let (json, bin) = document(
        &v,
        &f,
        Width::U32,
        r#","translation":[0.5,-0.25,1.0],"scale":[2.0,2.0,2.0]"#,
        &colours,
        None,
    );
    std::fs::write(dir.join("x.glb"), common::glb(&json, &bin)).unwrap();
    let s = scene(&dir, "x.glb", false).unwrap();
    let t = &s.triangles[0];
    let want = f[0].map(|k| {
        let p = v[k as usize];
        [
            p[0] as f64 * 2.0 + 0.5,
            p[1] as f64 * 2.0 - 0.25,
            p[2] as f64 * 2.0 + 1.0,
        ]
        .map(|x| x as f32)
    });
    assert_eq!(t.vertices, want);
    let named: Vec<_> = s
        .materials
        .iter()
        .filter(|m| m.name.starts_with("x.glb#"))
        .collect();
    assert_eq!(named.len(), 3, "two of the file's and the default");
    assert_eq!((named[0].ka, named[0].kd), (colours[0], colours[0]));
    assert_eq!(named[0].name, "x.glb#0:m0");
    let first = s
        .materials
        .iter()
        .position(|m| m.name == "x.glb#0:m0")
        .unwrap() as u32;
    assert_eq!(s.triangles[0].material, first);
    assert_eq!(s.triangles[f.len() - 1].material, first + 1);
    // A base colour the scene's colour check refuses, when the scene takes the file's
    // materials.
    let (json, bin) = document(
        &v,
        &f,
        Width::U32,
        "",
        &[[-0.5, 0.0, 0.0], colours[1]],
        None,
    );
    std::fs::write(dir.join("neg.glb"), common::glb(&json, &bin)).unwrap();
    let e = scene(&dir, "neg.glb", false).unwrap_err().to_string();
    assert!(
        e.contains(
            "glTF material 0 (\"m0\"): baseColorFactor [-0.5, 0.0, 0.0] has a negative component"
        ),
        "{e}"
    );
    // With `material =` every triangle is the scene's.
    let s = scene(&dir, "x.glb", true).unwrap();
    assert!(
        s.triangles
            .iter()
            .all(|t| s.materials[t.material as usize].name == "m")
    );
}

fn gltf_error(dir: &Path, file: &str, bytes: &[u8]) -> String {
    std::fs::write(dir.join(file), bytes).unwrap();
    let e = scene(dir, file, true).expect_err("accepted");
    match &e {
        SceneError::Mesh { error, .. } => assert!(matches!(**error, MeshError::Gltf(_)), "{e}"),
        other => panic!("not a mesh error: {other}"),
    }
    e.to_string()
}

/// What is left out is warned about; malformed files name the buffer, or the mesh and
/// primitive. The twin: the good file loads without a warning.
#[test]
fn gltf_warnings_and_errors() {
    let dir = common::Scratch::new("gltf-errors");
    let (v, f) = obj_mesh("suzanne");
    let (json, bin) = document(&v, &f, Width::U32, "", &[], None);
    std::fs::write(dir.join("ok.glb"), common::glb(&json, &bin)).unwrap();
    assert!(scene(&dir, "ok.glb", true).unwrap().warnings.is_empty());
    // A LINES primitive beside the triangles.
    let lines = json.replacen(
        r#""primitives":["#,
        r#""primitives":[{"attributes":{"POSITION":0},"mode":1},"#,
        1,
    );
    std::fs::write(dir.join("l.glb"), common::glb(&lines, &bin)).unwrap();
    let s = scene(&dir, "l.glb", true).unwrap();
    assert!(
        s.warnings
            .iter()
            .any(|w| w.contains("1 primitive(s) not of mode TRIANGLES")),
        "{:?}",
        s.warnings
    );
    // An index past the vertices.
    let mut bad = f.clone();
    bad[3][2] = v.len() as u32 + 5;
    let (j, b) = document(&v, &bad, Width::U32, "", &[], None);
    let e = gltf_error(&dir, "i.glb", &common::glb(&j, &b));
    assert!(
        e.contains(&format!(
            "glTF mesh 0 primitive 0: index {} is out of range (the primitive has {} vertices)",
            v.len() + 5,
            v.len()
        )),
        "{e}"
    );
    // A missing external buffer.
    let (j, _) = document(&v, &f, Width::U32, "", &[], Some("gone.bin"));
    let e = gltf_error(&dir, "g.gltf", j.as_bytes());
    assert!(e.contains("glTF buffer 0 (gone.bin): cannot read"), "{e}");
    // A buffer shorter than it says.
    std::fs::write(dir.join("short.bin"), &bin[..bin.len() - 8]).unwrap();
    let (j, _) = document(&v, &f, Width::U32, "", &[], Some("short.bin"));
    let e = gltf_error(&dir, "s.gltf", j.as_bytes());
    assert!(
        e.contains(&format!(
            "glTF buffer 0: holds {} bytes where it says {}",
            bin.len() - 8,
            bin.len()
        )),
        "{e}"
    );
    // Not JSON at all.
    let e = gltf_error(&dir, "j.gltf", b"{ not json");
    assert!(e.contains("glTF: "), "{e}");
}

/// A node graph that is not a forest is refused at once, naming the node: a node that is
/// its own child, a longer cycle, a child of two parents, a root listed twice. The twin is
/// the document's own tree (root → mesh node), which loads.
#[test]
fn gltf_node_cycles_are_errors_not_hangs() {
    let dir = common::Scratch::new("gltf-cycles");
    let (v, f) = obj_mesh("suzanne");
    let (json, bin) = document(&v, &f, Width::U32, "", &[], None);
    let tree = r#""nodes":[{"name":"root","children":[1]},{"mesh":0"#;
    assert!(json.contains(tree), "{json}");
    std::fs::write(dir.join("tree.glb"), common::glb(&json, &bin)).unwrap();
    assert!(scene(&dir, "tree.glb", true).is_ok());
    let cases = [
        // Node 0 its own child.
        (
            r#""nodes":[{"name":"root","children":[0,1]},{"mesh":0"#,
            "",
            0,
        ),
        // 0 → 1 → 0.
        (
            r#""nodes":[{"name":"root","children":[1]},{"children":[0],"mesh":0"#,
            "",
            0,
        ),
        // Node 1 the child of 0 and of 2.
        (
            r#""nodes":[{"name":"root","children":[1]},{"mesh":0"#,
            r#"{"children":[1]}"#,
            1,
        ),
        // A root listed twice.
        (tree, "", 0),
    ];
    for (k, (nodes, extra, index)) in cases.into_iter().enumerate() {
        let mut j = json.replacen(tree, nodes, 1);
        if !extra.is_empty() {
            // A third node, also a root.
            j = j.replacen(
                r#""scenes":[{"nodes":[0]}]"#,
                r#""scenes":[{"nodes":[0,2]}]"#,
                1,
            );
            let end = j.find(r#""meshes""#).unwrap();
            let close = j[..end].rfind(']').unwrap();
            j.insert_str(close, &format!(",{extra}"));
        }
        if k == 3 {
            j = j.replacen(
                r#""scenes":[{"nodes":[0]}]"#,
                r#""scenes":[{"nodes":[0,0]}]"#,
                1,
            );
        }
        let start = std::time::Instant::now();
        let e = gltf_error(&dir, &format!("c{k}.glb"), &common::glb(&j, &bin));
        assert!(
            e.contains(&format!("glTF node {index}: is reached twice")),
            "case {k}: {e}\n{j}"
        );
        assert!(
            start.elapsed().as_secs() < 10,
            "case {k} took {:?}",
            start.elapsed()
        );
    }
}

/// A smooth glTF's NORMALs shade as the OBJ's `vn` do, in every bit (identity transform).
/// The twin: without NORMALs the computed normals differ.
#[test]
fn gltf_normals_are_the_objs() {
    let dir = common::Scratch::new("gltf-normals");
    let (v, f) = obj_mesh("suzanne");
    let normals: Vec<[f32; 3]> = v
        .iter()
        .map(|p| {
            let l = (p[0] * p[0] + p[1] * p[1] + p[2] * p[2]).sqrt();
            [p[0] / l, p[1] / l, p[2] / l]
        })
        .collect();
    let mut obj = String::new();
    for p in &v {
        obj += &format!("v {:?} {:?} {:?}\n", p[0], p[1], p[2]);
    }
    for n in &normals {
        obj += &format!("vn {:?} {:?} {:?}\n", n[0], n[1], n[2]);
    }
    for t in &f {
        let [a, b, c] = t.map(|k| k + 1);
        obj += &format!("f {a}//{a} {b}//{b} {c}//{c}\n");
    }
    std::fs::write(dir.join("n.obj"), obj).unwrap();
    let smooth = |file: &str| {
        let toml = dir.join(format!("{file}.toml"));
        let src = std::fs::read_to_string(dir.join("base.toml"))
            .unwrap()
            .replace("FILE", file);
        std::fs::write(&toml, src).unwrap();
        Scene::load(&toml).unwrap()
    };
    std::fs::write(
        dir.join("base.toml"),
        "[camera]\neye = [0.0, 0.0, 4.0]\nlook_at = [0.0, 0.0, 0.0]\nfov = 45.0\nwidth = 8\nheight = 8\n[materials.m]\nmodel = \"ambient\"\nka = [1.0, 1.0, 1.0]\n[[meshes]]\nfile = \"FILE\"\nmaterial = \"m\"\nsmooth = true\n",
    )
    .unwrap();
    let want = smooth("n.obj");
    let (json, mut bin) = document(&v, &f, Width::U32, "", &[], None);
    let nstart = bin.len();
    bin.extend(normals.iter().flatten().flat_map(|x| x.to_le_bytes()));
    let json = json
        .replacen(
            r#""attributes":{"POSITION":0}"#,
            &format!(r#""attributes":{{"POSITION":0,"NORMAL":{}}}"#, 2),
            1,
        )
        .replace(
            r#""bufferViews":["#,
            &format!(
                r#""bufferViews":[{{"buffer":0,"byteOffset":{nstart},"byteLength":{}}},"#,
                normals.len() * 12
            ),
        );
    // The new view is first: shift the others' indices by one.
    let json = json
        .replace(r#""bufferView":1,"#, r#""bufferView":2,"#)
        .replace(r#""bufferView":0,"#, r#""bufferView":1,"#)
        .replace(
            r#""type":"SCALAR"}]"#,
            &format!(r#""type":"SCALAR"}},{{"bufferView":0,"componentType":5126,"count":{},"type":"VEC3"}}]"#, normals.len()),
        )
        .replace(&format!(r#""byteLength":{nstart}}}]"#), &format!(r#""byteLength":{}}}]"#, bin.len()));
    std::fs::write(dir.join("n.glb"), common::glb(&json, &bin)).unwrap();
    let got = smooth("n.glb");
    assert_eq!(got.triangles, want.triangles);
    assert_eq!(got.smooth, want.smooth);
    let (json, bin) = document(&v, &f, Width::U32, "", &[], None);
    std::fs::write(dir.join("c.glb"), common::glb(&json, &bin)).unwrap();
    assert_ne!(
        smooth("c.glb").smooth,
        want.smooth,
        "the twin: computed normals differ"
    );
}

/// A GLB whose lengths lie (a JSON chunk longer than the file, a total length beyond it, a
/// binary chunk that claims 2 GiB) is refused at once with the file named, never read past
/// its end. The twin: the honest GLB loads.
#[test]
fn glb_chunk_lengths_that_lie_are_refused() {
    let dir = common::Scratch::new("gltf-glb-lies");
    let (v, f) = obj_mesh("suzanne");
    let (json, bin) = document(&v, &f, Width::U32, "", &[], None);
    let good = common::glb(&json, &bin);
    std::fs::write(dir.join("ok.glb"), &good).unwrap();
    assert!(scene(&dir, "ok.glb", true).is_ok());
    let json_len = u32::from_le_bytes(good[12..16].try_into().unwrap()) as usize;
    let put = |at: usize, value: u32| {
        let mut g = good.clone();
        g[at..at + 4].copy_from_slice(&value.to_le_bytes());
        g
    };
    let cases = [
        ("json.glb", put(12, 0x7fff_fff0)),
        ("total.glb", put(8, good.len() as u32 + 4096)),
        ("bin.glb", put(20 + json_len, 0x8000_0000)),
        ("cut.glb", good[..good.len() / 2].to_vec()),
    ];
    for (name, bytes) in cases {
        let start = std::time::Instant::now();
        let e = gltf_error(&dir, name, &bytes);
        assert!(e.contains(name), "{name}: {e}");
        assert!(
            start.elapsed().as_secs() < 5,
            "{name}: {:?}",
            start.elapsed()
        );
    }
}
