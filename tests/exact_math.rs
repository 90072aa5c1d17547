//! Correctly rounded division and square root on the GPU (`shaders/exact.wgsl`): the WGSL
//! functions return IEEE 754's `/` and `sqrt` in every bit under a simulated inexact driver
//! (and `pow_det` its CPU twin's bits),
//! and every GPU test scene rendered with `--inexact-driver` equals the CPU mirror in every
//! bit with exact math (and differs with fast math: the twin). The CPU twin of the
//! functions is checked exhaustively in `tests/exact_twin.rs`.

mod common;

gpu_sentinel!();

use std::path::Path;

use common::specials;
use glint::buffers::{Math, MathMode, SceneBuffers, Specialisation};
use glint::scene::Scene;

/// The same bits, or both NaN (a NaN's payload is not part of the contract).
fn same(a: f32, b: f32) -> bool {
    a.to_bits() == b.to_bits() || (a.is_nan() && b.is_nan())
}

// ---- the WGSL functions on the test GPU --------------------------------------------------

/// A compute shader that applies `div_rn`, `sqrt_rn` and `pow_det` to pairs of bit patterns
/// (`x` and `y` of each input; the bits move through f32 loads and stores unchanged).
const PROBE: &str = r#"
@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) id: vec3<u32>) {
    let i = id.x;
    if i >= arrayLength(&input) {
        return;
    }
    let a = input[i].x;
    let b = input[i].y;
    output[i] = bitcast<vec4<f32>>(vec4<u32>(
        bitcast<u32>(div_rn(a, b)),
        bitcast<u32>(sqrt_rn(a)),
        bitcast<u32>(pow_det(a, b)),
        0u,
    ));
}
"#;

/// `div_rn`, `sqrt_rn` and `pow_det` of each pair on the GPU, with the math mode's constants.
fn probe_gpu(gpu: &glint::gpu::Gpu, pairs: &[[u32; 2]], math: MathMode) -> Vec<[u32; 4]> {
    let source = format!(
        "{}{}{PROBE}",
        include_str!("../shaders/exact.wgsl"),
        common::PROBE_BINDINGS
    );
    let b = |x: bool| if x { 1.0 } else { 0.0 };
    let constants = [
        ("EXACT_MATH", b(math.math != Math::Fast)),
        ("INEXACT_DRIVER", b(math.inexact_driver)),
    ];
    let input: Vec<[f32; 4]> = pairs
        .iter()
        .map(|p| [f32::from_bits(p[0]), f32::from_bits(p[1]), 0.0, 0.0])
        .collect();
    common::run_probe_with(gpu, &source, &constants, &input, pairs.len(), pairs.len())
        .into_iter()
        .map(|o| o.map(f32::to_bits))
        .collect()
}

/// Pairs for the GPU: every special against every special, then random bit patterns and
/// random normal pairs.
fn gpu_pairs() -> Vec<[u32; 2]> {
    let s = specials();
    let mut v: Vec<[u32; 2]> = s
        .iter()
        .flat_map(|a| s.iter().map(move |b| [a.to_bits(), b.to_bits()]))
        .collect();
    let mut rng = common::Rng::new(48);
    for _ in 0..1 << 18 {
        let r = rng.next_u64();
        v.push([r as u32, (r >> 32) as u32]);
        let q = rng.next_u64();
        // Normal floats of moderate exponent: the kernel's everyday operands.
        let normal = |x: u32| (x & 0x807f_ffff) | (((x >> 23) % 60 + 97) << 23);
        v.push([normal(q as u32), normal((q >> 32) as u32)]);
        // A Phong power's arguments: x in (0, 1], y in (0, 2048).
        let x = (r as u32) % 0x3f80_0001;
        v.push([x, ((q >> 40) as f32 * 1.220_703_1e-4).to_bits()]);
    }
    v
}

/// How many GPU results differ from Rust's `/` and `sqrt` and from the twin's `pow_det`
/// (NaN matching NaN); the first few are printed.
fn wrong(pairs: &[[u32; 2]], got: &[[u32; 4]]) -> usize {
    let shown = std::cell::Cell::new(0);
    pairs
        .iter()
        .zip(got)
        .filter(|(p, g)| {
            let (a, b) = (f32::from_bits(p[0]), f32::from_bits(p[1]));
            let bad = !same(f32::from_bits(g[0]), a / b)
                || !same(f32::from_bits(g[1]), a.sqrt())
                || !same(f32::from_bits(g[2]), glint::cpu::exact::pow_det(a, b));
            if bad && shown.replace(shown.get() + 1) < 5 {
                eprintln!(
                    "a = {a:e}, b = {b:e}: GPU a/b, sqrt a, pow_det(a, b) = {:e} {:e} {:e}; CPU {:e} {:e} {:e}",
                    f32::from_bits(g[0]),
                    f32::from_bits(g[1]),
                    f32::from_bits(g[2]),
                    a / b,
                    a.sqrt(),
                    glint::cpu::exact::pow_det(a, b)
                );
            }
            bad
        })
        .count()
}

