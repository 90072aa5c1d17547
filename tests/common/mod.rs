//! Shared by the integration tests: one GPU per test process, a seeded RNG, helpers.
#![allow(dead_code)]

pub mod hard;

use std::sync::OnceLock;

use glint::gpu::Gpu;
use wgpu::util::DeviceExt;

/// A test's own folder under the system's temporary folder, `glint-<name>-<pid>`: empty
/// when made, and removed with everything in it when dropped, also when the test fails
/// (a panic unwinds through it), so test runs leave nothing behind.
pub struct Scratch(std::path::PathBuf);

impl Scratch {
    /// Makes the folder, emptying what an earlier run of the same pid may have left.
    pub fn new(name: &str) -> Scratch {
        let d = std::env::temp_dir().join(format!("glint-{name}-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&d);
        std::fs::create_dir_all(&d).unwrap();
        Scratch(d)
    }
}

impl std::ops::Deref for Scratch {
    type Target = std::path::Path;
    fn deref(&self) -> &std::path::Path {
        &self.0
    }
}

impl AsRef<std::path::Path> for Scratch {
    fn as_ref(&self) -> &std::path::Path {
        &self.0
    }
}

impl Drop for Scratch {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.0);
    }
}

/// A finished command's exit status and its standard output followed by its standard error.
pub fn status_and_text(o: &std::process::Output) -> (Option<i32>, String) {
    (
        o.status.code(),
        format!(
            "{}{}",
            String::from_utf8_lossy(&o.stdout),
            String::from_utf8_lossy(&o.stderr)
        ),
    )
}

/// A command that runs the `glint` binary the way this test process runs: through
/// `GLINT_LAVAPIPE_LOADER` where `.ci/lavapipe.sh 26` set one (a driver built for a newer
/// C library than the system's runs only through its own dynamic loader, and a child
/// started plainly would find no adapter), else directly.
pub fn glint_command() -> std::process::Command {
    let exe = env!("CARGO_BIN_EXE_glint");
    match std::env::var_os("GLINT_LAVAPIPE_LOADER") {
        Some(loader) if !loader.is_empty() => {
            let mut c = std::process::Command::new(loader);
            c.arg(exe);
            c
        }
        _ => std::process::Command::new(exe),
    }
}

/// The process's GPU. Panics (fails the test) when there is no adapter, unless
/// `GLINT_SKIP_GPU=1`, in which case it says loudly that the test is skipped and returns None.
pub fn gpu() -> Option<&'static Gpu> {
    static GPU: OnceLock<Result<Gpu, String>> = OnceLock::new();
    let skip = std::env::var("GLINT_SKIP_GPU").is_ok_and(|v| v == "1");
    if skip {
        eprintln!(
            "\n*** GLINT_SKIP_GPU=1: SKIPPING this GPU test; it did NOT run and proves nothing. ***\n"
        );
        return None;
    }
    let adapter = std::env::var("GLINT_ADAPTER").ok();
    match GPU.get_or_init(|| {
        let g = Gpu::new(adapter.as_deref()).map_err(|e| e.to_string())?;
        eprintln!("GPU tests on: {}", g.describe());
        Ok(g)
    }) {
        Ok(g) => Some(g),
        Err(e) => {
            panic!("no GPU for the GPU tests: {e}\n(set GLINT_SKIP_GPU=1 to skip them explicitly)")
        }
    }
}

/// Defines the test binary's `gpu_tests_ran` sentinel: it fails when there is no adapter,
/// and it shows as "ignored", with the reason, in the test summary when `GLINT_SKIP_GPU=1`
/// (the tests are then built with `--cfg glint_skip_gpu` by `build.rs`), so a skipped GPU
/// suite can never read as a passed one.
#[macro_export]
macro_rules! gpu_sentinel {
    () => {
        #[test]
        #[cfg_attr(
            glint_skip_gpu,
            ignore = "GLINT_SKIP_GPU=1: every GPU check in this binary was SKIPPED"
        )]
        fn gpu_tests_ran() {
            let gpu = common::gpu().expect("GLINT_SKIP_GPU=1 at run time but not at build time");
            eprintln!("adapter: {}", gpu.describe());
            // `.ci/test.sh` names the driver each pass must run on.
            if let Ok(want) = std::env::var("GLINT_EXPECT_DRIVER") {
                assert!(
                    gpu.describe().contains(&want),
                    "this pass must run on {want}, but the adapter is {}",
                    gpu.describe()
                );
            }
        }
    };
}

