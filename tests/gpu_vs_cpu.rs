//! The GPU kernel against its CPU mirror, on every seed scene with every triangle
//! algorithm: bit for bit on lavapipe.

mod common;

gpu_sentinel!();

use common::{SEED_SCENES, buffers, check_agreement, render_gpu, seed_scene};
use glint::buffers::RayIn;
use glint::scene::TriangleAlgorithm;

#[test]
fn seed_scenes_agree_on_every_algorithm() {
    let Some(gpu) = common::gpu() else { return };
    let lavapipe = common::bit_exact_expected(gpu);
    for name in SEED_SCENES {
        let scene = seed_scene(name);
        for algo in TriangleAlgorithm::ALL {
            let (buf, spec) = buffers(&scene, 640, 480, algo);
            let g = render_gpu(gpu, &buf, spec);
            let c = glint::cpu::render_f32(&buf, spec);
            assert!(
                !g.is_blank() && g.hit_count() > 1000,
                "{name}/{algo}: GPU image is blank"
            );
            assert!(
                !c.is_blank() && c.hit_count() > 1000,
                "{name}/{algo}: CPU image is blank"
            );
            let d =
                check_agreement(&g, &c, lavapipe).unwrap_or_else(|e| panic!("{name}/{algo}: {e}"));
            eprintln!(
                "{name}/{algo}: {} differing pixels, {} hit/miss",
                d.differing_pixels, d.hit_miss
            );
        }
    }
}

/// The general pipeline (everything compiled in, the BVH on, as the bench's "general" rows
/// run it) agrees with the CPU mirror run with the same constants, and gives the specialised
/// pipeline's image.
#[test]
fn general_pipeline_agrees() {
    let Some(gpu) = common::gpu() else { return };
    let lavapipe = common::bit_exact_expected(gpu);
    for name in ["sphere", "umbrella", "mitsubishi", "mitsubishi-shadows"] {
        let scene = seed_scene(name);
        for algo in TriangleAlgorithm::ALL {
            let (buf, spec) = buffers(&scene, 320, 240, algo);
            let general = glint::buffers::Specialisation::general(&buf);
            assert_ne!(general, spec, "{name}: the general pipeline must differ");
            let g = render_gpu(gpu, &buf, general);
            let c = glint::cpu::render_f32(&buf, general);
            check_agreement(&g, &c, lavapipe)
                .unwrap_or_else(|e| panic!("{name}/{algo} general: {e}"));
            let specialised = glint::cpu::render_f32(&buf, spec);
            assert!(
                glint::compare::diff(&c, &specialised).bit_exact(),
                "{name}/{algo}: the general pipeline changes the image"
            );
        }
    }
}

/// The twin: one pixel changed by one ULP, or one hit turned into a miss, fails the check.
#[test]
fn agreement_check_fails_on_perturbed_image() {
    let scene = seed_scene("umbrella");
    let (buf, spec) = buffers(&scene, 64, 48, TriangleAlgorithm::MollerTrumbore);
    let c = glint::cpu::render_f32(&buf, spec);
    assert!(check_agreement(&c, &c, true).is_ok());
    let mut ulp = c.clone();
    let k = ulp
        .pixels
        .iter()
        .position(|p| p[3] >= 0.0 && p[0] > 0.0)
        .expect("a lit pixel");
    ulp.pixels[k][0] = f32::from_bits(ulp.pixels[k][0].to_bits() + 1);
    assert!(
        check_agreement(&ulp, &c, true).is_err(),
        "one ULP must fail on lavapipe"
    );
    // The hit distance is compared in every bit too (one ULP of t, colours unchanged).
    let mut far = c.clone();
    far.pixels[k][3] = f32::from_bits(far.pixels[k][3].to_bits() + 1);
    let d = glint::compare::diff(&far, &c);
    assert_eq!((d.differing_bits, d.differing_t), (0, 1));
    assert!(
        check_agreement(&far, &c, true).is_err(),
        "one ULP of t must fail on lavapipe"
    );
    let mut miss = c.clone();
    miss.pixels[k][3] = -1.0;
    assert!(check_agreement(&miss, &c, true).is_err());
    let mut many = c.clone();
    for p in many.pixels.iter_mut().step_by(7) {
        p[1] = (p[1] + 0.5) % 1.0;
    }
    assert!(
        check_agreement(&many, &c, false).is_err(),
        "gross differences must fail the tolerance too"
    );
}

