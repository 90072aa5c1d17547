use super::{FaceError, MeshError, Normals, Transform, gunzip_parse};
use crate::scene::{ObjError, ReadError, Scene, SceneError, obj};
use crate::stages::Stages;
use std::path::Path;

/// A scene of one mesh `m.obj` (scaled by `scale` in x), read through `read`.
fn one_mesh(scale: &str, read: &crate::scene::ReadFile<'_>) -> Result<Scene, SceneError> {
    let src = format!(
        "[camera]\neye = [0.0, 0.0, 5.0]\nlook_at = [0.0, 0.0, 0.0]\nfov = 45.0\n\
         width = 4\nheight = 4\n[materials.m]\nmodel = \"ambient\"\nka = [1.0, 1.0, 1.0]\n\
         [[meshes]]\nfile = \"m.obj\"\nmaterial = \"m\"\nscale = [{scale}, 1.0, 1.0]\n"
    );
    Scene::parse_with(&src, Path::new("s.toml"), read)
}

/// `one_mesh` with `obj` as the mesh's text.
fn with_obj(scale: &str, obj: &str) -> Result<Scene, SceneError> {
    one_mesh(scale, &|_: &Path| Ok(obj.as_bytes().to_vec()))
}

/// The mesh error inside a scene error, which must name the entry's line and key.
fn mesh_error(e: &SceneError) -> &MeshError {
    match e {
        SceneError::Mesh {
            line, key, error, ..
        } => {
            assert_eq!((*line, key.as_str()), (11, "meshes[0].file"), "{e}");
            error
        }
        _ => panic!("not a mesh error: {e}"),
    }
}

#[test]
fn mesh_errors_are_typed_and_print_file_line_key_and_the_meshs_line() {
    let tri = "v 0 0 0\nv 1 0 0\nv 0 1 0\n";
    let e = with_obj("1.0", &format!("{tri}f 1 2 9\n")).unwrap_err();
    assert!(matches!(
        mesh_error(&e),
        MeshError::Obj(ObjError::VertexIndex {
            line: 4,
            index: 9,
            defined: 3
        })
    ));
    assert_eq!(
        e.to_string(),
        "s.toml:11: meshes[0].file: mesh m.obj: line 4: face vertex index 9 is out of range (3 vertices defined before it)"
    );
    let e = with_obj("1e30", &format!("v 1e10 0 0\n{tri}f 1 2 3\nf 2 3 4\n")).unwrap_err();
    assert!(matches!(
        mesh_error(&e),
        MeshError::Face {
            face: 0,
            why: FaceError::Overflow
        }
    ));
    assert!(
        e.to_string()
            .ends_with("mesh m.obj: face 0: the transform overflows f32")
    );
    let e = one_mesh("1.0", &|_: &Path| Err(ReadError::Other("gone".into()))).unwrap_err();
    assert!(matches!(
        mesh_error(&e),
        MeshError::Read(ReadError::Other(_))
    ));
    assert_eq!(e.to_string(), "s.toml:11: meshes[0].file: mesh m.obj: gone");
    let e = with_obj("1.0", "# nothing\n").unwrap_err();
    assert!(matches!(mesh_error(&e), MeshError::Empty));
    // The twins: the same mesh with its faces in range, and a scale that keeps f32,
    // loads.
    let ok = with_obj("1e30", &format!("{tri}f 1 2 3\n")).unwrap();
    assert_eq!(ok.triangles.len(), 1);
    assert!(with_obj("1e20", &format!("v 1e10 0 0\n{tri}f 1 2 3\n")).is_ok());
}

fn gz(bytes: &[u8]) -> Vec<u8> {
    use std::io::Write;
    let mut e = flate2::write::GzEncoder::new(Vec::new(), flate2::Compression::fast());
    e.write_all(bytes).unwrap();
    e.finish().unwrap()
}

/// `obj::parse`'s result (or error) as text, to compare whole results.
fn shown(r: &Result<Option<obj::Parsed>, obj::ObjError>) -> String {
    format!("{r:?}")
}

/// An OBJ with comments, groups, polygons, negative indices, normals, CRLF line ends,
/// a long line and a short face.
fn sample() -> String {
    let mut s = String::from("# a comment\r\no thing\r\n");
    for k in 0..3000 {
        s += &format!("v {k} 0.5 -1e-3\nv {k} 1 0\r\nv {k} 0 1\nvn 0 0 1\n");
        s += &format!(
            "f -3//1 -2//1 -1//1\ng g{k}\nf {} {} {} {}\n",
            1,
            2,
            3,
            3 * k + 3
        );
    }
    s += &format!("# {}\nf 1 2\nf 1 2 3", "x".repeat(5000));
    s
}

#[test]
fn parsing_while_inflating_gives_what_parsing_the_whole_text_gives() {
    let text = sample();
    let gzipped = gz(text.as_bytes());
    for normals in [Normals::Skip, Normals::Read] {
        let whole = obj::parse(&text, normals);
        assert!(matches!(whole, Ok(Some(_))), "{}", shown(&whole));
        for piece in [1, 7, 100, 4096, 1 << 20] {
            let (bytes, parsed) =
                gunzip_parse(&gzipped, normals, piece, 1 << 30, &Stages::new()).expect("streamed");
            assert_eq!(bytes, text.as_bytes(), "piece {piece}");
            assert_eq!(shown(&parsed), shown(&whole), "piece {piece}");
        }
    }
    // The twin: the same two pieces joined in the wrong order give another result, and
    // the comparison sees it.
    let cut = text[..text.len() / 2].rfind('\n').unwrap() + 1;
    let (a, b) = text.split_at(cut);
    let piece = |t| obj::parse_piece(t, Normals::Skip);
    let swapped = obj::join_pieces(vec![piece(b), piece(a)], Normals::Skip);
    assert_ne!(shown(&swapped), shown(&obj::parse(&text, Normals::Skip)));
}