/// Whether the GPU image must equal the CPU mirror's in every bit: wherever the kernel
/// reaches the driver as glint's exact SPIR-V (every float result `NoContraction`), whose
/// divisions and square roots are correctly rounded by `shaders/exact.wgsl` whatever the
/// driver. Elsewhere (wgpu's own WGSL path) the driver may fuse and reorder.
pub fn bit_exact_expected(gpu: &Gpu) -> bool {
    gpu.kernel.exactness() == glint::gpu::exact::Exactness::NoContraction
}

/// SplitMix64: small, seeded, good enough for test inputs.
pub struct Rng(u64);

impl Rng {
    pub fn new(seed: u64) -> Self {
        Rng(seed)
    }
    pub fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9e37_79b9_7f4a_7c15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        z ^ (z >> 31)
    }
    /// Uniform in [0, 1).
    pub fn unit(&mut self) -> f64 {
        (self.next_u64() >> 11) as f64 / (1u64 << 53) as f64
    }
    /// Uniform in [lo, hi), rounded to f32.
    pub fn range(&mut self, lo: f32, hi: f32) -> f32 {
        (lo as f64 + (hi as f64 - lo as f64) * self.unit()) as f32
    }
}

/// The bindings every probe shader declares: `input` (read) and `output`.
pub const PROBE_BINDINGS: &str = "
@group(0) @binding(0) var<storage, read> input: array<vec4<f32>>;
@group(0) @binding(1) var<storage, read_write> output: array<vec4<f32>>;
";

/// Runs a probe shader (entry point `main`, `@workgroup_size(64)`, the bindings of
/// [`PROBE_BINDINGS`]) with `input` at binding 0 and `out_len` vec4s at binding 1, on at
/// least `invocations` invocations (the shader bounds-checks its own index).
pub fn run_probe(
    gpu: &Gpu,
    src: &str,
    input: &[[f32; 4]],
    out_len: usize,
    invocations: usize,
) -> Vec<[f32; 4]> {
    run_probe_with(gpu, src, &[], input, out_len, invocations)
}

/// [`run_probe`] with the shader's override `constants` set.
pub fn run_probe_with(
    gpu: &Gpu,
    src: &str,
    constants: &[(&str, f64)],
    input: &[[f32; 4]],
    out_len: usize,
    invocations: usize,
) -> Vec<[f32; 4]> {
    let d = &gpu.device;
    // The probe reaches the driver as the kernel does: NoContraction SPIR-V where the
    // device takes it (glint::gpu::exact), specialised while written; else WGSL, with the
    // constants given to the pipeline.
    let (module, pipeline_constants) =
        match glint::gpu::exact::ExactSource::new(d, src).expect("probe compiles") {
            Ok(exact) => (
                exact
                    .module(d, "main", constants, &[0, 1])
                    .expect("probe module"),
                &[][..],
            ),
            Err(_) => (
                d.create_shader_module(wgpu::ShaderModuleDescriptor {
                    label: None,
                    source: wgpu::ShaderSource::Wgsl(src.into()),
                }),
                constants,
            ),
        };
    let entry = |binding, read_only| wgpu::BindGroupLayoutEntry {
        binding,
        visibility: wgpu::ShaderStages::COMPUTE,
        ty: wgpu::BindingType::Buffer {
            ty: wgpu::BufferBindingType::Storage { read_only },
            has_dynamic_offset: false,
            min_binding_size: None,
        },
        count: None,
    };
    let bgl = d.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
        label: None,
        entries: &[entry(0, true), entry(1, false)],
    });
    let layout = d.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
        label: None,
        bind_group_layouts: &[Some(&bgl)],
        immediate_size: 0,
    });
    let pipeline = d.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
        label: None,
        layout: Some(&layout),
        module: &module,
        entry_point: Some("main"),
        compilation_options: wgpu::PipelineCompilationOptions {
            constants: pipeline_constants,
            zero_initialize_workgroup_memory: false,
        },
        cache: None,
    });
    let inb = d.create_buffer_init(&wgpu::util::BufferInitDescriptor {
        label: None,
        contents: bytemuck::cast_slice(input),
        usage: wgpu::BufferUsages::STORAGE,
    });
    let size = (out_len * 16) as u64;
    let outb = d.create_buffer(&wgpu::BufferDescriptor {
        label: None,
        size,
        usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
        mapped_at_creation: false,
    });
    let staging = d.create_buffer(&wgpu::BufferDescriptor {
        label: None,
        size,
        usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
        mapped_at_creation: false,
    });
    let bg = d.create_bind_group(&wgpu::BindGroupDescriptor {
        label: None,
        layout: &bgl,
        entries: &[
            wgpu::BindGroupEntry {
                binding: 0,
                resource: inb.as_entire_binding(),
            },
            wgpu::BindGroupEntry {
                binding: 1,
                resource: outb.as_entire_binding(),
            },
        ],
    });
    let mut enc = d.create_command_encoder(&Default::default());
    {
        let mut pass = enc.begin_compute_pass(&Default::default());
        pass.set_pipeline(&pipeline);
        pass.set_bind_group(0, &bg, &[]);
        pass.dispatch_workgroups((invocations as u32).div_ceil(64), 1, 1);
    }
    enc.copy_buffer_to_buffer(&outb, 0, &staging, 0, size);
    gpu.queue.submit([enc.finish()]);
    let slice = staging.slice(..);
    slice.map_async(wgpu::MapMode::Read, |r| r.expect("map"));
    d.poll(wgpu::PollType::wait_indefinitely()).expect("poll");
    let v =
        bytemuck::cast_slice::<u8, [f32; 4]>(&slice.get_mapped_range().expect("mapped")).to_vec();
    staging.unmap();
    v
}