/// The `query` entry point: random rays into the BB-8 scene give the same hits, bit for bit.
#[test]
fn query_entry_point_agrees() {
    let Some(gpu) = common::gpu() else { return };
    let scene = seed_scene("bb8");
    let mut rng = common::Rng::new(11);
    let rays: Vec<RayIn> = (0..20_000)
        .map(|_| RayIn {
            origin: [
                rng.range(-3.0, 3.0),
                rng.range(-3.0, 3.0),
                rng.range(3.0, 8.0),
            ],
            t_min: 0.0,
            dir: [rng.range(-0.5, 0.5), rng.range(-0.5, 0.5), -1.0],
            t_max: f32::MAX,
        })
        .collect();
    for algo in TriangleAlgorithm::ALL {
        let (buf, spec) = buffers(&scene, 64, 64, algo);
        let g = gpu
            .compute_kernel(spec)
            .expect("kernel")
            .query(&gpu.device, &gpu.queue, &buf, spec, &rays)
            .expect("query");
        let c = glint::cpu::query_f32(&buf, spec, &rays);
        let hits = c
            .iter()
            .filter(|h| h.prim != glint::buffers::PRIM_NONE)
            .count();
        assert!(
            hits > 2000,
            "{algo}: only {hits} hits: the rays miss the scene"
        );
        if common::bit_exact_expected(gpu) {
            let bad = g
                .iter()
                .zip(&c)
                .filter(|(a, b)| bytemuck::bytes_of(*a) != bytemuck::bytes_of(*b))
                .count();
            assert_eq!(
                bad,
                0,
                "{algo}: {bad} of {} query results differ",
                rays.len()
            );
        } else {
            // Other adapters round `dot`, `normalize` and fused products their own way: the
            // same tolerance as the images, 0.01 % hit/miss disagreements.
            let hit_miss = g
                .iter()
                .zip(&c)
                .filter(|(a, b)| {
                    (a.prim == glint::buffers::PRIM_NONE) != (b.prim == glint::buffers::PRIM_NONE)
                })
                .count();
            eprintln!(
                "{algo} on {}: {hit_miss} hit/miss disagreements",
                gpu.describe()
            );
            assert!(
                hit_miss * 10_000 <= rays.len(),
                "{algo}: {hit_miss} hit/miss"
            );
        }
    }
}

fn shading_scene(n: &str, light: [f32; 3]) -> glint::scene::Scene {
    let src = format!(
        r#"
ambient = [0.2, 0.2, 0.2]
[camera]
eye = [0.0, 0.0, 4.0]
look_at = [0.0, 0.0, 0.0]
fov = 50.0
width = 96
height = 72
[[lights]]
position = {light:?}
color = [1.0, 1.0, 1.0]
[materials.m]
model = "phong"
ka = [0.3, 0.2, 0.1]
kd = [0.5, 0.5, 0.5]
ks = [1.0, 0.5, 0.25]
n = {n}
[[spheres]]
center = [0.0, 0.0, 0.0]
radius = 1.0
material = "m"
[[triangles]]
vertices = [[-2.0, -1.2, -1.0], [2.0, -1.2, -1.0], [0.0, -1.2, 2.0]]
material = "m"
"#
    );
    glint::scene::Scene::parse(&src, "shading.toml".as_ref()).unwrap()
}

