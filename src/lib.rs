//! glint: a ray tracer for spheres and triangles whose main path is a WGSL compute shader
//! (`shaders/trace.wgsl`) run through wgpu, with a CPU mirror of that shader
//! ([`cpu::trace`]) that agrees with it bit for bit on Mesa lavapipe, and an f64 path that is
//! the ground truth for error.
//!
//! ```no_run
//! use glint::{Backend, RenderOptions, Renderer, scene::Scene};
//! let scene = Scene::load("scenes/sphere.toml")?;
//! let image = Renderer::new(Backend::Auto)?.render(&scene, &RenderOptions::default())?;
//! image.save("sphere.png".as_ref())?;
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```
//!
//! [`Renderer::with_device`] renders on a wgpu device of the caller's own; `examples/` has
//! both. The lower floors ([`buffers`], [`cpu`], [`gpu`]) stay public for the tests and for
//! cross-checking users.
#![deny(missing_docs)]

pub mod bench;
pub mod buffers;
pub mod bvh;
pub mod cache;
pub mod compare;
pub mod cpu;
#[cfg(feature = "testing")]
pub mod fuzzing;
pub mod gpu;
pub mod image;
#[cfg(feature = "testing")]
pub mod oracle;
pub mod render;
pub mod scene;
pub mod shared;
pub mod stages;
pub mod traversal_stats;
pub mod two_level;

pub use render::{
    Backend, RenderError, RenderOptions, Renderer, Tracer, TracerKind, UnknownBackend,
};
