//! The command line's everyday contract: `render` without `-o` names its output after the
//! scene, `--quiet` prints nothing on success, the summary line counts in words a person
//! would write, and `glint check` reads a scene as `render` would and says good or bad by its
//! exit status. CPU tracer only: no device is needed.

mod common;

use std::path::Path;
use std::process::Output;

const SCENE: &str = r#"[camera]
eye = [0.0, 0.0, 5.0]
look_at = [0.0, 0.0, 0.0]
fov = 45.0
width = 32
height = 24
[[lights]]
position = [2.0, 2.0, 5.0]
color = [1.0, 1.0, 1.0]
[materials.m]
model = "diffuse"
ka = [0.2, 0.2, 0.2]
kd = [0.8, 0.8, 0.8]
[[spheres]]
center = [0.0, 0.0, 0.0]
radius = 1.0
material = "m"
"#;

/// `glint ARGS` run in `dir`.
fn glint(dir: &Path, args: &[&str]) -> Output {
    common::glint_command()
        .current_dir(dir)
        .args(args)
        .output()
        .unwrap()
}

fn text(o: &Output) -> (String, String) {
    (
        String::from_utf8_lossy(&o.stdout).into_owned(),
        String::from_utf8_lossy(&o.stderr).into_owned(),
    )
}

#[test]
fn render_without_an_output_names_it_after_the_scene() {
    let d = common::Scratch::new("cli-default-output");
    std::fs::create_dir(d.join("scenes")).unwrap();
    std::fs::write(d.join("scenes/ball.toml"), SCENE).unwrap();
    let o = glint(&d, &["render", "scenes/ball.toml", "--backend", "cpu"]);
    let (out, err) = text(&o);
    assert!(o.status.success(), "{err}");
    // In the current folder, not beside the scene.
    let png = d.join("ball.png");
    assert!(png.is_file(), "{out}{err}");
    assert!(!d.join("scenes/ball.png").exists());
    let img = glint::image::Image::load(&png).unwrap();
    assert_eq!((img.width, img.height), (32, 24));
    // One sphere, no triangles: said as a person would.
    assert!(out.starts_with("ball.png: 32x24, 1 sphere, "), "{out}");
    assert!(!out.contains("triangle"), "{out}");
    // The twin: -o still wins.
    let o = glint(
        &d,
        &[
            "render",
            "scenes/ball.toml",
            "--backend",
            "cpu",
            "-o",
            "x.png",
        ],
    );
    assert!(o.status.success());
    assert!(d.join("x.png").is_file());
}

#[test]
fn quiet_prints_nothing_and_verbose_prints_the_stages() {
    let d = common::Scratch::new("cli-quiet");
    std::fs::write(d.join("s.toml"), SCENE).unwrap();
    let o = glint(&d, &["render", "s.toml", "--backend", "cpu", "--quiet"]);
    let (out, err) = text(&o);
    assert!(o.status.success(), "{err}");
    assert_eq!((out.as_str(), err.as_str()), ("", ""));
    assert!(d.join("s.png").is_file());
    // The twin: without --quiet the summary is printed; -v adds the stages.
    let o = glint(&d, &["render", "s.toml", "--backend", "cpu", "-v"]);
    let (out, err) = text(&o);
    assert!(out.contains("s.png: 32x24"), "{out}");
    assert!(err.contains("trace"), "{err}");
    // Together they make no sense: a usage error.
    let o = glint(&d, &["render", "s.toml", "-q", "-v"]);
    assert_eq!(o.status.code(), Some(2));
    // Errors are still printed under --quiet.
    let o = glint(&d, &["render", "absent.toml", "--quiet"]);
    let (_, err) = text(&o);
    assert_eq!(o.status.code(), Some(1));
    assert!(err.contains("absent.toml"), "{err}");
}