/// Shading edge cases through both tracers: n = 0 (0^0 = 1 where R·V ≤ 0), a very large
/// integer n, a light in the floor's plane (N·L = 0 there) and behind the sphere, and
/// non-integer n (`pow_det`, the same function on both sides, compiled in only for them:
/// `POWERS`).
#[test]
fn shading_edge_cases_agree() {
    let Some(gpu) = common::gpu() else { return };
    let lavapipe = common::bit_exact_expected(gpu);
    let cases = [
        ("0.0", [3.0, 3.0, 3.0]),
        ("1000000.0", [3.0, 3.0, 3.0]),
        ("16777216.0", [-3.0, 2.0, 3.0]),
        ("28.0", [5.0, -1.2, 0.0]),
        ("28.0", [0.0, 0.0, -3.0]),
        ("10.5", [3.0, 3.0, 3.0]),
        ("0.37", [-3.0, 2.0, 3.0]),
        ("1000.25", [3.0, 3.0, 3.0]),
    ];
    for (n, light) in cases {
        let scene = shading_scene(n, light);
        let (buf, spec) = buffers(&scene, 96, 72, TriangleAlgorithm::Watertight);
        let integer = n.parse::<f32>().unwrap().fract() == 0.0;
        assert_eq!(buf.materials[0].n_int >= 0, integer, "n = {n}");
        // `pow_det` is compiled in exactly where a non-integer exponent needs it, and
        // compiling it in where none does changes no bit.
        assert_eq!(spec.powers, !integer, "n = {n}");
        if integer {
            let with = glint::buffers::Specialisation {
                powers: true,
                ..spec
            };
            let (a, b) = (render_gpu(gpu, &buf, spec), render_gpu(gpu, &buf, with));
            assert!(glint::compare::diff(&a, &b).bit_exact(), "n = {n}: POWERS");
        }
        let g = render_gpu(gpu, &buf, spec);
        let c = glint::cpu::render_f32(&buf, spec);
        assert!(
            g.pixels.iter().all(|p| p.iter().all(|x| !x.is_nan())),
            "n = {n}: NaN colour"
        );
        check_agreement(&g, &c, lavapipe)
            .unwrap_or_else(|e| panic!("n = {n}, light {light:?}: {e}"));
    }
}

/// Both traversals of the compute tracer, the per-ray one (`trace.wgsl`'s own) and the
/// packet one (`trace_subgroup.wgsl`: one packet per subgroup, where the device has
/// subgroups), give the CPU mirror's image in every bit, on the seed scenes, a shadowed
/// mesh and the vertex grid with and without shadows, with every triangle algorithm; and
/// their `query` entry points give the mirror's hits.
#[test]
fn both_traversals_agree() {
    let Some(gpu) = common::gpu() else { return };
    let lavapipe = common::bit_exact_expected(gpu);
    let per_ray = glint::gpu::Kernel::new(&gpu.device).expect("per-ray kernel");
    assert!(!gpu.kernel.is_packet());
    let subgroups = gpu.device.features().contains(wgpu::Features::SUBGROUP);
    let (packet, packet_ray_shadows) = if subgroups {
        let packet = |shadows| glint::gpu::Kernel::new_packet_with(&gpu.device, shadows);
        (
            Some(packet(true).expect("packet kernel")),
            Some(packet(false).expect("packet kernel, shadow rays per ray")),
        )
    } else {
        eprintln!(
            "\n*** no subgroups on {}: the packet traversal was NOT checked ***\n",
            gpu.describe()
        );
        assert!(gpu.packet_kernel().expect("kernel").is_none());
        (None, None)
    };
    let mut scenes: Vec<(String, glint::scene::Scene)> = ["bb8-shadows", "mitsubishi", "umbrella"]
        .iter()
        .map(|n| (n.to_string(), seed_scene(n)))
        .collect();
    let grid = common::vertex_grid_scene([0.25, -0.5, 0.75], "watertight", 160, 120, 4);
    scenes.push((
        "vertex grid".into(),
        glint::scene::Scene::parse(&grid, std::path::Path::new("grid.toml")).unwrap(),
    ));
    // The same bumpy field with shadows on: shadow rays leave it together (the packet
    // `occluded_bvh`), and its bumps shadow each other.
    let shadowed = grid.replacen("ambient =", "shadows = true\nambient =", 1);
    scenes.push((
        "vertex grid, shadows".into(),
        glint::scene::Scene::parse(&shadowed, std::path::Path::new("grid.toml")).unwrap(),
    ));
    for (name, scene) in &scenes {
        for algo in TriangleAlgorithm::ALL {
            let (buf, spec) = buffers(scene, 200, 150, algo);
            let c = glint::cpu::render_f32(&buf, spec);
            let kernels = [
                ("per-ray", Some(&per_ray)),
                ("packet", packet.as_ref()),
                ("packet, shadow rays per ray", packet_ray_shadows.as_ref()),
            ];
            for (what, k) in kernels {
                let Some(k) = k else { continue };
                assert_eq!(k.traversal_name(), what);
                let g = k
                    .render(&gpu.device, &gpu.queue, &buf, spec, &mut |_, _| {})
                    .expect("render")
                    .0;
                check_agreement(&g, &c, lavapipe)
                    .unwrap_or_else(|e| panic!("{name}/{algo} {what}: {e}"));
            }
        }
    }
    // Incoherent rays through `query`: a packet of rays that go everywhere.
    let scene = seed_scene("bb8");
    let (buf, spec) = buffers(&scene, 64, 48, TriangleAlgorithm::Watertight);
    let mut rng = common::Rng::new(9);
    let rays: Vec<RayIn> = (0..4099)
        .map(|_| RayIn {
            origin: [
                rng.range(-3.0, 3.0),
                rng.range(-3.0, 3.0),
                rng.range(2.0, 8.0),
            ],
            t_min: 0.0,
            dir: [
                rng.range(-1.0, 1.0),
                rng.range(-1.0, 1.0),
                rng.range(-1.0, 0.2),
            ],
            t_max: f32::MAX,
        })
        .collect();
    let want = glint::cpu::query_f32(&buf, spec, &rays);
    for k in [Some(&per_ray), packet.as_ref(), packet_ray_shadows.as_ref()]
        .into_iter()
        .flatten()
    {
        let got = k
            .query(&gpu.device, &gpu.queue, &buf, spec, &rays)
            .expect("query");
        let differ = got
            .iter()
            .zip(&want)
            .filter(|(a, b)| bytemuck::bytes_of(*a) != bytemuck::bytes_of(*b))
            .count();
        if lavapipe {
            assert_eq!(differ, 0, "query, {}", k.traversal_name());
        }
    }
}

