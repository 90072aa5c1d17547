//! The library's pipeline (`glint::render::Job`): what `glint render` does, asked for by a
//! library user. Each output (memory, EXR, PNG) holds the image the tracer makes, in every
//! bit the format keeps; events come in order; `auto` falls back to the CPU where the GPU
//! cannot hold the scene, and says so.

mod common;

gpu_sentinel!();

use glint::buffers::{SceneBuffers, Specialisation};
use glint::gpu::{GpuError, GpuOptions};
use glint::image::{Image, to_u8};
use glint::render::{Event, Job, Note, Output};
use glint::{Backend, RenderError, RenderOptions, Renderer, TracerKind};

fn bits(img: &Image) -> Vec<u32> {
    img.pixels.iter().flatten().map(|v| v.to_bits()).collect()
}

fn small() -> RenderOptions {
    RenderOptions {
        size: Some((96, 72)),
        ..RenderOptions::default()
    }
}

/// The CPU mirror's own image of `name` at 96×72.
fn mirror(name: &str) -> Image {
    let scene = common::seed_scene(name);
    let buf = SceneBuffers::new(&scene, 96, 72, scene.triangle);
    glint::cpu::render_f32(&buf, Specialisation::for_scene(&buf))
}

/// A job to memory is the mirror's image in every bit; its report names the tracer, the
/// frame and the stages, and its row events end at the frame's height. The twin: another
/// scene's image is not equal to it.
#[test]
fn a_job_to_memory_is_the_mirrors_image() {
    let cpu = Renderer::new(Backend::Cpu).unwrap();
    let mut rows = Vec::new();
    let report = Job::new(common::seed_scene("bb8-shadows"), Output::Memory)
        .options(small())
        .on_event(|e| {
            if let Event::Rows { done, total } = e {
                rows.push((done, total));
            }
        })
        .run(&cpu)
        .unwrap();
    let img = report.image.as_ref().expect("a memory output's image");
    assert_eq!(bits(img), bits(&mirror("bb8-shadows")));
    assert_ne!(bits(img), bits(&mirror("bb8")), "the twin must differ");
    assert_eq!((report.width, report.height), (96, 72));
    assert_eq!(report.tracer, TracerKind::CpuF32);
    assert!(report.stages.iter().any(|(n, _)| *n == "trace"));
    assert_eq!(rows.last(), Some(&(72, 72)), "{rows:?}");
    assert!(rows.windows(2).all(|w| w[0].0 < w[1].0), "{rows:?}");
}

/// An EXR streamed row by row reads back equal to the memory image in every bit (t
/// included), and a PNG holds its 8-bit colours. The twins: a file of another scene is not
/// equal to it.
#[test]
fn files_hold_the_memory_image() {
    let cpu = Renderer::new(Backend::Cpu).unwrap();
    let d = common::Scratch::new("job-files");
    let run = |scene: &str, file: &str| {
        let path = d.join(file);
        Job::new(common::seed_scene(scene), Output::file(&path).unwrap())
            .options(small())
            .run(&cpu)
            .unwrap();
        Image::load(&path).unwrap()
    };
    let want = mirror("umbrella");
    assert_eq!(bits(&run("umbrella", "u.exr")), bits(&want));
    assert_ne!(bits(&run("sphere", "s.exr")), bits(&want));
    let u8s = |img: &Image| -> Vec<u8> {
        img.pixels
            .iter()
            .flat_map(|p| [to_u8(p[0]), to_u8(p[1]), to_u8(p[2])])
            .collect()
    };
    assert_eq!(u8s(&run("umbrella", "u.png")), u8s(&want));
    assert_ne!(u8s(&run("sphere", "s.png")), u8s(&want));
}

/// An output that is the scene file itself is refused before any work.
#[test]
fn the_scene_file_is_never_overwritten() {
    let d = common::Scratch::new("job-overwrite");
    let scene = d.join("s.exr");
    std::fs::copy("scenes/sphere.toml", &scene).unwrap();
    let mut s = common::seed_scene("sphere");
    s.path = scene.clone();
    let cpu = Renderer::new(Backend::Cpu).unwrap();
    let e = Job::new(s, Output::file(&scene).unwrap())
        .run(&cpu)
        .unwrap_err();
    assert!(matches!(e, RenderError::OverwritesScene(_)), "{e}");
    assert_eq!(
        std::fs::read(&scene).unwrap(),
        std::fs::read("scenes/sphere.toml").unwrap()
    );
}

