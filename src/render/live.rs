//! Frames of one scene under a moving camera, for interactive front ends (`glint view`).
//!
//! - **Built once.** The scene's buffers (the BVH included) are made once; moving the
//!   camera rewrites the camera fields of the parameters and nothing else. A scene loaded
//!   again (its file saved) keeps the BVH where its primitives are unchanged
//!   ([`SceneBuffers::new_reusing`]), so a change of lights, materials, textures or camera
//!   costs no BVH.
//! - **Refinement.** On the CPU, a scene with N×N samples a pixel is refined one sample
//!   position per [`Live::step`], summed in `trace_pixel`'s order, so after N² steps the
//!   picture is `glint render`'s for that camera in every bit ([`crate::cpu::add_sample_f32`]);
//!   one sample a pixel is one step of the packet tracer. On a GPU, each step renders the
//!   whole frame, every sample at once, with the specialised kernel; a viewer on the same
//!   device has it traced straight into its texture with the scene kept on the device
//!   ([`Live::step_to_texture`]).
//! - **Camera moves** ([`Live::orbit`], [`Live::pan`], [`Live::zoom`], [`Live::fly`]) are
//!   computed in f64 and rounded to f32 once, so the camera they leave can be written to a
//!   scene file ([`Live::camera_toml`]) and renders the same there.

use std::time::Duration;
use web_time::Instant;

use glam::DVec3;

use super::{RenderError, Renderer, Tracer};
use crate::buffers::{SceneBuffers, Specialisation};
use crate::image::Image;
use crate::scene::{Camera, Scene};

/// What a new scene ([`Live::replace_scene`]) needed rebuilt.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Rebuilt {
    /// Only shading (lights, materials, textures, camera, settings): the BVH was kept.
    Shading,
    /// The primitives changed: a new BVH.
    Geometry,
}

/// One scene's frames under a moving camera, on a [`Renderer`].
pub struct Live {
    scene: Scene,
    home: Camera,
    width: u32,
    height: u32,
    buf: SceneBuffers,
    spec: Specialisation,
    /// The running sums of the sample positions taken so far (CPU refinement).
    acc: Vec<[f32; 4]>,
    /// Sample positions taken for the current camera.
    done: u32,
    /// The picture as it stands.
    image: Image,
    /// The time of the last step.
    last: Duration,
    /// The scene on the GPU, for [`Live::step_to_texture`]: made on its first call, and
    /// again after a new scene or size.
    resident: Option<crate::gpu::Resident>,
}

impl Live {
    /// The frames of `scene` at `width`×`height` from its own camera. Builds the buffers
    /// and the BVH; nothing is traced before the first [`Live::step`].
    pub fn new(scene: Scene, width: u32, height: u32) -> Live {
        let buf = SceneBuffers::new(&scene, width, height, scene.triangle);
        let spec = Specialisation::for_scene(&buf);
        Live {
            home: scene.camera.clone(),
            width,
            height,
            acc: Vec::new(),
            done: 0,
            image: Image::new(width, height, [0.0; 4]),
            last: Duration::ZERO,
            resident: None,
            scene,
            buf,
            spec,
        }
    }

    /// Sets the GPU kernel's division and square root for the frames to come.
    pub fn set_math(&mut self, math: crate::buffers::MathMode) {
        if self.spec.math != math {
            self.spec = self.spec.with_math(math);
            self.resident = None;
            self.restart();
        }
    }

    /// The scene as it stands (its camera the current one).
    pub fn scene(&self) -> &Scene {
        &self.scene
    }

    /// The frame's size.
    pub fn size(&self) -> (u32, u32) {
        (self.width, self.height)
    }

    /// Replaces the scene (a file saved again), keeping the current camera unless the new
    /// scene's own camera differs from the one the old scene was loaded with (then that
    /// one is taken, and becomes the camera R resets to). Keeps the BVH where the
    /// primitives are the same.
    pub fn replace_scene(&mut self, mut scene: Scene) -> Rebuilt {
        if scene.camera == self.home {
            let samples = scene.camera.samples;
            scene.camera = Camera {
                samples,
                ..self.scene.camera.clone()
            };
        } else {
            self.home = scene.camera.clone();
        }
        let placeholder = SceneBuffers::assemble(
            self.buf.params,
            Vec::new(),
            Vec::new(),
            Vec::new(),
            Vec::new(),
            scene.triangle,
            false,
        );
        let old = std::mem::replace(&mut self.buf, placeholder);
        let (buf, kept) =
            SceneBuffers::new_reusing(&scene, self.width, self.height, scene.triangle, old);
        self.buf = buf;
        self.resident = None;
        self.spec = Specialisation::for_scene(&self.buf).with_math(self.spec.math);
        self.scene = scene;
        self.restart();
        if kept {
            Rebuilt::Shading
        } else {
            Rebuilt::Geometry
        }
    }