/// The lean frame (`render_rgba8`, what `glint render` reads back for a PNG) against the
/// mirror's f32 frame quantised by the mirror's `pack_rgba8`: equal in every byte on
/// lavapipe, for both traversals (and the ray-query tracer, where the adapter has it,
/// against its own f32 frame); elsewhere at most 0.1 % of pixels differ, each by at most one step a channel.
#[test]
fn lean_frame_is_the_mirror_quantised() {
    let Some(gpu) = common::gpu() else { return };
    let lavapipe = common::bit_exact_expected(gpu);
    let scenes = [
        ("bb8-shadows", TriangleAlgorithm::MollerTrumbore),
        ("umbrella", TriangleAlgorithm::Watertight),
        ("mitsubishi", TriangleAlgorithm::Naive),
        ("bb8-aa", TriangleAlgorithm::Watertight),
    ];
    for (name, algo) in scenes {
        let scene = seed_scene(name);
        // 203×101: tiles and packets cut at odd places.
        let (buf, spec) = buffers(&scene, 203, 101, algo);
        let want: Vec<u32> = glint::cpu::render_f32(&buf, spec)
            .pixels
            .iter()
            .map(|p| glint::cpu::common::pack_rgba8(*p))
            .collect();
        let mut kernels = vec![("per-ray", &gpu.kernel)];
        if let Some(packet) = gpu.packet_kernel().expect("packet kernel") {
            kernels.push(("packet", packet));
        }
        if gpu.has_ray_query() {
            kernels.push((
                "ray-query",
                gpu.ray_query_kernel().expect("ray-query kernel"),
            ));
        }
        for (tracer, kernel) in kernels {
            let got = common::render_gpu_rgba8(gpu, kernel, &buf, spec);
            let what = format!("{name}/{algo} {tracer}");
            // The ray-query tracer's triangles are the driver's (`tests/ray_query.rs` holds
            // it to its own allowance): its lean frame is checked against its own f32 frame.
            let want = if kernel.is_ray_query() {
                let f = kernel
                    .render(&gpu.device, &gpu.queue, &buf, spec, &mut |_, _| {})
                    .expect("render")
                    .0;
                f.pixels
                    .iter()
                    .map(|p| glint::cpu::common::pack_rgba8(*p))
                    .collect()
            } else {
                want.clone()
            };
            lean_agreement(&got, &want, lavapipe).unwrap_or_else(|e| panic!("{what}: {e}"));
            // What `glint render` calls: the same bytes, and the host's geometry freed
            // once the device has it (the counts kept).
            let mut released = buf.clone();
            let w = buf.params.width as usize;
            let mut again = vec![0u32; got.len()];
            kernel
                .render_bands_rgba8_releasing(
                    &gpu.device,
                    &gpu.queue,
                    &mut released,
                    spec,
                    37,
                    &mut |y, px| {
                        again[y as usize * w..y as usize * w + px.len()].copy_from_slice(px)
                    },
                )
                .expect("GPU render (lean frame, releasing)");
            lean_agreement(&again, &want, lavapipe)
                .unwrap_or_else(|e| panic!("{what}, releasing: {e}"));
            assert!(released.triangles.is_empty() && released.nodes.is_empty());
            assert!(released.prim_ids.is_empty() && released.normals.is_empty());
            assert_eq!(released.params, buf.params, "{what}: the counts stay");
            eprintln!("{what}: {} pixels equal in every byte", want.len());
        }
    }
}