#[test]
fn check_says_good_or_names_the_error_by_its_exit_status() {
    let d = common::Scratch::new("cli-check");
    std::fs::write(d.join("good.toml"), SCENE).unwrap();
    let o = glint(&d, &["check", "good.toml"]);
    let (out, err) = text(&o);
    assert!(o.status.success(), "{err}");
    assert_eq!(
        out.trim(),
        "good.toml: good (0 triangles, 1 sphere, 1 light)"
    );
    // A key in the wrong place: the file, the line and the key.
    std::fs::write(
        d.join("bad.toml"),
        SCENE.replace("fov = 45.0", "fov = 45.0\nfocal = 3.0"),
    )
    .unwrap();
    let o = glint(&d, &["check", "good.toml", "bad.toml"]);
    let (out, err) = text(&o);
    assert_eq!(o.status.code(), Some(1), "{out}{err}");
    assert!(out.contains("good.toml: good"), "{out}");
    assert!(err.contains("bad.toml:5"), "{err}");
    assert!(err.contains("focal"), "{err}");
    assert!(err.contains("1 of 2 scenes did not pass"), "{err}");
    // A missing mesh is found without rendering.
    std::fs::write(
        d.join("mesh.toml"),
        format!("{SCENE}[[meshes]]\nfile = \"gone.obj\"\nmaterial = \"m\"\n"),
    )
    .unwrap();
    let o = glint(&d, &["check", "mesh.toml"]);
    let (_, err) = text(&o);
    assert_eq!(o.status.code(), Some(1));
    assert!(err.contains("gone.obj"), "{err}");
    // A missing mesh beside glint's own fetch script says how to get it; elsewhere not.
    std::fs::write(d.join("fetch-meshes.sh"), "#!/bin/sh\n").unwrap();
    let o = glint(&d, &["check", "mesh.toml"]);
    let (_, err) = text(&o);
    assert_eq!(o.status.code(), Some(1));
    assert!(
        err.contains("meshes[0].file") && err.contains("gone.obj"),
        "{err}"
    );
    assert!(err.contains("fetch-meshes.sh"), "{err}");
    std::fs::remove_file(d.join("fetch-meshes.sh")).unwrap();
    let (_, err) = text(&glint(&d, &["check", "mesh.toml"]));
    assert!(!err.contains("fetch-meshes.sh"), "{err}");
    // Every shipped scene that needs no downloaded mesh is good.
    let scenes = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes");
    for name in [
        "sphere",
        "bb8",
        "whitted",
        "textured",
        "spot",
        "suzanne-ply",
    ] {
        let p = scenes.join(format!("{name}.toml"));
        let o = glint(&d, &["check", p.to_str().unwrap()]);
        assert!(o.status.success(), "{name}: {}", text(&o).1);
    }
}

/// `--threads N` changes who works, not what is made: the same f32 image in every bit with
/// one thread, three and the default, on a mesh whose bands and packets end unevenly.
#[test]
fn threads_change_no_bit() {
    let d = common::Scratch::new("cli-threads");
    let scene = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/suzanne-ply.toml");
    let mut images = Vec::new();
    for threads in [None, Some("1"), Some("3")] {
        let out = d.join(format!("t{}.exr", threads.unwrap_or("default")));
        let mut args = vec![
            "render",
            scene.to_str().unwrap(),
            "--backend",
            "cpu",
            "--size",
            "97x61",
            "-q",
            "-o",
            out.to_str().unwrap(),
        ];
        if let Some(n) = threads {
            args.extend(["--threads", n]);
        }
        let o = glint(&d, &args);
        assert!(o.status.success(), "{:?}: {}", threads, text(&o).1);
        images.push(std::fs::read(&out).unwrap());
    }
    assert!(images.iter().all(|i| *i == images[0]));
    // 0 threads is a usage error.
    let o = glint(&d, &["render", scene.to_str().unwrap(), "--threads", "0"]);
    assert_eq!(o.status.code(), Some(2));
}

/// A `GLINT_*` variable set to a value glint cannot use is an error naming it (exit 2, as
/// for a bad flag), not a setting ignored in silence. The twin: a good value renders.
#[test]
fn a_bad_environment_value_is_named() {
    let d = common::Scratch::new("cli-env");
    std::fs::write(d.join("s.toml"), SCENE).unwrap();
    for (k, v) in [
        ("GLINT_MAX_INPUT_MIB", "lots"),
        ("GLINT_CACHE_MIB", "-1"),
        ("GLINT_TRAVERSAL", "rays"),
        ("GLINT_PACKET_SHADOWS", "yes"),
    ] {
        let o = common::glint_command()
            .current_dir(&*d)
            .args(["render", "s.toml", "--backend", "cpu", "-q"])
            .env(k, v)
            .output()
            .unwrap();
        let (_, err) = text(&o);
        assert_eq!(o.status.code(), Some(2), "{k}={v}: {err}");
        assert!(err.contains(k) && err.contains(v), "{err}");
    }
    let o = common::glint_command()
        .current_dir(&*d)
        .args(["render", "s.toml", "--backend", "cpu", "-q"])
        .env("GLINT_MAX_INPUT_MIB", "64")
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", text(&o).1);
}