    /// Sample positions taken for this camera, and how many make the full picture (the
    /// scene's `samples`²).
    pub fn samples(&self) -> (u32, u32) {
        (self.done, self.total())
    }

    fn total(&self) -> u32 {
        self.buf.params.samples.max(1).pow(2)
    }

    /// Whether the picture is the full one (`glint render`'s for this camera).
    pub fn converged(&self) -> bool {
        self.done >= self.total()
    }

    /// How long the last [`Live::step`] took.
    pub fn last_step(&self) -> Duration {
        self.last
    }

    /// Refines the picture: on the CPU the next sample position (or, with one sample a
    /// pixel, the whole frame), on a GPU the whole frame. Does nothing once converged.
    pub fn step(&mut self, renderer: &Renderer) -> Result<(), RenderError> {
        if self.converged() {
            return Ok(());
        }
        let t0 = Instant::now();
        let total = self.total();
        if let Some((gpu, kernel)) = renderer.tracer().kernel(self.spec)? {
            kernel.render_into(
                &gpu.device,
                &gpu.queue,
                &self.buf,
                self.spec,
                &mut self.image,
                &mut |_, _| {},
            )?;
            self.done = total;
            self.last = t0.elapsed();
            return Ok(());
        }
        match renderer.tracer() {
            Tracer::Gpu(_) | Tracer::GpuRq(_) => {} // traced above
            Tracer::CpuF64 => {
                self.image = crate::cpu::render_f64(&self.scene, &self.buf, self.spec);
                self.done = total;
            }
            Tracer::Cpu if total == 1 => {
                crate::cpu::render_f32_into(&self.buf, self.spec, &mut self.image);
                self.done = 1;
            }
            Tracer::Cpu => {
                if self.done == 0 {
                    self.acc = crate::cpu::samples_start(self.width, self.height);
                }
                crate::cpu::add_sample_f32(&self.buf, self.spec, self.done, &mut self.acc);
                self.done += 1;
                self.image.reshape(self.width, self.height);
                self.image.pixels = crate::cpu::samples_finish(&self.acc, self.done, total);
            }
        }
        self.last = t0.elapsed();
        Ok(())
    }

    /// Refines the picture into `texture`, where the renderer traces on a GPU: the whole
    /// frame, straight into the texture (`Rgba8Unorm`, the frame's size, `COPY_DST`, on the
    /// renderer's device), the scene kept on the device between frames so that a moved
    /// camera uploads only its parameters; then `true` ([`Live::image`] and
    /// [`Live::rgba8`] are not updated). Elsewhere [`Live::step`], and `false`: the caller
    /// uploads [`Live::rgba8`].
    pub fn step_to_texture(
        &mut self,
        renderer: &Renderer,
        texture: &wgpu::Texture,
    ) -> Result<bool, RenderError> {
        let Some(gpu) = renderer.tracer().gpu() else {
            self.step(renderer)?;
            return Ok(false);
        };
        if self.converged() {
            return Ok(true);
        }
        let t0 = Instant::now();
        if self.resident.is_none()
            && let Some((_, kernel)) = renderer.tracer().kernel(self.spec)?
        {
            self.resident = Some(kernel.resident(&gpu.device, &gpu.queue, &self.buf, self.spec)?);
        }
        let resident = self.resident.as_ref().expect("made above");
        resident.frame(&gpu.device, &gpu.queue, &self.buf.params, texture)?;
        self.done = self.total();
        self.last = t0.elapsed();
        Ok(true)
    }

    /// The picture as it stands, linear f32 with t (see [`Image`]).
    pub fn image(&self) -> &Image {
        &self.image
    }

    /// The picture as it stands in 8 bits, RGBA, row-major: once converged, the bytes
    /// `glint render`'s PNG holds for this camera.
    pub fn rgba8(&self) -> Vec<u8> {
        self.image
            .pixels
            .iter()
            .flat_map(|p| {
                let c = crate::shared::real::pack_rgba8(*p);
                c.to_le_bytes()
            })
            .collect()
    }

    /// The camera as it stands.
    pub fn camera(&self) -> &Camera {
        &self.scene.camera
    }

