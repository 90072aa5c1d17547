//! Camera paths (`[[camera.keys]]`) and their frames (`glint render --frames`,
//! `glint::render::render_frames`): each frame file is, in every bit, the render of the
//! scene with the camera `Scene::camera_at` gives for it, on the CPU and on the GPU, with
//! the buffers made once; `--resume` keeps what exists; bad keys and templates are errors
//! naming the file, the line and the key.

mod common;

gpu_sentinel!();

use glint::image::Image;
use glint::render::{FrameDone, FrameRange, Job, Output, render_frames};
use glint::scene::Scene;
use glint::{Backend, RenderOptions, Renderer};
use std::path::Path;

/// bb8's spheres and lights under a camera path of three keys (the middle one changes only
/// the field of view).
fn path_scene(dir: &Path) -> std::path::PathBuf {
    let text = std::fs::read_to_string("scenes/bb8.toml").unwrap();
    let keys = "\n[[camera.keys]]\nframe = 0\n\n[[camera.keys]]\nframe = 4\nfov = 30.0\n\n\
                [[camera.keys]]\nframe = 8\neye = [6.0, 3.0, 9.0]\n";
    let p = dir.join("path.toml");
    std::fs::write(&p, format!("{text}{keys}")).unwrap();
    p
}

fn small() -> RenderOptions {
    RenderOptions {
        size: Some((64, 48)),
        ..RenderOptions::default()
    }
}

/// The scene's image at `frame`, rendered on its own (a fresh job, fresh buffers).
fn alone(scene: &Scene, frame: f64, renderer: &Renderer) -> Image {
    let mut s = scene.clone();
    s.camera = s.camera_at(frame).unwrap();
    renderer.render(&s, &small()).unwrap()
}

/// Frames 2..=6 to EXR files (every f32 bit): each is the frame rendered alone. The twin:
/// frame 2's file is not frame 6's image.
fn frames_are_each_frame_alone(renderer: &Renderer, name: &str) {
    let d = common::Scratch::new(name);
    let mut scene = Scene::load(path_scene(&d)).unwrap();
    let template = d.join("f_{:03}.exr");
    let mut written = Vec::new();
    render_frames(
        &mut scene,
        renderer,
        &small(),
        (&template, "2..6".parse().unwrap(), false),
        &mut |f, done| match done {
            FrameDone::Written(p, _) => written.push((f, p)),
            FrameDone::Kept(p) => panic!("nothing to keep, yet {p:?} was kept"),
        },
    )
    .unwrap();
    assert_eq!(
        written.iter().map(|(f, _)| *f).collect::<Vec<_>>(),
        vec![2, 3, 4, 5, 6]
    );
    let original = Scene::load(d.join("path.toml")).unwrap();
    for (f, p) in &written {
        assert_eq!(p, &d.join(format!("f_{f:03}.exr")));
        let file = Image::load(p).unwrap();
        common::same_bits(&file, &alone(&original, *f as f64, renderer))
            .unwrap_or_else(|e| panic!("frame {f}: {e}"));
    }
    let first = Image::load(&written[0].1).unwrap();
    assert!(common::same_bits(&first, &alone(&original, 6.0, renderer)).is_err());
}

#[test]
fn cpu_frames_are_each_frame_rendered_alone() {
    frames_are_each_frame_alone(&Renderer::new(Backend::Cpu).unwrap(), "frames-cpu");
}

#[test]
fn gpu_frames_are_each_frame_rendered_alone() {
    let Some(gpu) = common::gpu() else { return };
    let options = glint::gpu::GpuOptions::adapter(Some(&gpu.info.name));
    let renderer = Renderer::with_options(Backend::Gpu, &options).unwrap();
    frames_are_each_frame_alone(&renderer, "frames-gpu");
}

/// On the GPU a PNG frame (buffers kept for the next frame, f32 read back) has the bytes of
/// a PNG rendered alone (geometry released, packed to 8 bits by the shader). The twin: the
/// next frame's bytes differ.
#[test]
fn gpu_png_frames_are_the_png_rendered_alone() {
    let Some(gpu) = common::gpu() else { return };
    let options = glint::gpu::GpuOptions::adapter(Some(&gpu.info.name));
    let renderer = Renderer::with_options(Backend::Gpu, &options).unwrap();
    let d = common::Scratch::new("frames-png");
    let mut scene = Scene::load(path_scene(&d)).unwrap();
    render_frames(
        &mut scene,
        &renderer,
        &small(),
        (&d.join("f_{}.png"), "3..4".parse().unwrap(), false),
        &mut |_, _| {},
    )
    .unwrap();
    let original = Scene::load(d.join("path.toml")).unwrap();
    let mut s = original.clone();
    s.camera = s.camera_at(3.0).unwrap();
    Job::new(s, Output::file(d.join("alone.png")).unwrap())
        .options(small())
        .run(&renderer)
        .unwrap();
    let read = |n: &str| std::fs::read(d.join(n)).unwrap();
    assert_eq!(read("f_3.png"), read("alone.png"));
    assert_ne!(read("f_4.png"), read("alone.png"));
}

