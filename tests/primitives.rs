//! The assumptions the bit-exact mirror rests on, checked on the GPU adapter itself: WGSL's
//! `dot`, `normalize`, `sqrt` and the arithmetic `cpu::real::V3` writes out give the same
//! bits as the Rust code (on lavapipe; other adapters are reported, not asserted).

mod common;

gpu_sentinel!();

use glint::cpu::real::V3;

/// The probe's body, after `common::PROBE_BINDINGS`: invocation i reads input 2i and 2i + 1.
const PROBE: &str = r#"
@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) gid: vec3<u32>) {
    let i = gid.x;
    if i >= arrayLength(&input) / 2u { return; }
    let a = input[2u * i].xyz;
    let b = input[2u * i + 1u].xyz;
    let n = normalize(a);
    output[4u * i] = vec4<f32>(n, dot(a, b));
    output[4u * i + 1u] = vec4<f32>(a * b + b, sqrt(abs(a.x)));
    output[4u * i + 2u] = vec4<f32>(a.y * b.z - a.z * b.y, a.x * b.y + a.z, (a.x + 0.5) / b.y * 2.0 - 1.0, 1.0 / a.z);
    output[4u * i + 3u] = vec4<f32>(a - b * (a.x / b.x), a.x * a.y * a.z);
}
"#;

fn rust_probe(a: V3<f32>, b: V3<f32>) -> [[f32; 4]; 4] {
    let n = a.normalize();
    let ab = a * b + b;
    let d = a - b * (a.x / b.x);
    [
        [n.x, n.y, n.z, a.dot(b)],
        [ab.x, ab.y, ab.z, a.x.abs().sqrt()],
        [
            a.y * b.z - a.z * b.y,
            a.x * b.y + a.z,
            (a.x + 0.5) / b.y * 2.0 - 1.0,
            1.0 / a.z,
        ],
        [d.x, d.y, d.z, a.x * a.y * a.z],
    ]
}

#[test]
fn gpu_arithmetic_matches_rust_bit_for_bit() {
    let Some(gpu) = common::gpu() else { return };
    let mut rng = common::Rng::new(7);
    let n = 20_000;
    let mut input = Vec::with_capacity(2 * n);
    for _ in 0..2 * n {
        let s = 10f32.powi(rng.range(-6.0, 6.0) as i32);
        input.push([
            rng.range(-1.0, 1.0) * s,
            rng.range(-1.0, 1.0) * s,
            rng.range(-1.0, 1.0) * s,
            0.0,
        ]);
    }
    let src = format!("{}{PROBE}", common::PROBE_BINDINGS);
    let out = common::run_probe(gpu, &src, &input, 4 * n, n);
    let mut bad = 0;
    let mut first = None;
    for i in 0..n {
        let a = V3::new(input[2 * i][0], input[2 * i][1], input[2 * i][2]);
        let b = V3::new(
            input[2 * i + 1][0],
            input[2 * i + 1][1],
            input[2 * i + 1][2],
        );
        let want = rust_probe(a, b);
        for (k, row) in want.iter().enumerate() {
            for c in 0..4 {
                let (x, y) = (row[c], out[4 * i + k][c]);
                if x.to_bits() != y.to_bits() && !(x.is_nan() && y.is_nan()) {
                    bad += 1;
                    first.get_or_insert((i, k, c, x, y));
                }
            }
        }
    }
    let msg = format!("{bad} of {} values differ; first: {first:?}", n * 16);
    if common::bit_exact_expected(gpu) {
        assert_eq!(bad, 0, "{msg}");
    } else {
        eprintln!("adapter {}: {msg} (reported only)", gpu.describe());
    }
}

