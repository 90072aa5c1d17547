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
