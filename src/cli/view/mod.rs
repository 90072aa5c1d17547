//! `glint view`: a window on a scene. The library's [`Live`] does the work (the buffers
//! built once, the camera moved, the picture refined, the scene replaced on reload); this
//! module only opens the window (winit), presents the picture through a wgpu surface,
//! turns the mouse and keys into camera moves and watches the scene's files (notify).
//!
//! The picture goes to the screen through a texture of the viewer's own: written by the
//! shader on a GPU tracer (the scene kept on the device), uploaded from the CPU tracer's
//! 8-bit frame otherwise, then drawn over the surface by a full-screen triangle that copies
//! texels (`textureLoad`, no filtering), so the window shows exactly the bytes `glint
//! render` writes. `--screenshot` reads that texture back (surfaces need not allow reads).

use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::time::{Duration, Instant};

use anyhow::{Context, Result, anyhow, bail};
use glint::render::{Job, Live, Output, Rebuilt};
use glint::scene::{LoadOptions, Scene};
use glint::{Backend, RenderOptions, Renderer};
use winit::application::ApplicationHandler;
use winit::event::{ElementState, MouseButton, MouseScrollDelta, WindowEvent};
use winit::event_loop::{ActiveEventLoop, ControlFlow, EventLoop};
use winit::keyboard::{KeyCode, PhysicalKey};
use winit::window::{Window, WindowId};

mod watch;

use watch::Watch;

/// What `glint view` was asked.
pub struct Options {
    /// The scene file.
    pub scene: PathBuf,
    /// The tracer.
    pub backend: Backend,
    /// The window's size (default: the scene camera's).
    pub size: Option<(u32, u32)>,
    /// Samples a pixel side (default: the scene's).
    pub samples: Option<u32>,
    /// Draw this many frames, then exit.
    pub frames: Option<u32>,
    /// Write the last frame presented here.
    pub screenshot: Option<PathBuf>,
    /// The GPU kernel's division and square root.
    pub math: glint::buffers::Math,
    /// The adapter, by part of its name.
    pub adapter: Option<String>,
    /// How the scene is read.
    pub load: LoadOptions,
}

/// The keys, as H prints them.
const KEYS: &str = "glint view keys:
  left button drag   orbit around the look-at point
  right button drag  pan
  wheel              zoom
  W/S  A/D  Q/E      fly forward/back, left/right, down/up
  R                  reset to the scene's camera
  P                  save the view as PNG (full quality)
  X                  save the view as EXR (full quality)
  C                  print the camera as a [camera] table
  H                  print this list
  Esc                quit";

/// Degrees of orbit per pixel dragged.
const ORBIT_PER_PIXEL: f64 = 0.25;
/// Fly step, in units of the eye's distance to the look-at point.
const FLY_STEP: f64 = 0.05;
/// Zoom factor per wheel line.
const ZOOM_PER_LINE: f64 = 0.9;
/// Quiet time after a file event before the scene is read again (editors write in steps).
const SETTLE: Duration = Duration::from_millis(120);

/// What the watcher tells the event loop.
enum UserEvent {
    /// A file the scene reads changed.
    Changed,
}

/// `message` without the source location that winit's `OsError` prints ("os error at
/// FILE:LINE: "), a path inside winit's own sources that tells a user nothing.
fn without_source_location(message: &str) -> String {
    match message.find("os error at ") {
        Some(i) => match message[i..].find(": ") {
            Some(j) => format!("{}{}", &message[..i], &message[i + j + 2..]),
            None => message.to_owned(),
        },
        None => message.to_owned(),
    }
}