/// The shader's own `clamp01`, `to_u8` and `pack_rgba8`, cut from the kernel's source.
fn quantisation_source() -> String {
    let src = glint::gpu::SHADER_SOURCE;
    let cut = |name: &str| {
        let start = src
            .find(&format!("fn {name}("))
            .unwrap_or_else(|| panic!("the kernel has no {name}"));
        let end = start + src[start..].find("\n}\n").expect("the function's end") + 3;
        src[start..end].to_string()
    };
    let mut s = String::new();
    for name in ["clamp01", "to_u8", "pack_rgba8"] {
        s += &cut(name);
    }
    s + common::PROBE_BINDINGS
        + r#"
@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) gid: vec3<u32>) {
    let i = gid.x;
    if i >= arrayLength(&input) { return; }
    let c = input[i];
    let p = pack_rgba8(c);
    output[i] = vec4<f32>(f32(to_u8(c.w)), f32(p & 0xFFu), f32((p >> 8u) & 0xFFFFu), f32(p >> 24u));
}
"#
}

/// The lean frame's quantisation: the shader's `to_u8` and `pack_rgba8` give the mirror's
/// bytes for the values where rounding turns (k + ½)/255 and its neighbours), the ends of
/// [0, 1] and past them, ±0, NaN, infinities, subnormals and random values.
#[test]
fn quantisation_matches_the_mirror_bit_for_bit() {
    let Some(gpu) = common::gpu() else { return };
    let bad = quantisation_mismatches(gpu, &quantisation_source());
    assert!(bad.is_empty(), "{} differ; first: {:?}", bad.len(), bad[0]);
    assert_eq!(
        glint::cpu::common::pack_rgba8([1.0, 0.5, 0.0, -1.0]),
        0xFF00_80FF,
        "red lowest, alpha opaque"
    );
}

/// The twin: a shader that rounds at 0.4999 instead of one half is caught.
#[test]
fn quantisation_check_catches_another_rounding() {
    let Some(gpu) = common::gpu() else { return };
    let src = quantisation_source();
    let off = src.replacen("* 255.0 + 0.5", "* 255.0 + 0.4999", 1);
    assert_ne!(off, src, "the rounding was not found in the kernel");
    assert!(!quantisation_mismatches(gpu, &off).is_empty());
}

/// (input, mirror, shader) for each probe value whose bytes differ under `src`.
#[allow(clippy::type_complexity)]
fn quantisation_mismatches(
    gpu: &glint::gpu::Gpu,
    src: &str,
) -> Vec<([f32; 4], [f32; 4], [f32; 4])> {
    use glint::cpu::common::{pack_rgba8, to_u8};
    let mut values = vec![
        0.0f32,
        -0.0,
        1.0,
        f32::NAN,
        f32::INFINITY,
        f32::NEG_INFINITY,
        f32::MIN_POSITIVE,
        1e-40,
        -1e-40,
        f32::MAX,
        -1.0,
        2.0,
    ];
    for k in 0..=256u32 {
        for x in [k as f32 / 255.0, (k as f32 + 0.5) / 255.0] {
            for d in -2i32..=2 {
                values.push(f32::from_bits(x.to_bits().wrapping_add_signed(d)));
            }
        }
    }
    let mut rng = common::Rng::new(11);
    for _ in 0..4000 {
        values.push(rng.range(-0.25, 1.25));
    }
    // Each value in every channel position: as w (`to_u8` alone) and as r, g, b.
    let input: Vec<[f32; 4]> = values
        .iter()
        .enumerate()
        .map(|(i, &v)| {
            [
                v,
                values[(i + 1) % values.len()],
                values[(i + 7) % values.len()],
                v,
            ]
        })
        .collect();
    let out = common::run_probe(gpu, src, &input, input.len(), input.len());
    let mut bad = Vec::new();
    for (c, o) in input.iter().zip(&out) {
        let p = pack_rgba8(*c);
        let want = [
            to_u8(c[3]) as f32,
            (p & 0xFF) as f32,
            ((p >> 8) & 0xFFFF) as f32,
            (p >> 24) as f32,
        ];
        if want != *o {
            bad.push((*c, want, *o));
        }
    }
    bad
}
