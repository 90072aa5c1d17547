//! The browser page (web/) in headless Chromium with WebGPU (on its SwiftShader), driven
//! through the DevTools protocol by `web/test/browser.mjs`: the wasm CPU tracer's image
//! equals `glint render`'s PNG in every byte, the WebGPU image equals it within 1/255, a
//! broken scene shows its error under the editor, and every seed scene renders.
//!
//! These tests need `bash web/build.sh` (web/dist), Node.js 20 and Chromium, so they are
//! `#[ignore]`d in a plain `cargo test` (listed as ignored, never as passed); the test
//! command's pass 5 (`.ci/test.sh`) builds the page, installs Chromium and runs them with
//! `--ignored`, where a missing piece fails them.

mod common;

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::sync::OnceLock;

use common::{Scratch, glint_command};

const SEED: [&str; 5] = ["sphere", "triangle", "umbrella", "bb8", "mitsubishi"];

fn root() -> &'static Path {
    Path::new(env!("CARGO_MANIFEST_DIR"))
}

/// What one browser session answered, and the folder with its images.
struct Session {
    scenes: Vec<String>,
    results: serde_json::Value,
    out: Scratch,
}

/// bb8's camera moved: a scene whose image must differ from bb8's (the twins).
fn bb8_moved() -> String {
    let text = std::fs::read_to_string(root().join("scenes/bb8.toml")).unwrap();
    let moved = text.replace("eye = [1.2, 0.6, 7.0]", "eye = [1.3, 0.6, 7.0]");
    assert_ne!(
        moved, text,
        "bb8.toml's camera line changed: update this test"
    );
    moved
}

/// A bb8 whose field of view is a string: the error the page must show.
fn bb8_broken() -> String {
    let text = std::fs::read_to_string(root().join("scenes/bb8.toml")).unwrap();
    let broken = text.replace("fov = 45.0", "fov = \"wide\"");
    assert_ne!(
        broken, text,
        "bb8.toml's fov line changed: update this test"
    );
    broken
}

/// One Chromium session for all the tests: every scene of the page's index on both
/// backends, the twins, the editor's error, and a screenshot.
/// The session runs once: where it fails, every test fails with its message (not a second
/// run of Chromium each).
fn session() -> &'static Session {
    static S: OnceLock<Result<Session, String>> = OnceLock::new();
    let once = S.get_or_init(|| {
        std::panic::catch_unwind(start_session).map_err(|p| {
            p.downcast_ref::<String>()
                .cloned()
                .or_else(|| p.downcast_ref::<&str>().map(|s| s.to_string()))
                .unwrap_or_else(|| "the browser session panicked".to_string())
        })
    });
    match once {
        Ok(s) => s,
        Err(e) => panic!("{e}"),
    }
}