use glint::buffers::{SceneBuffers, Specialisation};
use glint::compare::{Diff, diff};
use glint::image::Image;
use glint::scene::{Scene, TriangleAlgorithm};

/// The five seed scenes.
pub const SEED_SCENES: [&str; 5] = ["sphere", "triangle", "umbrella", "bb8", "mitsubishi"];

/// Every scene in `scenes/` that needs no fetched mesh: the seed scenes, their shadowed,
/// antialiased and mirrored variants, the Whitted scene, the PLY scene, the spot-lit scene
/// and the textured scene (the README and docs/features.md show each).
pub const SHIPPED_SCENES: [&str; 13] = [
    "sphere",
    "triangle",
    "umbrella",
    "bb8",
    "mitsubishi",
    "bb8-shadows",
    "mitsubishi-shadows",
    "bb8-aa",
    "whitted",
    "bb8-mirror",
    "suzanne-ply",
    "spot",
    "textured",
];

/// Writes into `dir` a scene of 30,000 small ambient triangles (`many.obj`, 1.44 MB of
/// triangles on the GPU: more than a smaller GPU's 1 MB buffer limit) and returns its path.
pub fn too_large_scene(dir: &std::path::Path) -> std::path::PathBuf {
    let mut obj = String::new();
    for i in 0..30_000 {
        let (x, y) = ((i % 200) as f32 * 0.02 - 2.0, (i / 200) as f32 * 0.02 - 1.5);
        obj += &format!(
            "v {x} {y} 0\nv {} {y} 0\nv {x} {} 0\n",
            x + 0.015,
            y + 0.015
        );
    }
    for i in 0..30_000 {
        obj += &format!("f {} {} {}\n", 3 * i + 1, 3 * i + 2, 3 * i + 3);
    }
    std::fs::write(dir.join("many.obj"), obj).unwrap();
    let scene = dir.join("many.toml");
    std::fs::write(
        &scene,
        "[camera]\neye = [0.0, 0.0, 5.0]\nlook_at = [0.0, 0.0, 0.0]\nfov = 60.0\nwidth = 64\n\
         height = 48\n[materials.m]\nmodel = \"ambient\"\nka = [1.0, 1.0, 1.0]\n\
         [[meshes]]\nfile = \"many.obj\"\nmaterial = \"m\"\n",
    )
    .unwrap();
    scene
}

/// Loads `scenes/NAME.toml` from the crate root.
pub fn seed_scene(name: &str) -> Scene {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("scenes")
        .join(format!("{name}.toml"));
    Scene::load(&path).unwrap_or_else(|e| panic!("{e}"))
}

/// The scene's buffers at `w`×`h` with `algo`, and its specialisation.
pub fn buffers(
    scene: &Scene,
    w: u32,
    h: u32,
    algo: TriangleAlgorithm,
) -> (SceneBuffers, Specialisation) {
    let buf = SceneBuffers::new(scene, w, h, algo);
    let spec = Specialisation::for_scene(&buf);
    (buf, spec)
}

