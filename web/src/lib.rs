//! glint in the browser: the page (`web/index.html`, `web/app.js`) asks, this crate works.
//!
//! - [`render_cpu`]: the CPU tracer compiled to wasm, single-threaded (rayon runs on the
//!   page's thread where the browser gives no threads), through the library's own
//!   [`glint::Renderer`]: the same IEEE operations as a native `glint render --backend cpu`,
//!   so the same bytes.
//! - [`GpuRenderer`]: the WGSL kernel on WebGPU (wgpu's WebGPU backend), specialised per
//!   scene as natively ([`glint::buffers::Specialisation::for_scene`]), the frame packed
//!   to 8 bits by the shader and read back asynchronously.
//! - [`Files`] and [`needed_files`]: a scene's meshes, MTLs and textures come from the page,
//!   which fetches them by URL; the scene is parsed with a reader over what it has, and
//!   what is missing is asked for by name.
//! - [`compare_rgba8`]: the counts the page's verdict shows, and a difference map.
//! - [`start`]: panics reach the browser's console with their message.
//!
//! Assumption: a frame fits one WebGPU storage buffer (`4 × width × height` bytes under the
//! device's `maxStorageBufferBindingSize`); a larger one is refused with the limit named.
//!
//! The crate is the page's: it is built for `wasm32-unknown-unknown` only (by
//! `web/build.sh`), and is empty elsewhere, where the browser's objects it holds do not exist.
#![cfg(target_arch = "wasm32")]

use std::cell::RefCell;
use std::collections::HashMap;
use std::path::{Path, PathBuf};

use glint::buffers::{SceneBuffers, Specialisation};
use glint::gpu::Gpu;
use glint::scene::{ReadError, Scene};
use glint::{Backend, RenderOptions, Renderer};
use wasm_bindgen::prelude::*;

#[wasm_bindgen]
extern "C" {
    #[wasm_bindgen(js_namespace = console, js_name = error)]
    fn console_error(message: &str);
}

/// Runs when the module is instantiated: a panic (a defect; bad input is an `Err`) writes
/// its message, file and line to the console before the wasm traps, which alone would say
/// only "unreachable".
#[wasm_bindgen(start)]
pub fn start() {
    std::panic::set_hook(Box::new(|info| console_error(&format!("glint: {info}"))));
}

/// Files a scene names (meshes, MTLs, textures), by the path the scene resolves them to
/// (relative to the page, as the scene's own path is).
#[wasm_bindgen]
#[derive(Default)]
pub struct Files {
    by_path: HashMap<PathBuf, Vec<u8>>,
}

#[wasm_bindgen]
impl Files {
    /// No files.
    #[wasm_bindgen(constructor)]
    pub fn new() -> Files {
        Files::default()
    }

    /// Adds (or replaces) the file at `path`.
    pub fn add(&mut self, path: &str, bytes: Vec<u8>) {
        self.by_path.insert(normal(Path::new(path)), bytes);
    }

    /// Whether `path` is held.
    pub fn has(&self, path: &str) -> bool {
        self.by_path.contains_key(&normal(Path::new(path)))
    }
}

/// `path` with `.` dropped and `dir/..` folded, as a URL resolves it.
fn normal(path: &Path) -> PathBuf {
    let mut out = PathBuf::new();
    for c in path.components() {
        match c {
            std::path::Component::CurDir => {}
            std::path::Component::ParentDir if out.file_name().is_some() => {
                out.pop();
            }
            c => out.push(c),
        }
    }
    out
}

/// Parses `toml` (named `path` in errors; its meshes resolved next to it) with `files` as
/// the only files there are; the paths it asked for and `files` lacked are listed too.
fn parse(toml: &str, path: &str, files: &Files) -> (Result<Scene, String>, Vec<String>) {
    let missing = RefCell::new(Vec::new());
    let read = |p: &Path| -> Result<Vec<u8>, ReadError> {
        let p = normal(p);
        match files.by_path.get(&p) {
            Some(bytes) => Ok(bytes.clone()),
            None => {
                let name = p.to_string_lossy().replace('\\', "/");
                missing.borrow_mut().push(name.clone());
                Err(ReadError::Other(format!(
                    "{name} is not loaded in the page"
                )))
            }
        }
    };
    let scene = Scene::parse_with(toml, Path::new(path), &read).map_err(|e| e.to_string());
    (scene, missing.into_inner())
}

