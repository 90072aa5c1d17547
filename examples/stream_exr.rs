//! A library user's large render: a 16384×16384 EXR (4 GiB of f32 pixels) streamed to disk
//! row by row, with progress, in the memory of one band.
//!
//!     cargo run --release --example stream_exr -- [SCENE] [OUT.exr] [SIDE]
//!
//! Defaults: `scenes/bb8.toml`, `bb8-16k.exr`, 16384. The backend is `auto`: a real GPU
//! where there is one, else the CPU tracer; `glint diff` compares two such files bit for
//! bit.

use std::io::Write;
use std::time::Instant;

use glint::render::{Event, Job, Output};
use glint::scene::Scene;
use glint::{Backend, RenderOptions, Renderer};

fn main() -> anyhow::Result<()> {
    let mut args = std::env::args().skip(1);
    let scene = args.next().unwrap_or_else(|| "scenes/bb8.toml".into());
    let out = args.next().unwrap_or_else(|| "bb8-16k.exr".into());
    let side: u32 = args.next().map_or(Ok(16384), |s| s.parse())?;

    // The output is checked before the scene is read: its folder exists, a file can be made.
    let output = Output::file(&out)?;
    let scene = Scene::load(&scene)?;
    let renderer = Renderer::new(Backend::Auto)?;
    let start = Instant::now();
    let mut shown = 0;
    let report = Job::new(scene, output)
        .options(RenderOptions {
            size: Some((side, side)),
            ..RenderOptions::default()
        })
        .on_event(|e| match e {
            Event::Rows { done, total } => {
                let percent = done as u64 * 100 / total as u64;
                if percent > shown || done == total {
                    shown = percent;
                    eprint!(
                        "\r{done}/{total} rows ({percent} %), {:.1} s",
                        start.elapsed().as_secs_f64()
                    );
                    let _ = std::io::stderr().flush();
                }
            }
            Event::Cache(_) => {}
            e => eprintln!("{e}"),
        })
        .run(&renderer)?;
    eprintln!();
    println!("{report}");
    Ok(())
}