/// Renders on the GPU, with the traversal glint would use (packets for BVH scenes where
/// the device has subgroups).
pub fn render_gpu(gpu: &Gpu, buf: &SceneBuffers, spec: Specialisation) -> Image {
    gpu.compute_kernel(spec)
        .expect("kernel")
        .render(&gpu.device, &gpu.queue, buf, spec, &mut |_, _| {})
        .expect("GPU render")
        .0
}

/// `kernel`'s lean frame (`render_rgba8`) of `buf`: one packed pixel each, row-major.
pub fn render_gpu_rgba8(
    gpu: &Gpu,
    kernel: &glint::gpu::Kernel,
    buf: &SceneBuffers,
    spec: Specialisation,
) -> Vec<u32> {
    let mut out = vec![0u32; buf.params.width as usize * buf.params.height as usize];
    let w = buf.params.width as usize;
    // Tiles of 37 rows: the bands land at their rows, whatever the tiling.
    kernel
        .render_bands_rgba8(&gpu.device, &gpu.queue, buf, spec, 37, &mut |y, px| {
            out[y as usize * w..y as usize * w + px.len()].copy_from_slice(px);
        })
        .expect("GPU render (lean frame)");
    out
}

/// The agreement GPU and CPU images must reach: with glint's exact SPIR-V
/// ([`bit_exact_expected`]) every f32 bit of every pixel and every hit/miss; through wgpu's
/// WGSL path, where a driver may fuse and reorder, at most 0.1% of pixels off in 8 bits and
/// 0.01% hit/miss disagreements.
pub fn check_agreement(gpu_img: &Image, cpu_img: &Image, exact: bool) -> Result<Diff, String> {
    let d = diff(gpu_img, cpu_img);
    let ok = if exact {
        d.bit_exact()
    } else {
        d.differing_pixels * 1000 <= d.pixels && d.hit_miss * 10_000 <= d.pixels
    };
    if ok {
        Ok(d)
    } else {
        Err(format!(
            "GPU and CPU images disagree ({}): {d:?}",
            if exact {
                "exact SPIR-V: bit-exact required"
            } else {
                "tolerance"
            }
        ))
    }
}

use glint::buffers::{self, HitOut, RayIn};

/// Bare geometry as buffers: one Phong material, no lights, the given triangle algorithm.
pub fn geometry(
    spheres: Vec<buffers::Sphere>,
    triangles: Vec<buffers::Triangle>,
    algo: TriangleAlgorithm,
) -> (SceneBuffers, Specialisation) {
    let params = buffers::Params {
        width: 1,
        height: 1,
        n_spheres: spheres.len() as u32,
        n_triangles: triangles.len() as u32,
        tile_width: 1,
        tile_height: 1,
        ..Default::default()
    };
    let buf = SceneBuffers::assemble(
        params,
        spheres,
        triangles,
        vec![buffers::Material {
            ka: [1.0; 3],
            model: buffers::MODEL_AMBIENT,
            ..Default::default()
        }],
        vec![],
        algo,
        false,
    );
    let spec = Specialisation::for_scene(&buf);
    (buf, spec)
}

/// A triangle from three points.
pub fn tri(a: [f32; 3], b: [f32; 3], c: [f32; 3]) -> buffers::Triangle {
    buffers::Triangle {
        a,
        b,
        c,
        ..Default::default()
    }
}