/// The files the scene `toml` (at `path`) names that `files` lacks, so far as parsing can
/// tell: an OBJ's MTL, and the MTL's textures, are found only once the OBJ is there, so
/// the page asks again after fetching until the list is empty.
#[wasm_bindgen]
pub fn needed_files(toml: &str, path: &str, files: &Files) -> Vec<String> {
    parse(toml, path, files).1
}

/// A rendered frame: `rgba` holds the 8-bit values `glint render` writes to its PNG, row
/// by row from the top, alpha 255.
#[wasm_bindgen(getter_with_clone)]
pub struct Rendered {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// RGBA, 4 bytes a pixel.
    pub rgba: Vec<u8>,
    /// Milliseconds the render took (scene parse and set-up included; for the GPU, the
    /// pipeline's compile too).
    pub ms: f64,
}

/// Renders `toml` (at `path`) with the CPU tracer.
#[wasm_bindgen]
pub fn render_cpu(toml: &str, path: &str, files: &Files) -> Result<Rendered, JsError> {
    let t0 = web_time::Instant::now();
    let scene = parse(toml, path, files).0.map_err(|e| JsError::new(&e))?;
    let renderer = Renderer::new(Backend::Cpu).map_err(|e| JsError::new(&e.to_string()))?;
    let image = renderer
        .render(&scene, &RenderOptions::default())
        .map_err(|e| JsError::new(&e.to_string()))?;
    let rgba = image
        .to_rgb8()
        .chunks_exact(3)
        .flat_map(|c| [c[0], c[1], c[2], 255])
        .collect();
    Ok(Rendered {
        width: image.width,
        height: image.height,
        rgba,
        ms: t0.elapsed().as_secs_f64() * 1e3,
    })
}

/// The GPU tracer on the browser's WebGPU device.
#[wasm_bindgen]
pub struct GpuRenderer {
    gpu: Gpu,
}

#[wasm_bindgen]
impl GpuRenderer {
    /// Opens the browser's WebGPU adapter (the default one) with all its limits; an error
    /// where the browser has no WebGPU.
    pub async fn open() -> Result<GpuRenderer, JsError> {
        let instance = wgpu::Instance::new(wgpu::InstanceDescriptor {
            backends: wgpu::Backends::BROWSER_WEBGPU,
            ..wgpu::InstanceDescriptor::new_without_display_handle()
        });
        let adapter = instance
            .request_adapter(&wgpu::RequestAdapterOptions::default())
            .await
            .map_err(|e| JsError::new(&format!("this browser offers no WebGPU adapter ({e})")))?;
        let info = adapter.get_info();
        let offered = adapter.limits().max_storage_buffers_per_shader_stage;
        if offered < glint::gpu::RENDER_STORAGE_BUFFERS {
            return Err(JsError::new(&format!(
                "this WebGPU adapter offers {offered} storage buffers per shader stage and \
                 glint's kernel binds {}",
                glint::gpu::RENDER_STORAGE_BUFFERS
            )));
        }
        let (device, queue) = adapter
            .request_device(&wgpu::DeviceDescriptor {
                label: Some("glint"),
                required_limits: adapter.limits(),
                ..Default::default()
            })
            .await
            .map_err(|e| JsError::new(&format!("cannot open the WebGPU device: {e}")))?;
        let gpu =
            Gpu::from_device(info, device, queue).map_err(|e| JsError::new(&e.to_string()))?;
        Ok(GpuRenderer { gpu })
    }

    /// What the adapter says of itself.
    pub fn describe(&self) -> String {
        let i = &self.gpu.info;
        let what = [i.name.as_str(), i.driver.as_str(), i.driver_info.as_str()]
            .into_iter()
            .filter(|s| !s.is_empty())
            .collect::<Vec<_>>()
            .join(", ");
        if what.is_empty() {
            "WebGPU".to_string()
        } else {
            format!("WebGPU: {what}")
        }
    }