/// Opens the window and runs until it is closed (or `--frames` are drawn).
pub fn run(opts: Options) -> Result<()> {
    let scene = load(&opts)?;
    for w in &scene.warnings {
        eprintln!("warning: {w}");
    }
    // The window is X11's on Linux and the BSDs (the build's one windowing backend there).
    if cfg!(all(unix, not(target_os = "macos")))
        && std::env::var_os("DISPLAY").is_none_or(|d| d.is_empty())
    {
        bail!(
            "glint view needs an X11 display and DISPLAY is not set (a Wayland desktop \
             provides one through XWayland; without a screen, run it under Xvfb: \
             xvfb-run glint view ...)"
        );
    }
    let event_loop = EventLoop::<UserEvent>::with_user_event()
        .build()
        .map_err(|e| {
            anyhow!(
                "cannot open a window on display {:?}: {} (is an X server running there? \
                 without a screen, run it under Xvfb: xvfb-run glint view ...)",
                std::env::var("DISPLAY").unwrap_or_default(),
                without_source_location(&e.to_string())
            )
        })?;
    let proxy = event_loop.create_proxy();
    let watch = Watch::new(proxy)?;
    let size = opts.size.unwrap_or(scene.size());
    let mut app = App {
        live: Live::new(scene, size.0, size.1),
        opts,
        watch,
        view: None,
        fatal: None,
        frames: 0,
        error: None,
        drag: None,
        cursor: (0.0, 0.0),
        reload_at: None,
        saved: 0,
    };
    app.live.set_math(glint::buffers::MathMode {
        math: app.opts.math,
        inexact_driver: false,
    });
    app.watch.follow(&app.live.scene().inputs);
    event_loop
        .run_app(&mut app)
        .map_err(|e| anyhow!("the window's event loop failed: {e}"))?;
    match app.fatal {
        Some(e) => Err(e),
        None => Ok(()),
    }
}

/// The scene as the options say (samples overridden).
fn load(opts: &Options) -> Result<Scene> {
    let mut scene = Scene::load_with(&opts.scene, &opts.load)?;
    if let Some(n) = opts.samples {
        scene.camera.samples = n;
    }
    Ok(scene)
}

/// The window, its surface and the texture drawn onto it.
struct View {
    window: Arc<Window>,
    surface: wgpu::Surface<'static>,
    config: wgpu::SurfaceConfiguration,
    device: wgpu::Device,
    queue: wgpu::Queue,
    renderer: Renderer,
    blit: wgpu::RenderPipeline,
    layout: wgpu::BindGroupLayout,
    texture: wgpu::Texture,
    bind: wgpu::BindGroup,
    name: String,
}

struct App {
    live: Live,
    opts: Options,
    watch: Watch,
    view: Option<View>,
    /// Why the viewer stopped, when it could not go on.
    fatal: Option<anyhow::Error>,
    /// Frames presented.
    frames: u32,
    /// The last reload's error, shown in the title until a reload succeeds.
    error: Option<String>,
    /// The button held and where the drag last was.
    drag: Option<MouseButton>,
    cursor: (f64, f64),
    /// When to read the scene again (files changed).
    reload_at: Option<Instant>,
    /// Images saved with P or X.
    saved: u32,
}

impl ApplicationHandler<UserEvent> for App {
    fn resumed(&mut self, event_loop: &ActiveEventLoop) {
        if self.view.is_some() {
            return;
        }
        match View::open(event_loop, &self.opts, self.live.size()) {
            Ok(v) => {
                eprintln!("glint view: {} ({})", self.opts.scene.display(), v.name);
                if let Some(note) = v.renderer.note() {
                    eprintln!("{note}");
                }
                v.window.request_redraw();
                self.view = Some(v);
            }
            Err(e) => {
                self.fatal = Some(e);
                event_loop.exit();
            }
        }
    }

    fn user_event(&mut self, _: &ActiveEventLoop, event: UserEvent) {
        match event {
            UserEvent::Changed => self.reload_at = Some(Instant::now() + SETTLE),
        }
    }

    fn about_to_wait(&mut self, event_loop: &ActiveEventLoop) {
        if let Some(at) = self.reload_at {
            if Instant::now() >= at {
                self.reload_at = None;
                self.reload();
            } else {
                event_loop.set_control_flow(ControlFlow::WaitUntil(at));
                return;
            }
        }
        let more_frames = self.opts.frames.is_some_and(|n| self.frames < n);
        if let Some(v) = &self.view
            && (!self.live.converged() || more_frames)
        {
            v.window.request_redraw();
        }
        event_loop.set_control_flow(ControlFlow::Wait);
    }

