//! The exact path (src/gpu/exact.rs): every kernel glint compiles reaches the driver as
//! SPIR-V whose every floating-point result is decorated `NoContraction`, and holds no
//! built-in that a driver may fuse whatever the decoration says. The SPIR-V checks need
//! no GPU; the last test checks that the test GPU's kernels take the exact path.

mod common;

use glint::buffers::Specialisation;
use glint::gpu::exact::{ExactSource, Exactness, SpirvTarget};
use glint::gpu::spirv::{contractible, fused_builtins};
use glint::gpu::{SHADER_SOURCE, rq, subgroup};

gpu_sentinel!();

/// lavapipe's target: Vulkan 1.3 (SPIR-V 1.6) with robustBufferAccess2.
const LAVAPIPE: SpirvTarget = SpirvTarget {
    api_version: ash::vk::API_VERSION_1_3,
    robust_buffer_access2: true,
};

/// Every module glint compiles: (name, WGSL).
fn kernels() -> Vec<(&'static str, String)> {
    vec![
        ("per-ray", SHADER_SOURCE.to_string()),
        ("packet", subgroup::shader_source(true)),
        (
            "packet, shadow rays per ray",
            subgroup::shader_source(false),
        ),
        ("ray query", rq::shader_source()),
    ]
}

/// Everything on, and a lean one-sphere pipeline: the two ends of the specialisation.
fn specialisations() -> [Specialisation; 2] {
    let all = Specialisation {
        has_spheres: true,
        has_triangles: true,
        triangle_algo: glint::shared::layout::TRIANGLE_WATERTIGHT,
        uses_diffuse: true,
        uses_phong: true,
        shadows: true,
        use_bvh: true,
        smooth: true,
        antialias: true,
        whitted: true,
        light_kinds: true,
        textures: true,
        powers: true,
        instances: true,
        math: Default::default(),
    };
    let lean = Specialisation {
        has_triangles: false,
        triangle_algo: glint::shared::layout::TRIANGLE_NAIVE,
        shadows: false,
        use_bvh: false,
        smooth: false,
        antialias: false,
        whitted: false,
        light_kinds: false,
        textures: false,
        powers: false,
        instances: false,
        ..all
    };
    [all, lean]
}

#[test]
fn every_kernel_reaches_the_driver_with_no_contractible_arithmetic() {
    for target in [
        LAVAPIPE,
        SpirvTarget {
            api_version: ash::vk::API_VERSION_1_1,
            robust_buffer_access2: false,
        },
    ] {
        for (name, wgsl) in kernels() {
            let src = ExactSource::compile(&wgsl, target).unwrap();
            for spec in specialisations() {
                for entry in ["render", "render_rgba8", "query", "render_aov"] {
                    let c = spec.constants();
                    let words = src.spirv(entry, &c, &[]).unwrap();
                    let left = contractible(&words).unwrap();
                    assert!(
                        left.is_empty(),
                        "{name} {entry}: {} undecorated",
                        left.len()
                    );
                    // The twin: naga's own words have float arithmetic left undecorated,
                    // so the check above could fail.
                    let plain = src.plain_spirv(entry, &c, &[]).unwrap();
                    assert!(
                        contractible(&plain).unwrap().len() > 20,
                        "{name} {entry}: naga's SPIR-V should hold undecorated arithmetic"
                    );
                    assert_eq!(fused_builtins(&words).unwrap(), vec![], "{name} {entry}");
                }
            }
        }
    }
}

/// The AOV part of the kernel (`shaders/aov.wgsl`, last in the module) changes no word of
/// the colour entry points' SPIR-V: a render without AOVs runs the kernel it ran before
/// that part existed. The twin: without the part there is no `render_aov` to write.
#[test]
fn the_aov_part_changes_no_word_of_the_colour_kernels() {
    let cut = SHADER_SOURCE
        .find("// glint's kernel, part 7 of 8: arbitrary output variables")
        .expect("aov.wgsl is in the kernel");
    let without = ExactSource::compile(&SHADER_SOURCE[..cut], LAVAPIPE).unwrap();
    let with = ExactSource::compile(SHADER_SOURCE, LAVAPIPE).unwrap();
    for spec in specialisations() {
        let c = spec.constants();
        for entry in ["render", "render_rgba8", "query"] {
            assert_eq!(
                with.spirv(entry, &c, &[]).unwrap(),
                without.spirv(entry, &c, &[]).unwrap(),
                "{entry}"
            );
        }
        assert!(with.spirv("render_aov", &c, &[]).is_ok());
        assert!(without.spirv("render_aov", &c, &[]).is_err(), "the twin");
    }
}

