//! The cache of meshes and BVHs as `glint render` uses it: a second render reads both from
//! the cache and writes the same image to the bit; a changed input misses; a damaged entry
//! is caught, deleted and rebuilt with a warning, and the image is still the same;
//! `--no-cache` neither reads nor writes.

mod common;

use std::path::{Path, PathBuf};
use std::process::Command;

const GLINT: &str = env!("CARGO_BIN_EXE_glint");

fn scene(translate_x: f32) -> String {
    format!(
        r#"ambient = [0.1, 0.1, 0.1]
shadows = true
[camera]
eye = [0.0, 0.6, 3.2]
look_at = [0.0, 0.0, 0.0]
up = [0.0, 1.0, 0.0]
fov = 45.0
width = 96
height = 72
[[lights]]
position = [-3.0, 4.0, 5.0]
color = [0.9, 0.9, 0.9]
[materials.clay]
model = "phong"
ka = [0.5, 0.4, 0.3]
kd = [0.7, 0.5, 0.4]
ks = [0.4, 0.4, 0.4]
n = 20.0
[[meshes]]
file = "ico.obj"
material = "clay"
smooth = true
scale = [1.0, 0.8, 1.0]
rotate = [10.0, 20.0, 0.0]
translate = [{translate_x}, 0.0, 0.0]
[[spheres]]
center = [1.4, 0.0, -0.5]
radius = 0.4
material = "clay"
"#
    )
}

struct Run {
    png: Vec<u8>,
    stderr: String,
}

fn render(dir: &Path, extra: &[&str]) -> Run {
    let out = dir.join(format!("out-{}.png", extra.join("")));
    let o = Command::new(GLINT)
        .args(["render", "scene.toml", "-v", "--backend", "cpu", "-o"])
        .arg(&out)
        .args(extra)
        .current_dir(dir)
        .env("GLINT_CACHE_DIR", dir.join("cache"))
        .env("GLINT_CACHE_MIN_PRIMS", "0")
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&o.stderr).into_owned();
    assert!(o.status.success(), "{stderr}");
    Run {
        png: std::fs::read(&out).unwrap(),
        stderr,
    }
}

fn entries(dir: &Path) -> Vec<PathBuf> {
    let mut v: Vec<PathBuf> = std::fs::read_dir(dir.join("cache"))
        .map(|r| r.map(|e| e.unwrap().path()).collect())
        .unwrap_or_default();
    v.sort();
    v
}

#[test]
fn cached_renders_are_the_same_image_and_damage_is_rebuilt() {
    let dir = common::Scratch::new("cache");
    std::fs::write(dir.join("ico.obj"), glint::oracle::icosphere_obj(3)).unwrap();
    std::fs::write(dir.join("scene.toml"), scene(0.0)).unwrap();

    let first = render(&dir, &[]);
    assert!(
        first.stderr.contains("cache: stored mesh"),
        "{}",
        first.stderr
    );
    assert!(
        first.stderr.contains("cache: stored bvh"),
        "{}",
        first.stderr
    );
    assert_eq!(entries(&dir).len(), 2);

    let second = render(&dir, &[]);
    assert!(
        second.stderr.contains("cache: hit mesh"),
        "{}",
        second.stderr
    );
    assert!(
        second.stderr.contains("cache: hit bvh"),
        "{}",
        second.stderr
    );
    assert!(!second.stderr.contains("OBJ parse"), "{}", second.stderr);
    assert!(second.png == first.png, "the cached render differs");

    // --no-cache: neither reads nor writes, same image.
    let off = render(&dir, &["--no-cache"]);
    assert!(!off.stderr.contains("cache:"), "{}", off.stderr);
    assert!(off.png == first.png);

    // Every entry damaged (one bit flipped at its end): caught, rebuilt, same image.
    for e in entries(&dir) {
        let mut b = std::fs::read(&e).unwrap();
        *b.last_mut().unwrap() ^= 0x40;
        std::fs::write(&e, b).unwrap();
    }
    let healed = render(&dir, &[]);
    assert_eq!(
        healed.stderr.matches("was damaged").count(),
        2,
        "{}",
        healed.stderr
    );
    assert!(healed.stderr.contains("cache: stored mesh"));
    assert!(healed.png == first.png, "the rebuilt render differs");
    let again = render(&dir, &[]);
    assert!(again.stderr.contains("cache: hit mesh"), "{}", again.stderr);

    // The twin: the mesh moved by a hundredth misses both entries, and the image changes,
    // so the comparisons above can fail.
    std::fs::write(dir.join("scene.toml"), scene(0.01)).unwrap();
    let moved = render(&dir, &[]);
    assert!(
        moved.stderr.contains("cache: stored mesh"),
        "{}",
        moved.stderr
    );
    assert!(
        moved.stderr.contains("cache: stored bvh"),
        "{}",
        moved.stderr
    );
    assert!(moved.png != first.png);
    let _ = std::fs::remove_dir_all(&dir);
}