/// A scene of 30,000 triangles (1.44 MB) on an adapter given a smaller GPU's 1 MB buffer
/// limit: `gpu` fails naming the buffer; `auto` on that adapter renders on the CPU with one
/// [`Note::Fallback`], and its image is the CPU's.
#[test]
fn auto_falls_back_to_the_cpu_when_the_gpu_cannot_hold_the_scene() {
    let Some(gpu) = common::gpu() else { return };
    let d = common::Scratch::new("job-fallback");
    let path = common::too_large_scene(&d);
    let scene = glint::scene::Scene::load(&path).unwrap();
    let options = GpuOptions {
        max_buffer_bytes: Some(1_000_000),
        ..GpuOptions::adapter(Some(&gpu.info.name))
    };
    let on_gpu = Renderer::with_options(Backend::Gpu, &options).unwrap();
    match Job::borrowed(&scene, Output::Memory).run(&on_gpu) {
        Err(RenderError::Gpu(GpuError::TooLarge { needed, limit, .. })) => {
            assert_eq!((needed, limit), (1_440_000, 1_000_000))
        }
        other => panic!("the GPU must refuse: {other:?}"),
    }
    let auto = Renderer::with_options(Backend::Auto, &options).unwrap();
    let mut notes = 0;
    let report = Job::borrowed(&scene, Output::Memory)
        .on_event(|e| notes += matches!(e, Event::Note(Note::Fallback(_))) as usize)
        .run(&auto)
        .unwrap();
    assert_eq!(notes, 1);
    assert!(
        matches!(report.notes[..], [Note::Fallback(_)]),
        "{:?}",
        report.notes
    );
    assert_eq!(report.tracer, TracerKind::CpuF32);
    let cpu = Renderer::new(Backend::Cpu).unwrap();
    let want = cpu.render(&scene, &RenderOptions::default()).unwrap();
    assert_eq!(bits(report.image.as_ref().unwrap()), bits(&want));
}

/// A scene edited in memory into one that cannot render (the eye on the look-at point)
/// is refused before any work with the file loader's key and message, where it used to
/// render a silent all-background frame; a size outside 1..=32768 is refused too. The
/// twin: the scene as loaded renders.
#[test]
fn a_job_validates_a_scene_edited_in_memory() {
    let cpu = Renderer::new(Backend::Cpu).unwrap();
    let good = common::seed_scene("bb8");
    let mut bad = good.clone();
    bad.camera.look_at = bad.camera.eye;
    match Job::borrowed(&bad, Output::Memory)
        .options(small())
        .run(&cpu)
    {
        Err(RenderError::Scene(e)) => {
            assert_eq!(e.key(), Some("camera.look_at"));
            assert!(
                e.to_string()
                    .ends_with("camera.look_at: equals camera.eye: no view direction"),
                "{e}"
            );
        }
        other => panic!("expected a scene error, got {other:?}"),
    }
    let zero = RenderOptions {
        size: Some((0, 72)),
        ..RenderOptions::default()
    };
    assert!(matches!(
        Job::borrowed(&good, Output::Memory).options(zero).run(&cpu),
        Err(RenderError::Size(0, 72))
    ));
    assert!(
        Job::borrowed(&good, Output::Memory)
            .options(small())
            .run(&cpu)
            .is_ok()
    );
}

/// A job cancelled from its own progress events (as another thread or Ctrl-C would) stops
/// at the next band with `Cancelled`, and its PNG leaves no file, whole or partial. The
/// twin: the same job with the flag never set writes the file.
#[test]
fn a_cancelled_job_stops_and_leaves_no_file() {
    use std::sync::Arc;
    use std::sync::atomic::{AtomicBool, Ordering};
    let cpu = Renderer::new(Backend::Cpu).unwrap();
    let dir = common::Scratch::new("job-cancel");
    let png = dir.join("cancelled.png");
    let tall = RenderOptions {
        size: Some((1024, 2048)), // 2 MiB bands: 16 of them
        ..RenderOptions::default()
    };
    let flag = Arc::new(AtomicBool::new(false));
    let (setter, mut bands) = (flag.clone(), 0);
    let r = Job::new(common::seed_scene("bb8"), Output::file(&png).unwrap())
        .options(tall.clone())
        .cancel_on(flag)
        .on_event(|e| {
            if let Event::Rows { .. } = e {
                bands += 1;
                setter.store(true, Ordering::Relaxed);
            }
        })
        .run(&cpu);
    assert!(matches!(r, Err(RenderError::Cancelled)), "{r:?}");
    assert_eq!(bands, 1, "one band traced after the flag was set");
    let left: Vec<_> = std::fs::read_dir(&*dir).unwrap().collect();
    assert!(left.is_empty(), "files left: {left:?}");
    let report = Job::new(common::seed_scene("bb8"), Output::file(&png).unwrap())
        .options(tall)
        .cancel_on(Arc::new(AtomicBool::new(false)))
        .run(&cpu)
        .unwrap();
    assert_eq!(report.height, 2048);
    assert!(png.is_file());
}