/// Builds the requests, runs web/test/browser.mjs on them and reads its answers.
fn start_session() -> Session {
    {
        let dist = std::env::var_os("GLINT_WEB_DIST")
            .map(PathBuf::from)
            .unwrap_or_else(|| root().join("web/dist"));
        assert!(
            dist.join("index.html").is_file() && dist.join("glint_web_bg.wasm").is_file(),
            "{} holds no built page: run `bash web/build.sh` first",
            dist.display()
        );
        let index: serde_json::Value = serde_json::from_slice(
            &std::fs::read(dist.join("scenes/index.json")).expect("the page's scenes/index.json"),
        )
        .expect("scenes/index.json is JSON");
        let scenes: Vec<String> = index["scenes"]
            .as_array()
            .expect("a scenes list")
            .iter()
            .map(|s| s.as_str().unwrap().to_string())
            .collect();
        let mut requests = Vec::new();
        for name in &scenes {
            let toml = std::fs::read_to_string(dist.join(format!("scenes/{name}.toml"))).unwrap();
            for backend in ["cpu", "gpu"] {
                requests.push(serde_json::json!({
                    "name": format!("{name}-{backend}"),
                    "toml": toml,
                    "path": format!("scenes/{name}.toml"),
                    "backend": backend,
                }));
            }
        }
        requests.push(serde_json::json!({
            "name": "bb8-moved-cpu", "toml": bb8_moved(),
            "path": "scenes/bb8.toml", "backend": "cpu",
        }));
        let bb8 = std::fs::read_to_string(root().join("scenes/bb8.toml")).unwrap();
        requests.push(serde_json::json!({ "name": "broken", "edit": bb8_broken() }));
        requests.push(serde_json::json!({ "name": "fixed", "edit": bb8 }));
        // 10 MiB of scene (bb8 and comment lines); a mesh on a server that never answers.
        requests.push(serde_json::json!({ "name": "huge", "edit": bb8, "pad": 10 << 20 }));
        requests.push(serde_json::json!({
            "name": "hanging", "edit": format!("{bb8}\n{HANGING_MESH}"), "fetchTimeoutMs": 2000,
        }));
        requests.push(serde_json::json!({ "name": "recovered", "edit": bb8 }));
        requests.push(serde_json::json!({ "name": "page", "screenshot": true }));

        let out = Scratch::new("browser");
        let mut child = std::process::Command::new("node")
            .arg("--experimental-websocket")
            .arg(root().join("web/test/browser.mjs"))
            .arg(&dist)
            .arg(&*out)
            .stdin(std::process::Stdio::piped())
            .stderr(std::process::Stdio::piped())
            .spawn()
            .expect("node (Node.js 20 or newer) on PATH");
        {
            use std::io::Write;
            let mut stdin = child.stdin.take().unwrap();
            stdin
                .write_all(serde_json::to_string(&requests).unwrap().as_bytes())
                .unwrap();
        }
        let done = child.wait_with_output().unwrap();
        assert!(
            done.status.success(),
            "the browser session failed:\n{}",
            String::from_utf8_lossy(&done.stderr)
        );
        let results: serde_json::Value =
            serde_json::from_slice(&std::fs::read(out.join("results.json")).unwrap()).unwrap();
        eprintln!(
            "browser: {}\nWebGPU: {}",
            results["userAgent"], results["gpuStatus"]
        );
        if let Some(shot) = std::env::var_os("GLINT_WEB_SCREENSHOT") {
            std::fs::copy(out.join("page.png"), shot).unwrap();
        }
        Session {
            scenes,
            results,
            out,
        }
    }
}

impl Session {
    /// The RGBA bytes the page returned for request `name`, with its size; panics with the
    /// page's error where it gave one.
    fn image(&self, name: &str) -> (u32, u32, Vec<u8>) {
        let r = &self.results["results"][name];
        assert!(
            r["error"].is_null(),
            "{name}: the page answered with an error: {}",
            r["error"]
        );
        assert_eq!(r["isBytes"], true, "{name}: rgba is not a Uint8Array");
        let (w, h) = (r["width"].as_u64().unwrap(), r["height"].as_u64().unwrap());
        let bytes = std::fs::read(self.out.join(format!("{name}.rgba"))).unwrap();
        assert_eq!(
            bytes.len() as u64,
            4 * w * h,
            "{name}: rgba of the wrong length"
        );
        (w as u32, h as u32, bytes)
    }
}

/// `glint render --backend cpu` of `scenes/NAME.toml`, or of `toml` (a scene that names
/// no files) written into `dir`, as RGBA.
fn native(name: &str, toml: Option<&str>, dir: &Path) -> (u32, u32, Vec<u8>) {
    let scene = match toml {
        None => root().join(format!("scenes/{name}.toml")),
        Some(text) => {
            let p = dir.join(format!("{name}.toml"));
            std::fs::write(&p, text).unwrap();
            p
        }
    };
    let out = dir.join(format!("{name}-native.png"));
    // The page draws the linear bytes on its canvas whatever the scene's `[output]
    // encoding`, which is a PNG file's (the textured scene's is sRGB).
    let s = glint_command()
        .args(["render", "--backend", "cpu", "--encoding", "linear", "-o"])
        .arg(&out)
        .arg(&scene)
        .output()
        .unwrap();
    assert!(s.status.success(), "{}", String::from_utf8_lossy(&s.stderr));
    let img = image::open(&out).unwrap().to_rgba8();
    (img.width(), img.height(), img.into_raw())
}

