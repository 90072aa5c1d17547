//! Bad scene input: each case gives an error naming the file, the line and the key, never
//! a panic.

mod common;

use glint::scene::{Scene, SceneError};

const GOOD: &str = r#"ambient = [0.2, 0.2, 0.2]
[camera]
eye = [0.0, 0.0, 5.0]
look_at = [0.0, 0.0, 0.0]
up = [0.0, 1.0, 0.0]
fov = 45.0
width = 64
height = 48
[[lights]]
position = [1.0, 1.0, 1.0]
color = [1.0, 1.0, 1.0]
[materials.red]
model = "phong"
ka = [1.0, 0.0, 0.0]
kd = [1.0, 0.0, 0.0]
ks = [1.0, 1.0, 1.0]
n = 28.0
[[spheres]]
center = [0.0, 0.0, 0.0]
radius = 1.0
material = "red"
[[triangles]]
vertices = [[-1.0, -1.0, 0.0], [1.0, -1.0, 0.0], [0.0, 1.0, 0.0]]
material = "red"
"#;

/// Parses GOOD with `from` replaced by `to`, expecting an error at `line` naming `key`.
fn bad(from: &str, to: &str, line: usize, key: &str) -> SceneError {
    assert!(GOOD.contains(from), "{from:?} not in the scene");
    let src = GOOD.replacen(from, to, 1);
    let e = Scene::parse(&src, "bad.toml".as_ref()).expect_err(&format!("{to:?} was accepted"));
    let text = e.to_string();
    assert!(text.starts_with("bad.toml:"), "{text}");
    assert_eq!(e.line(), Some(line), "{text}");
    assert!(
        e.key().is_some_and(|k| k.contains(key)),
        "key {key:?} not in {text}"
    );
    e
}

#[test]
fn the_good_scene_parses() {
    let s = Scene::parse(GOOD, "good.toml".as_ref()).unwrap();
    assert_eq!(
        (s.spheres.len(), s.triangles.len(), s.materials.len()),
        (1, 1, 1)
    );
}

#[test]
fn malformed_unknown_and_missing() {
    // Each key by its whole path, the table's included.
    bad("fov = 45.0", "fov = 45.0.0", 6, "camera.fov");
    bad("fov = 45.0", "fov = 45.0\nzoom = 2", 7, "camera.zoom");
    bad("radius = 1.0\n", "", 18, "spheres[0].radius"); // the [[spheres]] table that lacks it
    bad("fov = 45.0", "fov = \"wide\"", 6, "camera.fov");
    // A table that does not exist is named alone.
    bad("[camera]", "[camra]", 2, "camra");
}

#[test]
fn out_of_domain_values() {
    bad("radius = 1.0", "radius = nan", 20, "spheres[0].radius");
    bad("radius = 1.0", "radius = -1.0", 20, "spheres[0].radius");
    bad("radius = 1.0", "radius = 0.0", 20, "spheres[0].radius");
    bad(
        "center = [0.0, 0.0, 0.0]",
        "center = [inf, 0.0, 0.0]",
        19,
        "spheres[0].center",
    );
    bad("n = 28.0", "n = -2.0", 17, "materials.red.n");
    bad(
        "material = \"red\"",
        "material = \"blue\"",
        21,
        "spheres[0].material",
    );
    bad(
        "model = \"phong\"",
        "model = \"pbr\"",
        13,
        "materials.red.model",
    );
    bad("width = 64", "width = 0", 7, "camera.width");
    bad("width = 64", "width = 100000000", 7, "camera.width");
    bad("fov = 45.0", "fov = 180.0", 6, "camera.fov");
    bad(
        "look_at = [0.0, 0.0, 0.0]",
        "look_at = [0.0, 0.0, 5.0]",
        4,
        "camera.look_at",
    );
    bad(
        "up = [0.0, 1.0, 0.0]",
        "up = [0.0, 0.0, 2.0]",
        5,
        "camera.up",
    );
    bad(
        "color = [1.0, 1.0, 1.0]",
        "color = [1.0, -1.0, 1.0]",
        11,
        "lights[0].color",
    );
    bad(
        "vertices = [[-1.0, -1.0, 0.0]",
        "vertices = [[nan, -1.0, 0.0]",
        23,
        "triangles[0].vertices",
    );
}

#[test]
fn zero_area_triangle_is_a_warning() {
    let src = GOOD.replace("[0.0, 1.0, 0.0]]", "[2.0, -1.0, 0.0]]");
    let s = Scene::parse(&src, "w.toml".as_ref()).unwrap();
    assert!(
        s.warnings
            .iter()
            .any(|w| w.contains("w.toml:23") && w.contains("zero area")),
        "{:?}",
        s.warnings
    );
}