    /// Makes `cam` (its eye, look-at point and up; the field of view and samples kept)
    /// the camera and restarts the refinement. A camera whose eye is its look-at point, or
    /// whose up is along the view, is refused (the camera stays).
    pub fn set_camera(&mut self, eye: [f32; 3], look_at: [f32; 3], up: [f32; 3]) -> bool {
        if crate::scene::validate::view(eye, look_at, up).is_err() {
            return false;
        }
        self.scene.camera.eye = eye;
        self.scene.camera.look_at = look_at;
        self.scene.camera.up = up;
        self.buf
            .set_camera(&self.scene.camera, self.width, self.height);
        self.restart();
        true
    }

    /// Back to the scene's own camera.
    pub fn reset_camera(&mut self) {
        let c = self.home.clone();
        self.set_camera(c.eye, c.look_at, c.up);
    }

    /// The frame at another size: the camera kept, the refinement restarted.
    pub fn resize(&mut self, width: u32, height: u32) {
        self.width = width.max(1);
        self.height = height.max(1);
        self.resident = None;
        self.buf
            .set_camera(&self.scene.camera, self.width, self.height);
        self.restart();
    }

    fn restart(&mut self) {
        self.done = 0;
    }

    fn basis(&self) -> (DVec3, DVec3, DVec3, DVec3, DVec3) {
        let c = &self.scene.camera;
        let v = |a: [f32; 3]| DVec3::new(a[0] as f64, a[1] as f64, a[2] as f64);
        let (eye, at, up) = (v(c.eye), v(c.look_at), v(c.up));
        let forward = (at - eye).normalize();
        let right = forward.cross(up).normalize();
        let up2 = right.cross(forward);
        (eye, at, forward, right, up2)
    }

    fn set_f64(&mut self, eye: DVec3, at: DVec3) -> bool {
        let up = self.scene.camera.up;
        self.set_camera(eye.as_vec3().to_array(), at.as_vec3().to_array(), up)
    }

    /// Turns the eye around the look-at point: `yaw` degrees about the camera's up hint,
    /// `pitch` degrees about its right axis (kept short of the poles, where the view would
    /// lie along the up hint).
    pub fn orbit(&mut self, yaw: f64, pitch: f64) -> bool {
        let (eye, at, _, right, _) = self.basis();
        let c = &self.scene.camera;
        let up = DVec3::new(c.up[0] as f64, c.up[1] as f64, c.up[2] as f64).normalize();
        let offset = eye - at;
        let yawed = glam::DQuat::from_axis_angle(up, -yaw.to_radians()) * offset;
        let right = glam::DQuat::from_axis_angle(up, -yaw.to_radians()) * right;
        let pitched = glam::DQuat::from_axis_angle(right, -pitch.to_radians()) * yawed;
        let d = pitched.normalize().dot(up).abs();
        let new = if d < 0.995 { pitched } else { yawed };
        self.set_f64(at + new, at)
    }

    /// Moves eye and look-at point together across the view: `dx`, `dy` in units of the
    /// distance between them (right and up on the screen).
    pub fn pan(&mut self, dx: f64, dy: f64) -> bool {
        let (eye, at, _, right, up) = self.basis();
        let d = (at - eye).length();
        let shift = right * (-dx * d) + up * (dy * d);
        self.set_f64(eye + shift, at + shift)
    }

    /// Moves the eye towards the look-at point (`factor` < 1) or away (> 1).
    pub fn zoom(&mut self, factor: f64) -> bool {
        let (eye, at, ..) = self.basis();
        self.set_f64(at + (eye - at) * factor, at)
    }

    /// Flies eye and look-at point together: `forward`, `right`, `up` in units of the
    /// distance between them.
    pub fn fly(&mut self, forward: f64, right: f64, up: f64) -> bool {
        let (eye, at, f, r, u) = self.basis();
        let d = (at - eye).length();
        let shift = (f * forward + r * right + u * up) * d;
        self.set_f64(eye + shift, at + shift)
    }

    /// The camera as a scene file's `[camera]` table, every number as it is (f32, written
    /// to round-trip): paste it into the scene to render this view.
    pub fn camera_toml(&self) -> String {
        let c = &self.scene.camera;
        let v = |a: [f32; 3]| format!("[{:?}, {:?}, {:?}]", a[0], a[1], a[2]);
        format!(
            "[camera]\neye = {}\nlook_at = {}\nup = {}\nfov = {:?}\nwidth = {}\nheight = {}\nsamples = {}\n",
            v(c.eye),
            v(c.look_at),
            v(c.up),
            c.fov,
            c.width,
            c.height,
            c.samples
        )
    }
}
