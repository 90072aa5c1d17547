//! docs/scene-format.md lists every key the parser accepts, and no other: the parser's own
//! list of each table's keys (serde's "expected one of" for an unknown key) against the
//! first cells of the document's key table.

use std::collections::BTreeSet;
use std::path::Path;

/// A scene with one of every table, `extra` written into the table `at` names.
fn scene_with(at: &str, extra: &str) -> String {
    let tables = [
        ("", ""),
        (
            "camera",
            "[camera]\neye = [0, 0, 5]\nlook_at = [0, 0, 0]\nfov = 45\nwidth = 4\nheight = 4\n",
        ),
        ("camera.keys[]", "[[camera.keys]]\nframe = 0\n"),
        (
            "lights[]",
            "[[lights]]\ncolor = [1, 1, 1]\nposition = [0, 0, 5]\n",
        ),
        (
            "materials.NAME",
            "[materials.m]\nmodel = \"ambient\"\nka = [1, 1, 1]\n",
        ),
        (
            "spheres[]",
            "[[spheres]]\ncenter = [0, 0, 0]\nradius = 1\nmaterial = \"m\"\n",
        ),
        (
            "triangles[]",
            "[[triangles]]\nvertices = [[0, 0, 0], [1, 0, 0], [0, 1, 0]]\nmaterial = \"m\"\n",
        ),
        ("meshes[]", "[[meshes]]\nfile = \"absent.obj\"\n"),
        ("instances[]", "[[instances]]\nmesh = \"m\"\n"),
        ("output", "[output]\n"),
    ];
    let mut s = String::new();
    for (name, text) in tables {
        s += text;
        if name == at {
            s += extra;
            s += "\n";
        }
    }
    s
}

/// The keys the parser accepts in the table `at`, as its error for an unknown key lists
/// them.
fn parser_keys(at: &str) -> BTreeSet<String> {
    let src = scene_with(at, "zzz_unknown = 1");
    let e = glint::scene::Scene::parse(&src, Path::new("probe.toml"))
        .expect_err("an unknown key is an error")
        .to_string();
    let list = e
        .split("expected one of ")
        .nth(1)
        .or_else(|| e.split("expected ").nth(1))
        .unwrap_or_else(|| panic!("{at}: no list of keys in {e:?}"));
    assert!(e.contains("zzz_unknown"), "{at}: {e}");
    list.split('`')
        .skip(1)
        .step_by(2)
        .map(|k| {
            let sep = if at.is_empty() { "" } else { "." };
            format!("{at}{sep}{k}")
        })
        .collect()
}

/// The first cells of docs/scene-format.md's key table.
fn documented_keys(text: &str) -> BTreeSet<String> {
    text.lines()
        .filter_map(|l| l.strip_prefix("| `"))
        .filter_map(|l| l.split('`').next())
        .map(str::to_owned)
        .collect()
}

const TABLES: [&str; 10] = [
    "",
    "camera",
    "camera.keys[]",
    "lights[]",
    "materials.NAME",
    "spheres[]",
    "triangles[]",
    "meshes[]",
    "instances[]",
    "output",
];

fn all_parser_keys() -> BTreeSet<String> {
    let mut keys = BTreeSet::new();
    for t in TABLES {
        keys.extend(parser_keys(t));
    }
    // The tables themselves are keys of the top level, documented by their own keys.
    for t in [
        "camera",
        "lights",
        "materials",
        "spheres",
        "triangles",
        "meshes",
        "instances",
        "output",
    ] {
        assert!(keys.remove(t), "{t} is not a top-level key of the parser");
    }
    assert!(
        keys.remove("camera.keys"),
        "camera.keys is not a key of [camera]"
    );
    keys
}

#[test]
fn every_key_is_documented_and_every_documented_key_is_read() {
    let doc =
        std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join("docs/scene-format.md"))
            .unwrap();
    let (parser, documented) = (all_parser_keys(), documented_keys(&doc));
    assert!(parser.len() > 40, "{parser:?}");
    let missing: Vec<_> = parser.difference(&documented).collect();
    let extra: Vec<_> = documented.difference(&parser).collect();
    assert!(
        missing.is_empty() && extra.is_empty(),
        "docs/scene-format.md lacks {missing:?} and lists keys the parser does not read: {extra:?}"
    );
}

/// The twin: a key dropped from the document, or one it invents, is seen.
#[test]
fn a_missing_or_invented_key_is_seen() {
    let doc =
        std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join("docs/scene-format.md"))
            .unwrap();
    let parser = all_parser_keys();
    let without: String = doc
        .lines()
        .filter(|l| !l.starts_with("| `camera.fov`"))
        .map(|l| format!("{l}\n"))
        .collect();
    assert_ne!(documented_keys(&without), parser);
    let invented = format!("{doc}\n| `camera.focal` | float | optional | | |\n");
    assert_ne!(documented_keys(&invented), parser);
}
