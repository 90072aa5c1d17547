//! A frame larger than one dispatch or one buffer allows is rendered in tiles: 8192×8192
//! on the GPU adapter, compared with the CPU mirror on rows at and around every tile seam.

mod common;

gpu_sentinel!();

use common::{buffers, seed_scene};
use glint::cpu::trace::{Camera, Globals, trace_pixel};

#[test]
fn frame_of_8192_squared_renders_in_tiles() {
    let Some(gpu) = common::gpu() else { return };
    let scene = seed_scene("umbrella");
    let (buf, spec) = buffers(&scene, 8192, 8192, scene.triangle);
    let rows = glint::gpu::tile_rows(&gpu.device, 8192, 8192);
    assert!(
        rows < 8192,
        "one tile would hold the frame: the test proves nothing"
    );
    let mut calls = Vec::new();
    let (img, _) = gpu
        .compute_kernel(spec)
        .expect("kernel")
        .render(&gpu.device, &gpu.queue, &buf, spec, &mut |d, n| {
            calls.push((d, n))
        })
        .expect("8192x8192 render");
    eprintln!("8192x8192 in {} tiles of {rows} rows", calls.len());
    assert_eq!(calls.len() as u32, 8192u32.div_ceil(rows));
    assert_eq!(calls.last(), Some(&(8192, 8192)));
    assert!(img.hit_count() > 8192 * 8192 / 10);

    // Rows on both sides of every seam, plus the first and last, against the CPU mirror.
    let g = Globals {
        cam: Camera::from_params(&buf.params),
        buf: &buf,
        spec,
        count: glint::cpu::count::NoCount,
    };
    let lavapipe = common::bit_exact_expected(gpu);
    let mut checked = 0;
    let mut rows_to_check: Vec<u32> = vec![0, 8191];
    for k in 1..8192u32.div_ceil(rows) {
        rows_to_check.extend([k * rows - 1, k * rows]);
    }
    for j in rows_to_check {
        for i in (0..8192).step_by(7) {
            let c = trace_pixel(&g, i, j);
            let p = img.pixels[(j * 8192 + i) as usize];
            if lavapipe {
                assert_eq!(
                    c.map(f32::to_bits),
                    p.map(f32::to_bits),
                    "pixel ({i}, {j}) differs"
                );
            } else {
                assert_eq!(c[3] < 0.0, p[3] < 0.0, "pixel ({i}, {j}): hit/miss differs");
            }
            checked += 1;
        }
    }
    eprintln!("{checked} pixels on the tile seams checked against the CPU mirror");
}

/// A scene larger than the device's buffers: `--backend gpu` fails naming the buffer and
/// both sizes; `auto` on that adapter falls back to the CPU tracer, says so in one line, and
/// renders. (`GLINT_MAX_BUFFER_BYTES` gives this adapter a smaller GPU's 1 MB limit, so
/// 30,000 triangles, 1.44 MB, do not fit.)
#[test]
fn scenes_larger_than_the_gpu_fall_back_to_the_cpu_under_auto() {
    let Some(gpu) = common::gpu() else { return };
    let d = common::Scratch::new("toolarge");
    let scene = common::too_large_scene(&d);
    let run = |backend: &str| {
        common::glint_command()
            .args(["render", scene.to_str().unwrap(), "-o"])
            .arg(d.join("out.png"))
            .args(["--backend", backend, "--adapter", &gpu.info.name])
            .env("GLINT_MAX_BUFFER_BYTES", "1000000")
            .output()
            .unwrap()
    };
    let o = run("gpu");
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success(), "the GPU must refuse: {err}");
    assert!(
        err.contains("triangles needs 1440000 bytes") && err.contains("1000000"),
        "{err}"
    );
    let o = run("auto");
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "{err}");
    assert_eq!(
        err.matches("so the CPU tracer renders this").count(),
        1,
        "{err}"
    );
    // "cpu (f32, avx512)", or whichever packet build this CPU runs.
    let out = String::from_utf8_lossy(&o.stdout);
    assert!(out.contains("cpu (f32, "), "{out}");
}