/// WGSL built-ins that Mesa 26.2 lowers to `ffma_weak` and emits as `llvm.fmuladd` (fused
/// on x86) whatever the decoration says, and matrix types (their products likewise); the
/// shaders write these out as multiplies and adds. Comments are ignored.
fn fusible_builtins(wgsl: &str) -> Vec<String> {
    let mut found = Vec::new();
    for (k, line) in wgsl.lines().enumerate() {
        let code = line.split("//").next().unwrap_or("");
        for word in ["fma(", "mix(", "cross(", "mat2x", "mat3x", "mat4x"] {
            // A built-in call, not the end of a longer name (`cross3(` is glint's own).
            let mut rest = code;
            while let Some(at) = rest.find(word) {
                let before = rest[..at].chars().next_back();
                if !before.is_some_and(|c| c.is_alphanumeric() || c == '_') {
                    found.push(format!("line {}: {}", k + 1, line.trim()));
                }
                rest = &rest[at + word.len()..];
            }
        }
    }
    found
}

#[test]
fn no_shader_calls_a_built_in_that_a_driver_may_fuse() {
    for (name, wgsl) in kernels() {
        assert_eq!(fusible_builtins(&wgsl), Vec::<String>::new(), "{name}");
    }
    // The twin: the scan sees each such call, and not glint's own `cross3` or a comment.
    let probe = "let a = mix(x, y, t);\nlet b = cross3(p, q); // fma(a, b, c)\nlet m = mat3x3<f32>();\nlet c = fma(a, b, c);";
    assert_eq!(
        fusible_builtins(probe).len(),
        3,
        "{:?}",
        fusible_builtins(probe)
    );
}

#[test]
fn the_test_gpus_kernels_take_the_exact_path() {
    let Some(gpu) = common::gpu() else { return };
    let spec = specialisations()[0];
    let mut kernels = vec![&gpu.kernel, gpu.compute_kernel(spec).unwrap()];
    if gpu.has_ray_query() {
        kernels.push(gpu.ray_query_kernel().unwrap());
    }
    for k in kernels {
        assert_eq!(
            k.exactness(),
            Exactness::NoContraction,
            "{} on {}",
            k.traversal_name(),
            gpu.describe()
        );
    }
}

/// A red Phong sphere whose specular power falls through the subnormal range around the
/// highlight (ks large, the light dim, n = 64): in its green and blue channels, the only
/// light is that power, so every subnormal term would show.
const SUBNORMAL_SCENE: &str = r#"
ambient = [0.2, 0.2, 0.2]
[camera]
eye = [0.0, 0.0, 5.0]
look_at = [0.0, 0.0, 0.0]
up = [0.0, 1.0, 0.0]
fov = 45.0
width = 160
height = 120
[[lights]]
position = [-4.0, 4.0, 6.0]
color = [1.0, 0.5, 0.25]
[materials.red]
model = "phong"
ka = [1.0, 0.0, 0.0]
kd = [1.0, 0.0, 0.0]
ks = [1.0, 0.75, 0.5]
n = 64.0
[[spheres]]
center = [0.0, 0.0, 0.0]
radius = 1.0
material = "red"
"#;

fn subnormals(img: &glint::image::Image) -> usize {
    img.pixels
        .iter()
        .flat_map(|p| p[..3].iter())
        .filter(|x| x.is_subnormal())
        .count()
}

#[test]
fn subnormal_shading_terms_are_flushed_and_every_tracer_agrees() {
    let scene = glint::scene::Scene::parse(SUBNORMAL_SCENE, "subnormal.toml".as_ref()).unwrap();
    let (buf, spec) = common::buffers(&scene, 160, 120, glint::scene::TriangleAlgorithm::Naive);
    let c = glint::cpu::render_f32(&buf, spec);
    assert_eq!(subnormals(&c), 0, "the CPU tracer keeps subnormal channels");
    let r = glint::cpu::render_f64(&scene, &buf, spec);
    assert_eq!(
        subnormals(&r),
        0,
        "the f64 reference keeps subnormal channels"
    );
    // The twin: the scene does reach the subnormal range. Some pixel's power, computed by
    // squaring without the flush, is subnormal; `phong_power` gives 0 there.
    let m = &buf.materials[0];
    let raw = |base: f32| {
        let (mut r, mut b, mut e) = (1.0f32, base, m.n_int as u32);
        while e != 0 {
            if e & 1 != 0 {
                r *= b;
            }
            b *= b;
            e >>= 1;
        }
        r
    };
    let base = 0.25f32; // 0.25^64 = 2^-128: subnormal
    assert!(raw(base).is_subnormal());
    assert_eq!(glint::cpu::trace::phong_power(base, m), 0.0);
    let Some(gpu) = common::gpu() else { return };
    let g = common::render_gpu(gpu, &buf, spec);
    assert_eq!(subnormals(&g), 0, "the GPU keeps subnormal channels");
    common::check_agreement(&g, &c, common::bit_exact_expected(gpu)).unwrap();
}