/// The rays through the CPU mirror and, when there is a GPU, through the shader's `query`
/// entry point; on lavapipe the two must agree bit for bit. Returns the CPU's answers.
pub fn query_both(
    buf: &SceneBuffers,
    spec: Specialisation,
    rays: &[RayIn],
    what: &str,
) -> Vec<HitOut> {
    let cpu = glint::cpu::query_f32(buf, spec, rays);
    // The other traversal (BVH or every primitive) gives the same nearest hit.
    let other = glint::cpu::query_f32(buf, spec.with_bvh(!spec.use_bvh), rays);
    let differ = cpu
        .iter()
        .zip(&other)
        .filter(|(a, b)| bytemuck::bytes_of(*a) != bytemuck::bytes_of(*b))
        .count();
    // The naive test accepts points well outside its triangle far from the origin (t off
    // by up to 1e-2 relative, docs/robustness.md), beyond any box padding: there the BVH
    // may skip a hit that brute force keeps, rarely.
    if std::env::var("GLINT_DEBUG_DIFF").is_ok() {
        for (k, (a, b)) in cpu.iter().zip(&other).enumerate() {
            if bytemuck::bytes_of(a) != bytemuck::bytes_of(b) {
                eprintln!("{:?}\n  {:?}\n  {:?}", rays[k], a, b);
            }
        }
    }
    let allowed = if spec.triangle_algo == buffers::TRIANGLE_NAIVE {
        rays.len() / 1000
    } else {
        0
    };
    assert!(
        differ <= allowed,
        "{what}: BVH and brute force differ on {differ} of {} rays (allowed {allowed})",
        rays.len()
    );
    if let Some(gpu) = gpu() {
        let g = gpu
            .compute_kernel(spec)
            .expect("kernel")
            .query(&gpu.device, &gpu.queue, buf, spec, rays)
            .expect("GPU query");
        let bad = g
            .iter()
            .zip(&cpu)
            .filter(|(a, b)| bytemuck::bytes_of(*a) != bytemuck::bytes_of(*b))
            .count();
        let hit_miss = g
            .iter()
            .zip(&cpu)
            .filter(|(a, b)| (a.prim == buffers::PRIM_NONE) != (b.prim == buffers::PRIM_NONE))
            .count();
        if bit_exact_expected(gpu) {
            assert_eq!(
                bad,
                0,
                "{what}: {bad} of {} GPU query results differ from the CPU's",
                rays.len()
            );
        } else if spec.triangle_algo == buffers::TRIANGLE_WATERTIGHT {
            // The watertight test decides a hit with +, − and × alone, which every Vulkan
            // device rounds as Rust does; the naive and Möller–Trumbore tests divide, which
            // Vulkan lets round within 2.5 ULP, so they may flip at a shared edge or vertex.
            assert_eq!(
                hit_miss, 0,
                "{what}: {hit_miss} hit/miss disagreements between GPU and CPU"
            );
        } else {
            eprintln!("{what}: {hit_miss} hit/miss disagreements between GPU and CPU (division)");
        }
    }
    cpu
}

// ---- random scenes ------------------------------------------------------------------

use std::fmt::Write;

/// `[x, y, z]` with each coordinate uniform in [lo, hi).
pub fn v3(rng: &mut Rng, lo: f32, hi: f32) -> String {
    format!(
        "[{}, {}, {}]",
        rng.range(lo, hi),
        rng.range(lo, hi),
        rng.range(lo, hi)
    )
}

/// A random scene as TOML text (so the parser is part of the property too).
pub fn random_scene(rng: &mut Rng) -> String {
    let mut s = String::new();
    let algo = ["naive", "moller-trumbore", "watertight"][(rng.next_u64() % 3) as usize];
    writeln!(s, "ambient = {}", v3(rng, 0.0, 0.4)).unwrap();
    writeln!(s, "background = {}", v3(rng, 0.0, 0.3)).unwrap();
    writeln!(s, "triangle = \"{algo}\"").unwrap();
    writeln!(s, "shadows = {}", rng.next_u64().is_multiple_of(2)).unwrap();
    writeln!(s, "[camera]").unwrap();
    writeln!(s, "eye = {}", v3(rng, -8.0, 8.0)).unwrap();
    writeln!(s, "look_at = {}", v3(rng, -1.0, 1.0)).unwrap();
    writeln!(s, "up = {}", v3(rng, -1.0, 1.0)).unwrap();
    writeln!(s, "fov = {}", rng.range(20.0, 110.0)).unwrap();
    writeln!(s, "width = 48\nheight = 36").unwrap();
    for _ in 0..1 + rng.next_u64() % 3 {
        writeln!(s, "[[lights]]").unwrap();
        writeln!(s, "position = {}", v3(rng, -10.0, 10.0)).unwrap();
        writeln!(s, "color = {}", v3(rng, 0.0, 1.0)).unwrap();
    }
    let n_materials = 1 + rng.next_u64() % 3;
    for k in 0..n_materials {
        let model = ["ambient", "diffuse", "phong"][(rng.next_u64() % 3) as usize];
        writeln!(s, "[materials.m{k}]\nmodel = \"{model}\"").unwrap();
        writeln!(s, "ka = {}", v3(rng, 0.0, 1.0)).unwrap();
        if model != "ambient" {
            writeln!(s, "kd = {}", v3(rng, 0.0, 1.0)).unwrap();
        }
        if model == "phong" {
            // Integer exponents: raised by squaring on both tracers (pow differs by ULPs).
            writeln!(s, "ks = {}", v3(rng, 0.0, 1.0)).unwrap();
            writeln!(s, "n = {}.0", rng.next_u64() % 200).unwrap();
        }
    }
    let mat = |rng: &mut Rng| format!("m{}", rng.next_u64() % n_materials);
    for _ in 0..rng.next_u64() % 6 {
        writeln!(s, "[[spheres]]").unwrap();
        writeln!(s, "center = {}", v3(rng, -3.0, 3.0)).unwrap();
        writeln!(s, "radius = {}", rng.range(0.05, 2.0)).unwrap();
        writeln!(s, "material = \"{}\"", mat(rng)).unwrap();
    }
    // Sometimes a few triangles (traced by testing each), sometimes enough for the BVH.
    let n_tris = if rng.next_u64().is_multiple_of(2) {
        rng.next_u64() % 8
    } else {
        20 + rng.next_u64() % 60
    };
    for _ in 0..n_tris {
        let c = [0, 1, 2].map(|_| rng.range(-3.0, 3.0));
        let p = |rng: &mut Rng| {
            format!(
                "[{}, {}, {}]",
                c[0] + rng.range(-1.0, 1.0),
                c[1] + rng.range(-1.0, 1.0),
                c[2] + rng.range(-1.0, 1.0)
            )
        };
        let (a, b, d) = (p(rng), p(rng), p(rng));
        writeln!(s, "[[triangles]]\nvertices = [{a}, {b}, {d}]").unwrap();
        writeln!(s, "material = \"{}\"", mat(rng)).unwrap();
    }
    s
}