/// `--set`: a key changed before the scene is read, a new key added, errors naming the
/// file's own line and, where the value at fault was set, the argument.
#[test]
fn set_changes_keys_and_errors_keep_the_files_lines() {
    let d = common::Scratch::new("cli-set");
    std::fs::write(d.join("s.toml"), SCENE).unwrap();
    let size = |args: &[&str]| {
        let mut all = vec!["render", "s.toml", "--backend", "cpu", "-q", "-o", "o.exr"];
        all.extend_from_slice(args);
        let o = glint(&d, &all);
        assert!(o.status.success(), "{}", text(&o).1);
        let img = glint::image::Image::load(&d.join("o.exr")).unwrap();
        (img.width, img.height, img)
    };
    // The twin of each: without --set the scene's own values.
    let (w, h, plain) = size(&[]);
    assert_eq!((w, h), (32, 24));
    let (w, h, _) = size(&["--set", "camera.width=16", "--set", "camera.height=8"]);
    assert_eq!((w, h), (16, 8));
    // A new key (the camera has no `samples`) and a changed colour change the image.
    let (_, _, aa) = size(&["--set", "camera.samples=2"]);
    assert_ne!(aa.pixels, plain.pixels);
    let (_, _, red) = size(&["--set", "lights[0].color=[1,0,0]"]);
    // Red light: no pixel gains green, and the lit ones lose it.
    let pairs = || red.pixels.iter().zip(&plain.pixels);
    assert!(pairs().all(|(r, p)| r[1] <= p[1]));
    assert!(pairs().any(|(r, p)| r[1] < p[1]));

    let err = |args: &[&str]| {
        let mut all = vec!["check", "s.toml"];
        all.extend_from_slice(args);
        let o = glint(&d, &all);
        assert_eq!(o.status.code(), Some(1), "{args:?}");
        text(&o).1
    };
    // The value at fault was set: the file's line of the key, and the argument.
    let e = err(&[
        "--set",
        "camera.samples=2",
        "--set",
        "materials.m.kd=[2e6,0,0]",
    ]);
    assert!(
        e.contains("s.toml:13: materials.m.kd:")
            && e.contains("(set by --set materials.m.kd=[2e6,0,0])"),
        "{e}"
    );
    // A fault of the file's own, below an inserted line: still the file's line, no argument.
    std::fs::write(
        d.join("bad.toml"),
        SCENE.replace("radius = 1.0", "radius = -1.0"),
    )
    .unwrap();
    let o = glint(
        &d,
        &[
            "check",
            "bad.toml",
            "--set",
            "camera.samples=2",
            "--set",
            "shadows=true",
        ],
    );
    let (_, e) = text(&o);
    assert!(
        e.contains("bad.toml:16: spheres[0].radius:") && !e.contains("--set"),
        "{e}"
    );
    // Paths that do not exist, and arguments that are not settings.
    let e = err(&["--set", "lights[1].color=[1,0,0]"]);
    assert!(
        e.contains("--set lights[1].color=[1,0,0]: lights has 1 entry"),
        "{e}"
    );
    let o = glint(&d, &["check", "s.toml", "--set", "camera.fov"]);
    assert_eq!(
        o.status.code(),
        Some(2),
        "a malformed --set is a usage error"
    );
    // A word is a string: an unknown encoding is named with its key.
    let e = err(&["--set", "output.encoding=rgb"]);
    assert!(
        e.contains("output.encoding") && e.contains("\"rgb\""),
        "{e}"
    );
}