    /// Renders `toml` (at `path`) with the WGSL kernel.
    pub async fn render(&self, toml: &str, path: &str, files: &Files) -> Result<Rendered, JsError> {
        let t0 = web_time::Instant::now();
        let scene = parse(toml, path, files).0.map_err(|e| JsError::new(&e))?;
        let (width, height) = RenderOptions::default()
            .checked_size(&scene)
            .map_err(|e| JsError::new(&e.to_string()))?;
        let buf = SceneBuffers::new(&scene, width, height, scene.triangle);
        let spec = Specialisation::for_scene(&buf);
        let (device, queue) = (&self.gpu.device, &self.gpu.queue);
        let err = |e: glint::gpu::GpuError| JsError::new(&e.to_string());
        let resident = self
            .gpu
            .kernel
            .resident(device, queue, &buf, spec)
            .map_err(err)?;
        let bytes = 4 * width as u64 * height as u64;
        let staging = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("readback"),
            size: bytes,
            usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        resident
            .frame_to_buffer(device, queue, &buf.params, &staging)
            .map_err(err)?;
        map_read(&staging).await?;
        let rgba = staging
            .slice(..)
            .get_mapped_range()
            .map_err(|e| JsError::new(&format!("readback: {e}")))?
            .to_vec();
        staging.unmap();
        Ok(Rendered {
            width,
            height,
            rgba,
            ms: t0.elapsed().as_secs_f64() * 1e3,
        })
    }
}

/// Maps `buffer` for reading, waiting on the page's event loop (where WebGPU answers).
async fn map_read(buffer: &wgpu::Buffer) -> Result<(), JsError> {
    let result: std::rc::Rc<RefCell<Option<String>>> = Default::default();
    let slot = result.clone();
    let promise = js_sys::Promise::new(&mut |resolve, _reject| {
        let slot = slot.clone();
        buffer.slice(..).map_async(wgpu::MapMode::Read, move |r| {
            if let Err(e) = r {
                *slot.borrow_mut() = Some(e.to_string());
            }
            let _ = resolve.call0(&JsValue::NULL);
        });
    });
    wasm_bindgen_futures::JsFuture::from(promise)
        .await
        .map_err(|_| JsError::new("readback: the map was abandoned"))?;
    match result.borrow_mut().take() {
        Some(e) => Err(JsError::new(&format!("readback: {e}"))),
        None => Ok(()),
    }
}

/// How two 8-bit RGBA frames of the same size differ (alpha ignored), with a difference map.
#[wasm_bindgen(getter_with_clone)]
pub struct Comparison {
    /// Pixels compared.
    pub pixels: u32,
    /// Pixels whose colour differs in some channel.
    pub differing: u32,
    /// Pixels that differ by more than 1/255 in some channel.
    pub beyond_one: u32,
    /// The largest channel difference, in 1/255 steps.
    pub max_diff: u8,
    /// RGBA: black where equal, red where a channel differs by one step, brighter for
    /// larger differences, white beyond 16 steps.
    pub map: Vec<u8>,
}

/// Compares `a` with `b`, two RGBA frames of `width × height`.
#[wasm_bindgen]
pub fn compare_rgba8(a: &[u8], b: &[u8], width: u32, height: u32) -> Result<Comparison, JsError> {
    let n = width as usize * height as usize;
    if a.len() != 4 * n || b.len() != 4 * n {
        return Err(JsError::new(&format!(
            "frames of different sizes: {} and {} bytes for {width}×{height}",
            a.len(),
            b.len()
        )));
    }
    let mut c = Comparison {
        pixels: n as u32,
        differing: 0,
        beyond_one: 0,
        max_diff: 0,
        map: Vec::with_capacity(4 * n),
    };
    for (p, q) in a.chunks_exact(4).zip(b.chunks_exact(4)) {
        let d = (0..3).map(|k| p[k].abs_diff(q[k])).max().unwrap_or(0);
        c.differing += (d > 0) as u32;
        c.beyond_one += (d > 1) as u32;
        c.max_diff = c.max_diff.max(d);
        let px = match d {
            0 => [0, 0, 0],
            1..=16 => [127 + 8 * d, 0, 0],
            _ => [255, 255, 255],
        };
        c.map.extend_from_slice(&[px[0], px[1], px[2], 255]);
    }
    Ok(c)
}

/// The kernel's WGSL as this build holds it (`glint::gpu::SHADER_SOURCE`), for a page that
/// shows what its GPU runs.
#[wasm_bindgen]
pub fn shader_source() -> String {
    glint::gpu::SHADER_SOURCE.to_string()
}
