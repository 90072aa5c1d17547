//! The assumptions the bit-exact mirror rests on, checked on the GPU adapter itself: WGSL's
//! `dot`, `normalize`, `sqrt` and the arithmetic `cpu::real::V3` writes out give the same
//! bits as the Rust code (on lavapipe; other adapters are reported, not asserted).

mod common;

gpu_sentinel!();

use glint::cpu::real::V3;

const PROBE: &str = r#"
@group(0) @binding(0) var<storage, read> input: array<vec4<f32>>;
@group(0) @binding(1) var<storage, read_write> output: array<vec4<f32>>;

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
    let out = common::run_probe(gpu, PROBE, &input, 4 * n);
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
    if common::is_lavapipe(gpu) {
        assert_eq!(bad, 0, "{msg}");
    } else {
        eprintln!("adapter {}: {msg} (reported only)", gpu.describe());
    }
}