#[test]
fn errors_and_tobj_files_come_out_as_from_the_whole_text() {
    let bad = sample() + "\nv 1 2\nf 1 2 3\n";
    let needs_tobj = sample() + "\nusemtl red\nf 1 2 3\n";
    for text in [bad, needs_tobj] {
        let whole = obj::parse(&text, Normals::Skip);
        assert!(!matches!(whole, Ok(Some(_))));
        for piece in [1, 100, 1 << 20] {
            let (_, parsed) = gunzip_parse(
                &gz(text.as_bytes()),
                Normals::Skip,
                piece,
                1 << 30,
                &Stages::new(),
            )
            .unwrap();
            assert_eq!(shown(&parsed), shown(&whole), "piece {piece}");
        }
    }
}

#[test]
fn what_it_cannot_stream_is_left_to_the_ordinary_path() {
    let text = sample();
    let good = gz(text.as_bytes());
    // A trailer that lies about the size, either way.
    for delta in [1u32, u32::MAX] {
        let mut lying = good.clone();
        let n = lying.len();
        let size = u32::from_le_bytes(lying[n - 4..].try_into().unwrap());
        lying[n - 4..].copy_from_slice(&size.wrapping_add(delta).to_le_bytes());
        assert!(
            gunzip_parse(&lying, Normals::Skip, 100, 1 << 30, &Stages::new()).is_none(),
            "{delta}"
        );
    }
    // Two members (the first's size alone in the last trailer), a damaged stream, a
    // byte-order mark, bytes that are not UTF-8, an empty file, a short one.
    let two = [gz(text.as_bytes()), gz(b"v 1 2 3\n")].concat();
    let mut damaged = good.clone();
    damaged[good.len() / 2] ^= 0x55;
    let bom = gz(&[b"\xEF\xBB\xBF".as_slice(), text.as_bytes()].concat());
    let latin1 = gz(&[text.as_bytes(), b"\n# caf\xE9\n"].concat());
    for (what, raw) in [
        ("two members", two),
        ("damaged", damaged),
        ("bom", bom),
        ("latin-1", latin1),
        ("empty", gz(b"")),
        ("short", vec![0x1f, 0x8b]),
    ] {
        assert!(
            gunzip_parse(&raw, Normals::Skip, 100, 1 << 30, &Stages::new()).is_none(),
            "{what}"
        );
    }
}

/// The transform as it was written out by hand before glam: rows of Rz·Ry·Rx summed
/// left to right. glam's must give the same f32 vertices, bit for bit.
fn by_hand(scale: [f32; 3], rot: [f32; 3], tr: [f32; 3], p: [f32; 3]) -> [f32; 3] {
    let [ax, ay, az] = rot.map(|d| (d as f64).to_radians());
    let (sx, cx) = ax.sin_cos();
    let (sy, cy) = ay.sin_cos();
    let (sz, cz) = az.sin_cos();
    let rx = [[1.0, 0.0, 0.0], [0.0, cx, -sx], [0.0, sx, cx]];
    let ry = [[cy, 0.0, sy], [0.0, 1.0, 0.0], [-sy, 0.0, cy]];
    let rz = [[cz, -sz, 0.0], [sz, cz, 0.0], [0.0, 0.0, 1.0]];
    let mul = |a: [[f64; 3]; 3], b: [[f64; 3]; 3]| {
        let mut m = [[0.0; 3]; 3];
        for (i, row) in m.iter_mut().enumerate() {
            for (j, x) in row.iter_mut().enumerate() {
                *x = a[i][0] * b[0][j] + a[i][1] * b[1][j] + a[i][2] * b[2][j];
            }
        }
        m
    };
    let r = mul(rz, mul(ry, rx));
    let s = [0, 1, 2].map(|k| p[k] as f64 * scale[k] as f64);
    [0, 1, 2].map(|i| (r[i][0] * s[0] + r[i][1] * s[1] + r[i][2] * s[2] + tr[i] as f64) as f32)
}

#[test]
fn glam_transform_equals_the_written_out_one() {
    let mut x = 7u64;
    let mut r = |lo: f32, hi: f32| {
        x = x
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        lo + (hi - lo) * ((x >> 40) as f32 / (1u64 << 24) as f32)
    };
    for _ in 0..10_000 {
        let scale = [r(-3.0, 3.0), r(-3.0, 3.0), r(-3.0, 3.0)];
        let rot = [r(-360.0, 360.0), r(-360.0, 360.0), r(-360.0, 360.0)];
        let tr = [r(-100.0, 100.0), r(-100.0, 100.0), r(-100.0, 100.0)];
        let p = [r(-50.0, 50.0), r(-50.0, 50.0), r(-50.0, 50.0)];
        let xf = Transform::new(scale, rot, tr);
        let (a, b) = (xf.apply(p), by_hand(scale, rot, tr, p));
        assert_eq!(
            a.map(f32::to_bits),
            b.map(f32::to_bits),
            "{scale:?} {rot:?} {tr:?} {p:?}"
        );
    }
}