    fn window_event(&mut self, event_loop: &ActiveEventLoop, _: WindowId, event: WindowEvent) {
        match event {
            // The close button (a window manager's WM_DELETE_WINDOW), or the window destroyed
            // under the viewer: either ends it with exit status 0.
            WindowEvent::CloseRequested | WindowEvent::Destroyed => event_loop.exit(),
            WindowEvent::Resized(s) if s.width > 0 && s.height > 0 => {
                if let Some(v) = &mut self.view
                    && (s.width, s.height) != self.live.size()
                {
                    v.resize(s.width, s.height);
                    self.live.resize(s.width, s.height);
                    v.window.request_redraw();
                }
            }
            WindowEvent::RedrawRequested => {
                if let Err(e) = self.redraw(event_loop) {
                    self.fatal = Some(e);
                    event_loop.exit();
                }
            }
            WindowEvent::MouseInput { state, button, .. } => {
                self.drag = (state == ElementState::Pressed).then_some(button);
            }
            WindowEvent::CursorMoved { position, .. } => {
                let (dx, dy) = (position.x - self.cursor.0, position.y - self.cursor.1);
                self.cursor = (position.x, position.y);
                let h = self.live.size().1 as f64;
                let moved = match self.drag {
                    Some(MouseButton::Left) => {
                        self.live.orbit(dx * ORBIT_PER_PIXEL, dy * ORBIT_PER_PIXEL)
                    }
                    Some(MouseButton::Right) => self.live.pan(dx / h, dy / h),
                    _ => false,
                };
                if moved {
                    self.request_redraw();
                }
            }
            WindowEvent::MouseWheel { delta, .. } => {
                let lines = match delta {
                    MouseScrollDelta::LineDelta(_, y) => y as f64,
                    MouseScrollDelta::PixelDelta(p) => p.y / 40.0,
                };
                if self.live.zoom(ZOOM_PER_LINE.powf(lines)) {
                    self.request_redraw();
                }
            }
            // Synthetic presses (winit's, for keys held when the window gains focus) are
            // not the user's: a key pressed just as the window was focused came twice.
            WindowEvent::KeyboardInput {
                event,
                is_synthetic: false,
                ..
            } if event.state == ElementState::Pressed => {
                if let PhysicalKey::Code(code) = event.physical_key {
                    self.key(event_loop, code);
                }
            }
            _ => {}
        }
    }
}

impl App {
    fn request_redraw(&self) {
        if let Some(v) = &self.view {
            v.window.request_redraw();
        }
    }

    /// One key press.
    fn key(&mut self, event_loop: &ActiveEventLoop, code: KeyCode) {
        let moved = match code {
            KeyCode::KeyW => self.live.fly(FLY_STEP, 0.0, 0.0),
            KeyCode::KeyS => self.live.fly(-FLY_STEP, 0.0, 0.0),
            KeyCode::KeyD => self.live.fly(0.0, FLY_STEP, 0.0),
            KeyCode::KeyA => self.live.fly(0.0, -FLY_STEP, 0.0),
            KeyCode::KeyE => self.live.fly(0.0, 0.0, FLY_STEP),
            KeyCode::KeyQ => self.live.fly(0.0, 0.0, -FLY_STEP),
            KeyCode::KeyR => {
                self.live.reset_camera();
                true
            }
            KeyCode::KeyP => {
                self.save("png");
                false
            }
            KeyCode::KeyX => {
                self.save("exr");
                false
            }
            KeyCode::KeyC => {
                print!("{}", self.live.camera_toml());
                false
            }
            KeyCode::KeyH => {
                println!("{KEYS}");
                false
            }
            KeyCode::Escape => {
                event_loop.exit();
                false
            }
            _ => false,
        };
        use std::io::Write;
        let _ = std::io::stdout().flush();
        if moved {
            self.request_redraw();
        }
    }

    /// Renders the current view at full quality into `<scene>-view-<n>.<ext>` in the
    /// current folder (the first free n), through the library's job, as `glint render`
    /// does.
    fn save(&mut self, ext: &str) {
        let Some(v) = &self.view else { return };
        let stem = self
            .opts
            .scene
            .file_stem()
            .map_or("glint".into(), |s| s.to_string_lossy().into_owned());
        let path = loop {
            self.saved += 1;
            let p = PathBuf::from(format!("{stem}-view-{}.{ext}", self.saved));
            if !p.exists() {
                break p;
            }
        };
        let result = Output::file(&path)
            .map_err(anyhow::Error::from)
            .and_then(|out| {
                Job::borrowed(self.live.scene(), out)
                    .options(RenderOptions {
                        size: Some(self.live.size()),
                        ..RenderOptions::default()
                    })
                    .run(&v.renderer)
                    .map_err(anyhow::Error::from)
            });
        match result {
            Ok(_) => println!("saved {}", path.display()),
            Err(e) => eprintln!("error: saving {}: {e:#}", path.display()),
        }
    }