// ---- vertices on pixel rays -----------------------------------------------------------

/// The directions of the tracer's own f32 camera rays through the centres of pixels (i, j).
pub fn pixel_dirs(scene: &Scene, pixels: &[(u32, u32)]) -> Vec<[f32; 3]> {
    let (w, h) = scene.size();
    let buf = SceneBuffers::new(scene, w, h, scene.triangle);
    let g = glint::cpu::trace::Globals {
        cam: glint::cpu::trace::Camera::from_params(&buf.params),
        buf: &buf,
        spec: Specialisation::for_scene(&buf),
        count: glint::cpu::count::NoCount,
    };
    pixels
        .iter()
        .map(|&(i, j)| glint::cpu::trace::camera_ray(&g, i, j, 0.5, 0.5).dir.into())
        .collect()
}

/// A bumpy height field seen from `eye`, whose shared vertices lie on pixel rays (to the
/// ulp of `eye + dir * d`): every `step`-th pixel's centre ray carries a vertex at a
/// distance that rises and falls from vertex to vertex, so many rays pass within an ulp of
/// a vertex or an edge that two, four or six triangles share. `w`×`h` pixels.
pub fn vertex_grid_scene(eye: [f32; 3], algo: &str, w: u32, h: u32, step: u32) -> String {
    let look = [eye[0], eye[1], eye[2] - 1.0];
    let head = format!(
        "ambient = [0.2, 0.2, 0.2]\ntriangle = \"{algo}\"\n[camera]\neye = {eye:?}\n\
         look_at = {look:?}\nfov = 50.0\nwidth = {w}\nheight = {h}\n\
         [[lights]]\nposition = [{}, {}, {}]\ncolor = [1.0, 1.0, 1.0]\n\
         [materials.m]\nmodel = \"phong\"\nka = [0.2, 0.3, 0.4]\nkd = [0.6, 0.5, 0.4]\n\
         ks = [0.5, 0.5, 0.5]\nn = 12.0\n",
        eye[0] - 3.0,
        eye[1] + 4.0,
        eye[2] + 2.0
    );
    let probe = Scene::parse(&head, std::path::Path::new("vertex-grid.toml")).unwrap();
    let (nx, ny) = ((w - 1) / step + 1, (h - 1) / step + 1);
    let pixels: Vec<(u32, u32)> = (0..ny)
        .flat_map(|b| (0..nx).map(move |a| (a * step, b * step)))
        .collect();
    let dirs = pixel_dirs(&probe, &pixels);
    let vertex = |a: u32, b: u32| {
        let d = dirs[(b * nx + a) as usize];
        let bump = 4.0 + 0.35 * ((a % 3) as f32 - 1.0) + 0.25 * ((b % 2) as f32);
        [0, 1, 2].map(|k| eye[k] + d[k] * bump)
    };
    let mut s = head;
    for b in 0..ny - 1 {
        for a in 0..nx - 1 {
            let (p, q, r, t) = (
                vertex(a, b),
                vertex(a + 1, b),
                vertex(a, b + 1),
                vertex(a + 1, b + 1),
            );
            // Alternate the diagonal, so vertices are shared by 4 or 8 triangles.
            let quads = if (a + b) % 2 == 0 {
                [[p, q, t], [p, t, r]]
            } else {
                [[p, q, r], [q, t, r]]
            };
            for v in quads {
                writeln!(s, "[[triangles]]\nvertices = {v:?}\nmaterial = \"m\"").unwrap();
            }
        }
    }
    s
}