/// `--frames` through the command line: frames 0..=2 written, then `--resume` keeps the
/// files that exist (a stand-in's bytes stay) and writes the one removed.
#[test]
fn the_command_line_writes_frames_and_resumes() {
    let d = common::Scratch::new("frames-cli");
    let scene = path_scene(&d);
    let template = d.join("out").join("frame_{:04}.png");
    std::fs::create_dir_all(d.join("out")).unwrap();
    let run = |extra: &[&str]| {
        let mut c = common::glint_command();
        c.args([
            "render",
            "--backend",
            "cpu",
            "--size",
            "32x24",
            "--no-cache",
        ])
        .arg(&scene)
        .arg("-o")
        .arg(&template)
        .args(extra);
        common::status_and_text(&c.output().unwrap())
    };
    let (code, text) = run(&["--frames", "0..2"]);
    assert_eq!(code, Some(0), "{text}");
    assert!(text.contains("3 frames written, 0 kept"), "{text}");
    let f = |n: u32| d.join("out").join(format!("frame_{n:04}.png"));
    let frame1 = std::fs::read(f(1)).unwrap();
    std::fs::write(f(0), b"stand-in").unwrap();
    std::fs::remove_file(f(2)).unwrap();
    let (code, text) = run(&["--frames", "0..2", "--resume"]);
    assert_eq!(code, Some(0), "{text}");
    assert!(text.contains("1 frames written, 2 kept"), "{text}");
    assert_eq!(std::fs::read(f(0)).unwrap(), b"stand-in");
    assert_eq!(std::fs::read(f(1)).unwrap(), frame1);
    assert!(f(2).exists());
    // The twin: without --resume the stand-in is rendered over.
    let (code, _) = run(&["--frames", "0"]);
    assert_eq!(code, Some(0));
    assert_ne!(std::fs::read(f(0)).unwrap(), b"stand-in");
    // A template without a place for the number is refused before any work.
    let mut c = common::glint_command();
    c.args(["render", "--backend", "cpu", "--frames", "0..1", "-o"])
        .arg(d.join("plain.png"))
        .arg(&scene);
    let (code, text) = common::status_and_text(&c.output().unwrap());
    assert_ne!(code, Some(0), "{text}");
    assert!(text.contains("needs {} or {:0N}"), "{text}");
    assert!(!d.join("plain.png").exists());
}

/// Keys out of order, out of range, unknown, or without a view are errors naming the
/// file, the line and the key.
#[test]
fn bad_keys_name_file_line_and_key() {
    let base = "ambient = [0.1, 0.1, 0.1]\n[camera]\neye = [0.0, 0.0, 5.0]\n\
                look_at = [0.0, 0.0, 0.0]\nfov = 40.0\nwidth = 8\nheight = 6\n";
    let cases = [
        (
            "[[camera.keys]]\nframe = 5\n[[camera.keys]]\nframe = 5\n",
            "keys.toml:11: camera.keys[1].frame",
            "not after the previous key's frame, 5",
        ),
        (
            "[[camera.keys]]\nframe = -1\n",
            "keys.toml:9: camera.keys[0].frame",
            "outside 0..=1000000000",
        ),
        (
            "[[camera.keys]]\nframe = 1\nfov = 180.0\n",
            "keys.toml:10: camera.keys[0].fov",
            "",
        ),
        (
            "[[camera.keys]]\nframe = 1\neye = [0.0, 0.0, 0.0]\n",
            "camera.keys[0].look_at",
            "equals camera.eye",
        ),
        (
            "[[camera.keys]]\nframe = 1\nzoom = 2.0\n",
            "keys.toml:10",
            "zoom",
        ),
    ];
    for (keys, place, what) in cases {
        let e = Scene::parse(&format!("{base}{keys}"), Path::new("keys.toml"))
            .unwrap_err()
            .to_string();
        assert!(e.contains(place) && e.contains(what), "{keys}: {e}");
    }
    // The twin: the same keys in order load, and the path is what they say.
    let s = Scene::parse(
        &format!("{base}[[camera.keys]]\nframe = 5\n[[camera.keys]]\nframe = 6\nfov = 50.0\n"),
        Path::new("keys.toml"),
    )
    .unwrap();
    assert_eq!(s.camera_keys.len(), 2);
    assert_eq!(s.camera_at(5.5).unwrap().fov, 45.0);
    let _: FrameRange = "5..6".parse().unwrap();
}
