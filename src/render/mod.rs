//! The library's pipeline: what `glint render` and `glint compare` do, for any caller.
//!
//! - [`Renderer`]: a backend resolved to a tracer (the `auto` policy), holding its device.
//! - [`Job`]: one frame of a scene on a renderer, streamed into an [`Output`] (a PNG written
//!   band by band, an EXR, or memory), with `auto`'s fallback to the CPU when the scene is
//!   too large for the GPU, the cache's lifecycle, typed [`Warning`]s and [`Note`]s as they
//!   happen, progress, and the timings in a [`RenderReport`].
//! - [`Live`]: frames of one scene under a moving camera, refined while it is still, for
//!   interactive viewers (`glint view`).
//! - [`render_frames`]: the frames of a scene's camera path, each to its own file, the
//!   scene's buffers made once.
//! - [`Aov`]: the AOVs (depth, normals, albedo, ids, ...) a job writes beside the colour
//!   ([`RenderOptions::aovs`]), as an [`AovImage`].
//! - [`compare()`]: the GPU against its CPU mirror and both against the f64 ground truth, as
//!   a [`CompareReport`].
//!
//! ```no_run
//! use glint::render::{Job, Output};
//! use glint::{Backend, Renderer, scene::Scene};
//! let renderer = Renderer::new(Backend::Auto)?;
//! let scene = Scene::load("scenes/bb8.toml")?;
//! let report = Job::new(scene, Output::file("bb8.png")?)
//!     .on_event(|e| eprintln!("{e}"))
//!     .run(&renderer)?;
//! println!("{report}");
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

mod aov;
mod compare;
mod frames;
mod job;
mod live;
mod memory;
mod output;
mod renderer;

pub use aov::{Aov, AovError, AovImage, IdMap, UnknownAov};
pub use compare::{AovDiff, CompareReport, RayQueryResult, compare, diff_aov};
pub use frames::{FrameDone, FrameRange, FramesError, check_template, frame_path, render_frames};
pub use job::{Event, Job, Note, RenderReport, Warning};
pub use live::{Live, Rebuilt};
pub use memory::check_memory;
pub use output::Output;
pub use renderer::{
    Backend, RenderError, RenderOptions, Renderer, Tracer, TracerKind, UnknownBackend,
};