/// (pixels differing at all, pixels differing by more than 1/255 in some channel).
fn differences(a: &[u8], b: &[u8]) -> (usize, usize) {
    let mut n = (0, 0);
    for (p, q) in a.chunks_exact(4).zip(b.chunks_exact(4)) {
        let d = (0..4).map(|k| p[k].abs_diff(q[k])).max().unwrap();
        n.0 += (d > 0) as usize;
        n.1 += (d > 1) as usize;
    }
    n
}

/// The wasm CPU tracer's image of every scene the page offers is `glint render`'s linear
/// PNG in every byte; the twin: bb8 with its camera moved is not.
#[test]
#[ignore = "needs web/dist, node and chromium: run by .ci/test.sh's pass 5 with --ignored"]
fn wasm_cpu_images_are_the_native_pngs() {
    let s = session();
    let dir = Scratch::new("browser-native");
    for name in &s.scenes {
        let page = s.image(&format!("{name}-cpu"));
        let want = native(name, None, &dir);
        assert_eq!((page.0, page.1), (want.0, want.1), "{name}: size");
        assert!(
            page.2 == want.2,
            "{name}: the wasm CPU image differs from glint render's PNG in {:?} pixels",
            differences(&page.2, &want.2)
        );
    }
    let moved = s.image("bb8-moved-cpu");
    let bb8 = native("bb8", None, &dir);
    assert!(
        moved.2 != bb8.2,
        "the twin: a moved camera must change the image"
    );
    // and the moved scene is what native glint renders for it
    assert!(moved.2 == native("bb8-moved", Some(&bb8_moved()), &dir).2);
}

/// The WebGPU image of every scene (Chromium's Tint and SwiftShader) equals `glint
/// render`'s PNG within 1/255 on at least 99.9 % of its pixels; how many differ at all is
/// printed. The twin: bb8's WebGPU image against the moved camera's fails that bar.
#[test]
#[ignore = "needs web/dist, node and chromium: run by .ci/test.sh's pass 5 with --ignored"]
fn webgpu_images_match_within_one_step() {
    let s = session();
    assert_eq!(
        s.results["hasGpu"], true,
        "the page found no WebGPU: {}",
        s.results["gpuStatus"]
    );
    let dir = Scratch::new("browser-gpu");
    let mut report = BTreeMap::new();
    for name in &s.scenes {
        let page = s.image(&format!("{name}-gpu"));
        let want = native(name, None, &dir);
        assert_eq!((page.0, page.1), (want.0, want.1), "{name}: size");
        let (any, beyond) = differences(&page.2, &want.2);
        let pixels = (page.0 * page.1) as usize;
        report.insert(name.clone(), (any, beyond, pixels));
        assert!(
            beyond * 1000 <= pixels,
            "{name}: {beyond} of {pixels} pixels differ by more than 1/255"
        );
    }
    for (name, (any, beyond, pixels)) in &report {
        eprintln!(
            "WebGPU vs native CPU, {name}: {any} of {pixels} pixels differ ({beyond} by more \
             than 1/255)"
        );
    }
    let gpu = s.image("bb8-gpu");
    let moved = s.image("bb8-moved-cpu");
    let (_, beyond) = differences(&gpu.2, &moved.2);
    assert!(
        beyond * 1000 > (gpu.0 * gpu.1) as usize,
        "the twin: a moved camera must fail the 99.9 % bar"
    );
}