/// A [`vertex_grid_scene`] at 48×36 with a random eye (near the origin or up to 1e4 away),
/// triangle algorithm and vertex spacing.
pub fn random_vertex_grid(rng: &mut Rng) -> String {
    let far = [1.0, 1e4][(rng.next_u64() % 2) as usize];
    let eye = [0, 1, 2].map(|_| rng.range(-far, far));
    let algo = ["naive", "moller-trumbore", "watertight"][(rng.next_u64() % 3) as usize];
    let step = 2 + (rng.next_u64() % 3) as u32;
    vertex_grid_scene(eye, algo, 48, 36, step)
}

/// Ok when the two images are equal in every bit; else where they first differ.
pub fn same_bits(a: &glint::image::Image, b: &glint::image::Image) -> Result<(), String> {
    if (a.width, a.height) != (b.width, b.height) {
        return Err("the images differ in size".into());
    }
    let differing: Vec<usize> = (0..b.pixels.len())
        .filter(|&k| a.pixels[k].map(f32::to_bits) != b.pixels[k].map(f32::to_bits))
        .collect();
    match differing.first() {
        None => Ok(()),
        Some(&k) => Err(format!(
            "{} pixels differ; first ({}, {}): {:?} against {:?}",
            differing.len(),
            k % b.width as usize,
            k / b.width as usize,
            a.pixels[k],
            b.pixels[k]
        )),
    }
}

/// A `.glb` container of the glTF `json` and its binary chunk `bin` (a multiple of 4
/// bytes): the header, the JSON chunk padded with spaces, the BIN chunk.
pub fn glb(json: &str, bin: &[u8]) -> Vec<u8> {
    let mut j = json.as_bytes().to_vec();
    while !j.len().is_multiple_of(4) {
        j.push(b' ');
    }
    let total = 12 + 8 + j.len() + 8 + bin.len();
    let mut out = b"glTF".to_vec();
    out.extend(2u32.to_le_bytes());
    out.extend((total as u32).to_le_bytes());
    out.extend((j.len() as u32).to_le_bytes());
    out.extend(b"JSON");
    out.extend(&j);
    out.extend((bin.len() as u32).to_le_bytes());
    out.extend(b"BIN\0");
    out.extend(bin);
    out
}

/// Floats of every class: zeros, subnormals, normals around the range's edges, infinities
/// and NaN, of both signs.
pub fn specials() -> Vec<f32> {
    let mut v = vec![
        0.0f32,
        f32::from_bits(1),
        f32::from_bits(2),
        f32::from_bits(0x0040_0000),
        f32::from_bits(0x007f_ffff),
        f32::MIN_POSITIVE,
        f32::from_bits(0x0080_0001),
        2f32.powi(-125),
        0.5,
        1.0,
        1.000_000_1,
        1.5,
        2.0,
        3.0,
        0.1,
        2f32.powi(126),
        2f32.powi(127),
        f32::MAX,
        f32::INFINITY,
        f32::NAN,
    ];
    let negatives: Vec<f32> = v.iter().map(|x| -x).collect();
    v.extend(negatives);
    v
}

/// The CRC-32 of PNG chunks (ISO 3309), bit by bit.
pub fn crc32(bytes: &[u8]) -> u32 {
    let mut c = 0xffff_ffffu32;
    for &b in bytes {
        c ^= b as u32;
        for _ in 0..8 {
            c = if c & 1 != 0 {
                0xedb8_8320 ^ (c >> 1)
            } else {
                c >> 1
            };
        }
    }
    !c
}