/// How many GPU division and square-root results differ from Rust's.
fn wrong_div_sqrt(pairs: &[[u32; 2]], got: &[[u32; 4]]) -> usize {
    pairs
        .iter()
        .zip(got)
        .filter(|(p, g)| {
            let (a, b) = (f32::from_bits(p[0]), f32::from_bits(p[1]));
            !same(f32::from_bits(g[0]), a / b) || !same(f32::from_bits(g[1]), a.sqrt())
        })
        .count()
}

#[test]
fn the_wgsl_replacements_are_ieee_on_the_gpu_under_an_inexact_driver() {
    let Some(gpu) = common::gpu() else { return };
    let pairs = gpu_pairs();
    for inexact_driver in [true, false] {
        let corrected = MathMode {
            math: Math::Corrected,
            inexact_driver,
        };
        let got = probe_gpu(gpu, &pairs, corrected);
        assert_eq!(
            wrong(&pairs, &got),
            0,
            "{} pairs on {}, inexact driver: {inexact_driver}",
            pairs.len(),
            gpu.describe()
        );
    }
    // The twin: the raw operations under the same simulated driver are wrong often.
    let fast = MathMode {
        math: Math::Fast,
        inexact_driver: true,
    };
    let raw = probe_gpu(gpu, &pairs, fast);
    let bad = wrong(&pairs, &raw);
    assert!(
        bad > pairs.len() / 4,
        "fast math under the inexact driver: only {bad} wrong"
    );
}

/// Where glint trusts the driver's own `/` and `sqrt` (`gpu::rounds_correctly`), they are
/// IEEE 754's on every pair of normal operands with a normal quotient (subnormals follow the
/// driver's flush policy: Mesa 26.1 flushes them in compute).
#[test]
fn the_driver_glint_trusts_rounds_correctly() {
    let Some(gpu) = common::gpu() else { return };
    if !gpu.kernel.native_rounding() {
        eprintln!(
            "{}: not trusted; every division is corrected",
            gpu.describe()
        );
        return;
    }
    let normal = |x: f32| x.is_normal();
    let pairs: Vec<[u32; 2]> = gpu_pairs()
        .into_iter()
        .filter(|p| {
            let (a, b) = (f32::from_bits(p[0]), f32::from_bits(p[1]));
            normal(a) && normal(b) && normal(a / b)
        })
        .collect();
    assert!(pairs.len() > 200_000);
    let fast = MathMode {
        math: Math::Fast,
        inexact_driver: false,
    };
    let got = probe_gpu(gpu, &pairs, fast);
    assert_eq!(
        wrong_div_sqrt(&pairs, &got),
        0,
        "{} pairs on {}",
        pairs.len(),
        gpu.describe()
    );
}

// ---- whole scenes ----------------------------------------------------------------------

/// Every scene the GPU tests render that ships with the repository, plus vertex grids
/// with each triangle algorithm, at a small size.
fn scenes() -> Vec<(String, Scene)> {
    let mut v = Vec::new();
    for name in [
        "sphere",
        "triangle",
        "umbrella",
        "bb8",
        "mitsubishi",
        "bb8-shadows",
        "bb8-mirror",
        "bb8-aa",
        "mitsubishi-shadows",
        "whitted",
        "textured",
        "spot",
        "suzanne-ply",
    ] {
        let path = format!("{}/scenes/{name}.toml", env!("CARGO_MANIFEST_DIR"));
        v.push((name.to_string(), Scene::load(&path).expect(&path)));
    }
    // A non-integer Phong exponent: `pow_det`.
    let path = format!("{}/scenes/bb8.toml", env!("CARGO_MANIFEST_DIR"));
    let src = std::fs::read_to_string(&path)
        .unwrap()
        .replace("n = 64.0", "n = 63.7");
    assert!(src.contains("n = 63.7"));
    let scene = Scene::parse(&src, Path::new(&path)).unwrap();
    v.push(("bb8 with n = 63.7".to_string(), scene));
    for algo in ["naive", "moller-trumbore", "watertight"] {
        for eye in [[0.0, 0.0, 0.0], [1000.0, -2000.0, 500.0]] {
            let src = common::vertex_grid_scene(eye, algo, 64, 48, 4);
            let scene = Scene::parse(&src, Path::new("vertex-grid.toml")).unwrap();
            v.push((format!("vertex grid {algo} at {eye:?}"), scene));
        }
    }
    v
}

/// The GPU's image of `scene` at 64×48 with `math`, against the mirror's, through the
/// scene's own specialised pipeline, as a render takes it. (Not the general kernel: each
/// of its pipelines costs a cold lavapipe 20 to 25 s to compile, a specialised one a few
/// seconds, and CI starts every driver cold.)
fn scene_diff(gpu: &glint::gpu::Gpu, scene: &Scene, math: MathMode) -> glint::compare::Diff {
    let buf = SceneBuffers::new(scene, 64, 48, scene.triangle);
    let spec = Specialisation::for_scene(&buf).with_math(math);
    let g = common::render_gpu(gpu, &buf, spec);
    let c = glint::cpu::render_f32(&buf, spec);
    glint::compare::diff(&g, &c)
}