#[test]
fn missing_file_and_non_utf8() {
    let e = Scene::load("/nonexistent/scene.toml").unwrap_err();
    assert!(e.to_string().contains("/nonexistent/scene.toml"));
    let dir = common::Scratch::new("errors");
    let p = dir.join("latin1.toml");
    std::fs::write(&p, b"ambient = [0.2, 0.2, 0.2]\n# caf\xe9\n").unwrap();
    let e = Scene::load(&p).unwrap_err();
    assert_eq!(e.line(), Some(2), "{e}");
    let m = dir.join("mesh.toml");
    std::fs::write(
        &m,
        GOOD.to_string() + "[[meshes]]\nfile = \"missing.obj\"\nmaterial = \"red\"\n",
    )
    .unwrap();
    let e = Scene::load(&m).unwrap_err();
    assert!(
        e.to_string().contains("missing.obj") && e.line() == Some(26),
        "{e}"
    );
    std::fs::write(dir.join("bad.obj"), "v 0 0 0\nv 1 0 0\nf 1 2 9\n").unwrap();
    std::fs::write(
        &m,
        GOOD.to_string() + "[[meshes]]\nfile = \"bad.obj\"\nmaterial = \"red\"\n",
    )
    .unwrap();
    let e = Scene::load(&m).unwrap_err();
    assert!(e.to_string().contains("bad.obj"), "{e}");
    std::fs::write(dir.join("empty.obj"), "# nothing\n").unwrap();
    std::fs::write(
        &m,
        GOOD.to_string() + "[[meshes]]\nfile = \"empty.obj\"\nmaterial = \"red\"\n",
    )
    .unwrap();
    let e = Scene::load(&m).unwrap_err();
    assert!(e.to_string().contains("empty"), "{e}");
}

/// The message of `e` after its `file:line: ` or `file: ` prefix: the key and the message.
fn key_and_message(e: &SceneError) -> String {
    let text = e.to_string();
    let key = e.key().expect("a key");
    text[text
        .find(&format!(" {key}: "))
        .expect("the key in the message")
        + 1..]
        .to_string()
}

/// `Scene::validate` checks a scene edited in memory as loading checks a file: for each
/// bad value, the in-memory edit and the file with that value give the same key and the
/// same message (the file's with its line, the edit's without). The twin: the good scene
/// validates, and two different faults' messages differ.
#[test]
fn validate_gives_the_files_errors_for_edits_in_memory() {
    type Edit = fn(&mut Scene);
    let cases: [(&str, &str, Edit); 10] = [
        (
            "look_at = [0.0, 0.0, 0.0]",
            "look_at = [0.0, 0.0, 5.0]",
            |s| s.camera.look_at = s.camera.eye,
        ),
        ("up = [0.0, 1.0, 0.0]", "up = [0.0, 0.0, 1.0]", |s| {
            s.camera.up = [0.0, 0.0, 1.0]
        }),
        ("fov = 45.0", "fov = 180.0", |s| s.camera.fov = 180.0),
        ("width = 64", "width = 0", |s| s.camera.width = 0),
        ("radius = 1.0", "radius = -2.0", |s| {
            s.spheres[0].radius = -2.0
        }),
        ("n = 28.0", "n = -1.0", |s| s.materials[0].n = -1.0),
        ("ka = [1.0, 0.0, 0.0]", "ka = [1.0, -0.5, 0.0]", |s| {
            s.materials[0].ka = [1.0, -0.5, 0.0]
        }),
        ("color = [1.0, 1.0, 1.0]", "color = [1.0, 2e7, 1.0]", |s| {
            s.lights[0].color = [1.0, 2e7, 1.0]
        }),
        (
            "ambient = [0.2, 0.2, 0.2]",
            "ambient = [0.2, 0.2, 0.2]\nmax_depth = 17",
            |s| s.max_depth = 17,
        ),
        (
            "ambient = [0.2, 0.2, 0.2]",
            "ambient = [0.2, 0.2, 0.2]\nmin_weight = -1.0",
            |s| s.min_weight = -1.0,
        ),
    ];
    let good = Scene::parse(GOOD, "mem.toml".as_ref()).unwrap();
    good.validate().expect("the good scene validates");
    let mut messages = Vec::new();
    for (from, to, edit) in cases {
        let file_error = Scene::parse(&GOOD.replacen(from, to, 1), "mem.toml".as_ref())
            .expect_err(&format!("{to:?} was accepted"));
        let mut s = good.clone();
        edit(&mut s);
        let e = s
            .validate()
            .expect_err(&format!("the edit for {to:?} was accepted"));
        assert!(matches!(e, SceneError::Value { .. }), "{e:?}");
        assert_eq!(e.line(), None);
        assert!(e.to_string().starts_with("mem.toml: "), "{e}");
        assert_eq!(key_and_message(&e), key_and_message(&file_error), "{to:?}");
        messages.push(key_and_message(&e));
    }
    assert_ne!(
        messages[0], messages[1],
        "the twin: different faults differ"
    );
    // A material index past the list, which a file cannot express.
    let mut s = good.clone();
    s.spheres[0].material = 7;
    let e = s.validate().unwrap_err();
    assert_eq!(e.key(), Some("spheres[0].material"));
    let mut s = good;
    s.triangles[0].vertices[1][2] = f32::NAN;
    assert_eq!(
        s.validate().unwrap_err().key(),
        Some("triangles[0].vertices")
    );
}