/// `--encoding srgb` (or `[output] encoding`) writes the sRGB curve's bytes, exactly the
/// library's table applied to the f32 image, and says so in the PNG; linear stays linear.
#[test]
fn srgb_encoding_is_the_curve_of_the_exr() {
    use glint::image::Encoding;
    let d = common::Scratch::new("cli-encoding");
    std::fs::write(d.join("s.toml"), SCENE).unwrap();
    let run = |args: &[&str]| {
        let mut all = vec!["render", "s.toml", "--backend", "cpu", "-q"];
        all.extend_from_slice(args);
        let o = glint(&d, &all);
        assert!(o.status.success(), "{}", text(&o).1);
    };
    run(&["-o", "s.exr"]);
    run(&["-o", "srgb.png", "--encoding", "srgb"]);
    run(&["-o", "set.png", "--set", "output.encoding=srgb"]);
    run(&["-o", "linear.png"]);
    let exr = glint::image::Image::load(&d.join("s.exr")).unwrap();
    let png = |name: &str| image::open(d.join(name)).unwrap().to_rgb8().into_raw();
    assert_eq!(png("srgb.png"), exr.to_rgb8_encoded(Encoding::Srgb));
    assert_eq!(png("set.png"), png("srgb.png"));
    // The twin: the linear PNG is the plain quantisation, and it is not the sRGB one.
    assert_eq!(png("linear.png"), exr.to_rgb8());
    assert_ne!(png("linear.png"), png("srgb.png"));
    let info = |name: &str| {
        let f = std::fs::File::open(d.join(name)).unwrap();
        png::Decoder::new(std::io::BufReader::new(f))
            .read_info()
            .unwrap()
            .info()
            .srgb
    };
    assert!(info("srgb.png").is_some());
    assert!(info("linear.png").is_none());
}

/// `glint bench` with no scene measures the seed scenes shipped in the binary, from any
/// folder.
#[test]
fn bench_without_scenes_works_anywhere() {
    let d = common::Scratch::new("cli-bench-anywhere");
    let o = glint(
        &d,
        &[
            "bench",
            "--no-gpu",
            "--runs",
            "1",
            "--size",
            "16x12",
            "--triangle",
            "naive",
            "--out",
            "out",
        ],
    );
    let (out, err) = text(&o);
    assert!(o.status.success(), "{err}");
    for name in ["sphere", "triangle", "umbrella", "bb8", "mitsubishi"] {
        assert!(out.contains(name), "{name} missing: {out}");
    }
    assert!(d.join("out/report.json").is_file());
}

/// `glint view` on a display with no X server names the display, never a path in winit's
/// sources. (No DISPLAY at all: tests/view.rs, `no_display_is_a_one_line_error`.)
#[test]
fn view_on_a_display_without_a_server_names_it() {
    let d = common::Scratch::new("cli-view-nodisplay");
    std::fs::write(d.join("s.toml"), SCENE).unwrap();
    let o = common::glint_command()
        .current_dir(&*d)
        .args(["view", "s.toml", "--backend", "cpu"])
        .env_remove("WAYLAND_DISPLAY")
        .env("DISPLAY", ":97")
        .output()
        .unwrap();
    let e = text(&o).1;
    assert_eq!(o.status.code(), Some(1), "{e}");
    assert!(e.contains("cannot open a window on display \":97\""), "{e}");
    assert!(!e.contains(".cargo") && !e.contains(".rs:"), "{e}");
}

/// `glint completions SHELL` and `glint manpage` are generated from the parser itself, so
/// they name today's flags.
#[test]
fn completions_and_manual_page_come_from_the_parser() {
    let d = common::Scratch::new("cli-completions");
    for (shell, mark) in [
        ("bash", "_glint"),
        ("zsh", "#compdef glint"),
        ("fish", "complete -c glint"),
    ] {
        let o = glint(&d, &["completions", shell]);
        let (out, err) = text(&o);
        assert!(o.status.success(), "{err}");
        assert!(
            out.contains(mark) && out.contains("encoding") && out.contains("tolerance"),
            "{shell}"
        );
    }
    let o = glint(&d, &["manpage"]);
    let (out, _) = text(&o);
    assert!(o.status.success());
    assert!(
        out.starts_with(".ie") || out.contains(".TH glint"),
        "{}",
        &out[..out.len().min(200)]
    );
    assert!(out.contains("render") && out.contains("compare"));
    // The twin: a shell clap_complete does not know is a usage error.
    let o = glint(&d, &["completions", "tcsh"]);
    assert_eq!(o.status.code(), Some(2));
}