/// The scenes whose image with fast math must differ from the mirror's.
const TWINS: [&str; 3] = [
    "sphere",
    "suzanne-ply",
    "vertex grid moller-trumbore at [0.0, 0.0, 0.0]",
];

/// Every GPU test scene whose index in `scenes()` is `half` modulo 2, through its own
/// pipeline with exact math under the simulated inexact driver, is the mirror in every
/// bit; on the twins among them fast math is not. (The sweep is two tests so that the
/// harness compiles their pipelines on two threads: a cold lavapipe spends minutes on it.)
fn inexact_driver_sweep(half: usize) {
    let Some(gpu) = common::gpu() else { return };
    assert!(
        common::bit_exact_expected(gpu),
        "the test GPU must take the exact SPIR-V path: {}",
        gpu.describe()
    );
    let exact = MathMode {
        math: Math::Exact,
        inexact_driver: true,
    };
    let fast = MathMode {
        math: Math::Fast,
        inexact_driver: true,
    };
    let all = scenes();
    let twins = all
        .iter()
        .enumerate()
        .filter(|(k, (name, _))| k % 2 == half && TWINS.contains(&name.as_str()))
        .count();
    let mut fast_differs = Vec::new();
    for (name, scene) in all.into_iter().skip(half).step_by(2) {
        let d = scene_diff(gpu, &scene, exact);
        assert!(d.bit_exact(), "{name}, exact math, inexact driver: {d:?}");
        // The twin, on three scenes: the driver's raw (perturbed) results differ.
        if TWINS.contains(&name.as_str()) {
            let f = scene_diff(gpu, &scene, fast);
            eprintln!(
                "{name}: exact = mirror; fast: {} pixels differ in some bit, {} hit/miss",
                f.differing_bits, f.hit_miss
            );
            fast_differs.push(!f.bit_exact());
        }
    }
    assert_eq!(fast_differs.len(), twins, "a twin scene is missing");
    assert!(
        fast_differs.iter().all(|&d| d),
        "fast math gave the mirror's bits: {fast_differs:?}"
    );
}

#[test]
fn every_gpu_test_scene_is_the_mirror_under_an_inexact_driver() {
    inexact_driver_sweep(0);
}

#[test]
fn every_gpu_test_scene_is_the_mirror_under_an_inexact_driver_second_half() {
    inexact_driver_sweep(1);
}

/// Both halves together hold every scene once and every twin.
#[test]
fn the_inexact_driver_sweep_covers_every_scene_and_twin() {
    let names: Vec<String> = scenes().into_iter().map(|(n, _)| n).collect();
    let halves: Vec<Vec<&String>> = (0..2)
        .map(|h| names.iter().skip(h).step_by(2).collect())
        .collect();
    assert_eq!(halves[0].len() + halves[1].len(), names.len());
    for t in TWINS {
        assert!(names.iter().any(|n| n == t), "twin {t} is not a scene");
    }
    let twins: usize = halves
        .iter()
        .map(|h| h.iter().filter(|n| TWINS.contains(&n.as_str())).count())
        .sum();
    assert_eq!(twins, TWINS.len(), "every twin in one half");
}

/// `glint compare SCENE --inexact-driver [extra]` on the tests' adapter: exit status and
/// standard output.
fn glint_compare(scene: &str, extra: &[&str]) -> (Option<i32>, String) {
    let d = common::Scratch::new(&format!("exact-compare-{}", extra.len()));
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join(format!("scenes/{scene}.toml"));
    let mut c = common::glint_command();
    c.args(["compare", path.to_str().unwrap(), "--size", "64x48"])
        .args(["--inexact-driver", "--diff"])
        .arg(d.join("d.png"))
        .args(extra);
    if let Ok(adapter) = std::env::var("GLINT_ADAPTER") {
        c.args(["--adapter", &adapter]);
    }
    let o = c.output().unwrap();
    common::status_and_text(&o)
}

#[test]
fn glint_compare_exits_0_with_exact_math_and_1_with_fast() {
    let Some(gpu) = common::gpu() else { return };
    assert!(common::bit_exact_expected(gpu), "{}", gpu.describe());
    let (code, out) = glint_compare("bb8", &[]);
    assert_eq!(code, Some(0), "{out}");
    assert!(
        out.contains("equal by every bit (colour, hit/miss, t): yes"),
        "{out}"
    );
    // The twin: the perturbed raw division and square root reach the image.
    let (code, out) = glint_compare("bb8", &["--math", "fast"]);
    assert_eq!(code, Some(1), "{out}");
    assert!(out.contains("NO (exit status 1)"), "{out}");
}
