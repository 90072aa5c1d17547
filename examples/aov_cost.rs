//! What AOVs cost on the CPU tracer: the `trace` stage of a render to memory, colour only
//! against colour with AOVs, interleaved, median of `--runs` each, one line a scene.
//!
//! `cargo run --release --example aov_cost -- [--runs 15] [--size 1024x768]
//! [--aov depth,normal,prim_id,object_id,material_id] SCENE...`

use std::time::Duration;

use anyhow::{Context, Result, bail};
use glint::render::{Aov, Job, Output};
use glint::scene::Scene;
use glint::{Backend, RenderOptions, Renderer};

fn median(mut v: Vec<Duration>) -> f64 {
    v.sort();
    v[v.len() / 2].as_secs_f64() * 1e3
}

fn trace_stage(renderer: &Renderer, scene: &Scene, options: &RenderOptions) -> Result<Duration> {
    let report = Job::borrowed(scene, Output::Memory)
        .options(options.clone())
        .run(renderer)?;
    Ok(report.frame)
}

fn main() -> Result<()> {
    let mut args = std::env::args().skip(1);
    let (mut runs, mut size) = (15usize, (1024u32, 768u32));
    let mut aovs = Aov::parse_list("depth,normal,prim_id,object_id,material_id")?;
    let mut scenes = Vec::new();
    while let Some(a) = args.next() {
        match a.as_str() {
            "--runs" => runs = args.next().context("--runs N")?.parse()?,
            "--size" => {
                let s = args.next().context("--size WxH")?;
                let (w, h) = s.split_once('x').context("--size WxH")?;
                size = (w.parse()?, h.parse()?);
            }
            "--aov" => aovs = Aov::parse_list(&args.next().context("--aov LIST")?)?,
            s if s.starts_with("--") => bail!("unknown option {s}"),
            s => scenes.push(s.to_string()),
        }
    }
    if scenes.is_empty() {
        scenes.push("scenes/bb8.toml".into());
    }
    let renderer = Renderer::new(Backend::Cpu)?;
    let colour = RenderOptions {
        size: Some(size),
        ..RenderOptions::default()
    };
    let with = RenderOptions {
        aovs: aovs.clone(),
        ..colour.clone()
    };
    println!(
        "| scene | colour only | colour + {} | ratio |",
        aovs.iter().map(|a| a.name()).collect::<Vec<_>>().join(", ")
    );
    println!("|---|---|---|---|");
    for path in &scenes {
        let scene = Scene::load(path).with_context(|| path.clone())?;
        trace_stage(&renderer, &scene, &colour)?;
        trace_stage(&renderer, &scene, &with)?;
        let (mut a, mut b) = (Vec::new(), Vec::new());
        for _ in 0..runs {
            a.push(trace_stage(&renderer, &scene, &colour)?);
            b.push(trace_stage(&renderer, &scene, &with)?);
        }
        let (a, b) = (median(a), median(b));
        println!("| {path} | {a:.1} ms | {b:.1} ms | {:.2} |", b / a);
    }
    Ok(())
}