    /// Reads the scene again: on success the new scene replaces the old (the BVH kept
    /// where the primitives are the same); on failure the last picture stays and the error
    /// is shown.
    fn reload(&mut self) {
        match load(&self.opts) {
            Ok(scene) => {
                for w in &scene.warnings {
                    eprintln!("warning: {w}");
                }
                self.watch.follow(&scene.inputs);
                let what = match self.live.replace_scene(scene) {
                    Rebuilt::Shading => "shading only, the BVH kept",
                    Rebuilt::Geometry => "new geometry, a new BVH",
                };
                eprintln!("reloaded {}: {what}", self.opts.scene.display());
                self.error = None;
            }
            Err(e) => {
                let line = format!("{e:#}");
                eprintln!("error: {line}");
                self.error = Some(line);
            }
        }
        self.update_title();
        self.request_redraw();
    }

    fn update_title(&self) {
        let Some(v) = &self.view else { return };
        let (done, total) = self.live.samples();
        let title = match &self.error {
            Some(e) => format!("glint view: {e}"),
            None => format!(
                "glint view: {} | {} | {:.1} ms | {done}/{total} samples",
                self.opts.scene.display(),
                v.name,
                self.live.last_step().as_secs_f64() * 1e3
            ),
        };
        v.window.set_title(&title);
    }

    /// Refines the picture by a step (when it is not yet full), draws it, and after the
    /// `--frames` asked for writes the screenshot and stops.
    fn redraw(&mut self, event_loop: &ActiveEventLoop) -> Result<()> {
        let Some(v) = &mut self.view else {
            return Ok(());
        };
        if !self.live.converged() {
            match self.live.step_to_texture(&v.renderer, &v.texture) {
                Ok(true) => {}
                Ok(false) => v.upload(&self.live)?,
                Err(e) => {
                    let line = format!("{e:#}");
                    eprintln!("error: {line}");
                    self.error = Some(line);
                }
            }
        }
        v.present()?;
        self.frames += 1;
        self.update_title();
        if let Some(n) = self.opts.frames
            && self.frames >= n
        {
            if let (Some(path), Some(v)) = (&self.opts.screenshot, &self.view) {
                v.screenshot(path)?;
                eprintln!("wrote {}", path.display());
            }
            event_loop.exit();
        }
        Ok(())
    }
}

/// The copy from the viewer's texture to the surface: one triangle over the screen, each
/// fragment the texel under it.
const BLIT: &str = include_str!("../../../shaders/blit.wgsl");