/// Whether the lean frame `got` agrees with `want` (see `lean_frame_is_the_mirror_quantised`).
fn lean_agreement(got: &[u32], want: &[u32], lavapipe: bool) -> Result<(), String> {
    if got.len() != want.len() {
        return Err(format!("{} pixels, not {}", got.len(), want.len()));
    }
    let step = |a: u32, b: u32| {
        (0..4)
            .map(|k| ((a >> (8 * k)) as u8).abs_diff((b >> (8 * k)) as u8))
            .max()
            .unwrap_or(0)
    };
    let differ: Vec<usize> = (0..got.len()).filter(|&i| got[i] != want[i]).collect();
    if let Some(&i) = differ.first() {
        let worst = differ
            .iter()
            .map(|&i| step(got[i], want[i]))
            .max()
            .unwrap_or(0);
        if lavapipe || worst > 1 || differ.len() * 1000 > got.len() {
            return Err(format!(
                "{} pixels differ (the first, pixel {i}: {:#010x} against {:#010x}; \
                 the largest step {worst})",
                differ.len(),
                got[i],
                want[i]
            ));
        }
    }
    Ok(())
}

/// The twin: one channel of one pixel one step off fails on lavapipe; a pixel two steps
/// off fails everywhere.
#[test]
fn lean_agreement_fails_on_a_perturbed_frame() {
    let scene = seed_scene("umbrella");
    let (buf, spec) = buffers(&scene, 64, 48, TriangleAlgorithm::MollerTrumbore);
    let want: Vec<u32> = glint::cpu::render_f32(&buf, spec)
        .pixels
        .iter()
        .map(|p| glint::cpu::common::pack_rgba8(*p))
        .collect();
    assert!(lean_agreement(&want, &want, true).is_ok());
    let k = want
        .iter()
        .position(|&p| p & 0xFF > 2)
        .expect("a red pixel");
    let mut one = want.clone();
    one[k] -= 1;
    assert!(lean_agreement(&one, &want, true).is_err());
    assert!(lean_agreement(&one, &want, false).is_ok());
    let mut two = want.clone();
    two[k] -= 2;
    assert!(lean_agreement(&two, &want, false).is_err());
}

/// `Kernel::render_into` (what the bench's timed runs call) over an image that held
/// something else, NaN in every channel, of the same size or another: the fresh render's
/// pixels, bit for bit; and its twin, the stale image before it is drawn over, fails.
#[test]
fn rendering_into_a_used_image_equals_a_fresh_render() {
    let Some(gpu) = common::gpu() else { return };
    let (buf, spec) = buffers(
        &seed_scene("bb8-shadows"),
        97,
        61,
        TriangleAlgorithm::Watertight,
    );
    let kernel = gpu.compute_kernel(spec).expect("kernel");
    let (fresh, _) = kernel
        .render(&gpu.device, &gpu.queue, &buf, spec, &mut |_, _| {})
        .expect("render");
    for (w, h) in [(97, 61), (3, 2)] {
        let mut used = glint::image::Image {
            width: w,
            height: h,
            pixels: vec![[f32::NAN; 4]; (w * h) as usize],
        };
        if (w, h) == (97, 61) {
            assert!(
                common::same_bits(&used, &fresh).is_err(),
                "the twin: a stale image must fail"
            );
        }
        kernel
            .render_into(
                &gpu.device,
                &gpu.queue,
                &buf,
                spec,
                &mut used,
                &mut |_, _| {},
            )
            .expect("render_into");
        common::same_bits(&used, &fresh).unwrap_or_else(|e| panic!("{w}x{h} before: {e}"));
    }
}