/// A scene with a bad value, typed into the editor, shows `file:line: key: message` under
/// it; the twin: the same scene fixed shows no error and a verdict.
#[test]
#[ignore = "needs web/dist, node and chromium: run by .ci/test.sh's pass 5 with --ignored"]
fn a_broken_scene_shows_its_error_under_the_editor() {
    let s = session();
    let broken = &s.results["results"]["broken"];
    let shown = broken["shownError"].as_str().unwrap_or_default();
    let line = bb8_broken()
        .lines()
        .position(|l| l.starts_with("fov = "))
        .unwrap()
        + 1;
    assert!(
        shown.contains(&format!("scenes/bb8.toml:{line}: camera.fov:")),
        "the error under the editor: {shown:?}"
    );
    let fixed = &s.results["results"]["fixed"];
    assert_eq!(fixed["shownError"], "", "the fixed scene shows an error");
    assert!(
        fixed["verdict"]
            .as_str()
            .unwrap_or_default()
            .contains("GPU"),
        "the fixed scene shows no verdict: {fixed}"
    );
}

/// A mesh whose file is on a server that never answers (the test server's `/never/`).
const HANGING_MESH: &str = "[[meshes]]\nfile = \"../never/m.obj\"\nmaterial = \"white\"\n";

/// The page under bad input: a 10 MiB scene is refused at once, naming its size; a mesh on
/// a server that never answers is given up after the page's fetch timeout (2 s here) and
/// the error names the file and why; each time the last good picture stays, dimmed. The
/// twins: after them the scene renders again with no error and no dimming, and the good
/// render before them was not dimmed.
#[test]
#[ignore = "needs web/dist, node and chromium: run by .ci/test.sh's pass 5 with --ignored"]
fn the_page_refuses_what_it_cannot_take_and_keeps_the_last_picture() {
    let s = session();
    let r = |name: &str| &s.results["results"][name];
    let fixed = r("fixed");
    assert_eq!(
        fixed["stale"], false,
        "the twin: a good render is not dimmed: {fixed}"
    );
    let good = fixed["cpuSize"].clone();
    assert!(good[0].as_u64().unwrap_or(0) > 1, "no picture: {fixed}");
    // The last good picture is still shown, dimmed.
    let kept_dimmed = |r: &serde_json::Value| {
        assert_eq!(r["stale"], true, "{r}");
        assert_eq!(r["cpuSize"], good, "the last picture is gone: {r}");
    };

    let huge = r("huge");
    let shown = huge["shownError"].as_str().unwrap_or_default();
    assert!(
        shown.contains("scenes/bb8.toml: the scene text is 10.")
            && shown.contains("the page takes scenes up to 4 MiB"),
        "{huge}"
    );
    kept_dimmed(huge);

    let hanging = r("hanging");
    let shown = hanging["shownError"].as_str().unwrap_or_default();
    assert!(
        shown.contains("never/m.obj is not loaded")
            && shown.contains("(fetching never/m.obj: no answer in 2 s)"),
        "{hanging}"
    );
    let seconds = hanging["seconds"].as_f64().unwrap_or(f64::MAX);
    assert!((2.0..20.0).contains(&seconds), "{hanging}");
    kept_dimmed(hanging);

    let recovered = r("recovered");
    assert_eq!(recovered["shownError"], "", "{recovered}");
    assert_eq!(recovered["stale"], false, "{recovered}");
    assert!(
        recovered["verdict"]
            .as_str()
            .unwrap_or_default()
            .contains("GPU"),
        "{recovered}"
    );
}

/// The five seed scenes are in the page's picker, and each renders on both backends (not
/// a blank frame).
#[test]
#[ignore = "needs web/dist, node and chromium: run by .ci/test.sh's pass 5 with --ignored"]
fn every_seed_scene_renders() {
    let s = session();
    for name in SEED {
        assert!(s.scenes.iter().any(|n| n == name), "{name} is not offered");
        for backend in ["cpu", "gpu"] {
            let (_, _, rgba) = s.image(&format!("{name}-{backend}"));
            let first = &rgba[..4];
            assert!(
                rgba.chunks_exact(4).any(|p| p != first),
                "{name} on {backend}: a blank frame"
            );
        }
    }
    assert!(s.out.join("page.png").is_file(), "no screenshot");
}
