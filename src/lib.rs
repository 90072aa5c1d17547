//! glint: a ray tracer for spheres and triangles whose main path is a WGSL compute shader
//! (`shaders/trace.wgsl`) run through wgpu, with a CPU mirror of that shader
//! ([`cpu::trace`]) that agrees with it bit for bit on Mesa lavapipe, and an f64 path that is
//! the ground truth for error.
//!
//! ```no_run
//! let scene = glint::scene::Scene::load("scenes/sphere.toml")?;
//! let buf = glint::buffers::SceneBuffers::new(&scene, 640, 480, scene.triangle);
//! let image = glint::cpu::render_f32(&buf, glint::buffers::Specialisation::for_scene(&buf));
//! image.save_png("sphere.png".as_ref())?;
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

pub mod bench;
pub mod buffers;
pub mod bvh;
pub mod compare;
pub mod cpu;
pub mod fuzzing;
pub mod gpu;
pub mod image;
pub mod oracle;
pub mod scene;
pub mod stages;