impl View {
    /// The window, a device that can present to it and trace on it, and the pipeline
    /// that draws the picture.
    fn open(event_loop: &ActiveEventLoop, opts: &Options, size: (u32, u32)) -> Result<View> {
        let window = Arc::new(
            event_loop
                .create_window(
                    Window::default_attributes()
                        .with_title("glint view")
                        .with_inner_size(winit::dpi::PhysicalSize::new(size.0, size.1))
                        .with_resizable(true),
                )
                .map_err(|e| anyhow!("cannot make a window: {e}"))?,
        );
        let instance = wgpu::Instance::new(wgpu::InstanceDescriptor {
            backends: wgpu::Backends::VULKAN,
            ..wgpu::InstanceDescriptor::new_without_display_handle()
        });
        let surface = instance
            .create_surface(window.clone())
            .map_err(|e| {
                anyhow!(
                    "cannot present to the window: no Vulkan adapter can ({e}; apt-get install mesa-vulkan-drivers libvulkan1)"
                )
            })?;
        let mut list: Vec<wgpu::Adapter> =
            pollster::block_on(instance.enumerate_adapters(wgpu::Backends::VULKAN))
                .into_iter()
                .filter(|a| a.is_surface_supported(&surface))
                .collect();
        glint::gpu::rank_adapters(&mut list);
        let wanted = opts.adapter.as_deref().map(str::to_lowercase);
        let adapter = list
            .into_iter()
            .find(|a| {
                wanted
                    .as_ref()
                    .is_none_or(|w| a.get_info().name.to_lowercase().contains(w))
            })
            .ok_or_else(|| match &opts.adapter {
                Some(name) => anyhow!("no Vulkan adapter named like {name:?} can present to the window"),
                None => anyhow!(
                    "no Vulkan adapter can present to the window (apt-get install mesa-vulkan-drivers libvulkan1)"
                ),
            })?;
        let gpu = glint::gpu::Gpu::from_adapters(
            vec![adapter.clone()],
            &crate::cli::env::gpu_options(None),
            Instant::now(),
        )?;
        let (device, queue) = (gpu.device.clone(), gpu.queue.clone());
        let adapter_name = gpu.info.name.clone();
        let renderer = Renderer::from_gpu(opts.backend, gpu)?;
        let name = match renderer.tracer().gpu() {
            None => format!("{}, shown on {adapter_name}", renderer.describe()),
            Some(_) => renderer.describe(),
        };
        let mut config = surface
            .get_default_config(&adapter, size.0, size.1)
            .ok_or_else(|| anyhow!("the adapter {adapter_name} cannot present to this window"))?;
        // Bytes in, bytes out: a format without sRGB encoding, so the window shows the PNG's
        // values.
        let caps = surface.get_capabilities(&adapter);
        if let Some(f) = caps.formats.iter().find(|f| !f.is_srgb()) {
            config.format = *f;
        }
        config.present_mode = wgpu::PresentMode::Fifo;
        surface.configure(&device, &config);
        let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("blit"),
            source: wgpu::ShaderSource::Wgsl(BLIT.into()),
        });
        let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("blit"),
            entries: &[wgpu::BindGroupLayoutEntry {
                binding: 0,
                visibility: wgpu::ShaderStages::FRAGMENT,
                ty: wgpu::BindingType::Texture {
                    sample_type: wgpu::TextureSampleType::Float { filterable: false },
                    view_dimension: wgpu::TextureViewDimension::D2,
                    multisampled: false,
                },
                count: None,
            }],
        });
        let pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("blit"),
            bind_group_layouts: &[Some(&layout)],
            immediate_size: 0,
        });
        let blit = device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
            label: Some("blit"),
            layout: Some(&pipeline_layout),
            vertex: wgpu::VertexState {
                module: &module,
                entry_point: Some("vs"),
                compilation_options: Default::default(),
                buffers: &[],
            },
            primitive: wgpu::PrimitiveState::default(),
            depth_stencil: None,
            multisample: wgpu::MultisampleState::default(),
            fragment: Some(wgpu::FragmentState {
                module: &module,
                entry_point: Some("fs"),
                compilation_options: Default::default(),
                targets: &[Some(config.format.into())],
            }),
            multiview_mask: None,
            cache: None,
        });
        let (texture, bind) = picture_texture(&device, &layout, size);
        Ok(View {
            window,
            surface,
            config,
            device,
            queue,
            renderer,
            blit,
            layout,
            texture,
            bind,
            name,
        })
    }

    /// The surface and the picture texture at a new size.
    fn resize(&mut self, width: u32, height: u32) {
        self.config.width = width;
        self.config.height = height;
        self.surface.configure(&self.device, &self.config);
        (self.texture, self.bind) = picture_texture(&self.device, &self.layout, (width, height));
    }

    /// The live picture into the texture.
    fn upload(&mut self, live: &Live) -> Result<()> {
        let (w, h) = live.size();
        if (self.texture.width(), self.texture.height()) != (w, h) {
            (self.texture, self.bind) = picture_texture(&self.device, &self.layout, (w, h));
        }
        self.queue.write_texture(
            wgpu::TexelCopyTextureInfo {
                texture: &self.texture,
                mip_level: 0,
                origin: wgpu::Origin3d::ZERO,
                aspect: wgpu::TextureAspect::All,
            },
            &live.rgba8(),
            wgpu::TexelCopyBufferLayout {
                offset: 0,
                bytes_per_row: Some(4 * w),
                rows_per_image: Some(h),
            },
            wgpu::Extent3d {
                width: w,
                height: h,
                depth_or_array_layers: 1,
            },
        );
        Ok(())
    }

    /// Draws the texture over the surface and presents it.
    fn present(&mut self) -> Result<()> {
        let frame = match self.surface.get_current_texture() {
            wgpu::CurrentSurfaceTexture::Success(t)
            | wgpu::CurrentSurfaceTexture::Suboptimal(t) => t,
            wgpu::CurrentSurfaceTexture::Timeout | wgpu::CurrentSurfaceTexture::Occluded => {
                return Ok(());
            }
            wgpu::CurrentSurfaceTexture::Outdated | wgpu::CurrentSurfaceTexture::Lost => {
                self.surface.configure(&self.device, &self.config);
                return Ok(());
            }
            wgpu::CurrentSurfaceTexture::Validation => bail!("the window's surface is invalid"),
        };
        let view = frame
            .texture
            .create_view(&wgpu::TextureViewDescriptor::default());
        let mut enc = self.device.create_command_encoder(&Default::default());
        {
            let mut pass = enc.begin_render_pass(&wgpu::RenderPassDescriptor {
                label: Some("blit"),
                color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                    view: &view,
                    depth_slice: None,
                    resolve_target: None,
                    ops: wgpu::Operations {
                        load: wgpu::LoadOp::Clear(wgpu::Color::BLACK),
                        store: wgpu::StoreOp::Store,
                    },
                })],
                depth_stencil_attachment: None,
                timestamp_writes: None,
                occlusion_query_set: None,
                multiview_mask: None,
            });
            pass.set_pipeline(&self.blit);
            pass.set_bind_group(0, &self.bind, &[]);
            pass.draw(0..3, 0..1);
        }
        self.queue.submit([enc.finish()]);
        self.window.pre_present_notify();
        self.queue.present(frame);
        Ok(())
    }

    /// The picture texture, as presented, to a PNG written as `glint render` writes one.
    fn screenshot(&self, path: &Path) -> Result<()> {
        let (w, h) = (self.texture.width(), self.texture.height());
        let row = (4 * w).div_ceil(wgpu::COPY_BYTES_PER_ROW_ALIGNMENT)
            * wgpu::COPY_BYTES_PER_ROW_ALIGNMENT;
        let buffer = self.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("screenshot"),
            size: row as u64 * h as u64,
            usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let mut enc = self.device.create_command_encoder(&Default::default());
        enc.copy_texture_to_buffer(
            wgpu::TexelCopyTextureInfo {
                texture: &self.texture,
                mip_level: 0,
                origin: wgpu::Origin3d::ZERO,
                aspect: wgpu::TextureAspect::All,
            },
            wgpu::TexelCopyBufferInfo {
                buffer: &buffer,
                layout: wgpu::TexelCopyBufferLayout {
                    offset: 0,
                    bytes_per_row: Some(row),
                    rows_per_image: Some(h),
                },
            },
            wgpu::Extent3d {
                width: w,
                height: h,
                depth_or_array_layers: 1,
            },
        );
        self.queue.submit([enc.finish()]);
        let slice = buffer.slice(..);
        let (tx, rx) = std::sync::mpsc::channel();
        slice.map_async(wgpu::MapMode::Read, move |r| {
            let _ = tx.send(r);
        });
        self.device
            .poll(wgpu::PollType::wait_indefinitely())
            .map_err(|e| anyhow!("reading the picture back: {e}"))?;
        rx.recv()
            .context("reading the picture back")?
            .map_err(|e| anyhow!("reading the picture back: {e}"))?;
        let data = slice
            .get_mapped_range()
            .map_err(|e| anyhow!("reading the picture back: {e}"))?;
        let mut pixels = Vec::with_capacity(w as usize * h as usize);
        for y in 0..h as usize {
            let r = &data[y * row as usize..y * row as usize + 4 * w as usize];
            pixels.extend(
                r.chunks_exact(4)
                    .map(|p| u32::from_le_bytes([p[0], p[1], p[2], p[3]])),
            );
        }
        let mut png = glint::image::PngStream::create(path, w, h)?;
        png.write_rgba8_rows(&pixels)?;
        png.finish()?;
        Ok(())
    }
}

/// The texture the picture is uploaded to (8-bit RGBA, no sRGB encoding), and its binding.
fn picture_texture(
    device: &wgpu::Device,
    layout: &wgpu::BindGroupLayout,
    (w, h): (u32, u32),
) -> (wgpu::Texture, wgpu::BindGroup) {
    let texture = device.create_texture(&wgpu::TextureDescriptor {
        label: Some("picture"),
        size: wgpu::Extent3d {
            width: w,
            height: h,
            depth_or_array_layers: 1,
        },
        mip_level_count: 1,
        sample_count: 1,
        dimension: wgpu::TextureDimension::D2,
        format: wgpu::TextureFormat::Rgba8Unorm,
        usage: wgpu::TextureUsages::TEXTURE_BINDING
            | wgpu::TextureUsages::COPY_DST
            | wgpu::TextureUsages::COPY_SRC,
        view_formats: &[],
    });
    let view = texture.create_view(&wgpu::TextureViewDescriptor::default());
    let bind = device.create_bind_group(&wgpu::BindGroupDescriptor {
        label: Some("picture"),
        layout,
        entries: &[wgpu::BindGroupEntry {
            binding: 0,
            resource: wgpu::BindingResource::TextureView(&view),
        }],
    });
    (texture, bind)
}
