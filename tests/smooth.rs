//! Smooth meshes (`smooth = true`) and antialiasing (`[camera] samples = N`): GPU = CPU in
//! every bit on lavapipe with each option and every triangle algorithm; one sample is
//! today's image; the vertex normals are what the docs say; bad input names file, line and
//! key; and the shadow terminator is measured, with and without Hanika's point.

// `!(x > 0)` as `shade` writes it (NaN counts as not lit).
#![allow(clippy::neg_cmp_op_on_partial_ord)]

mod common;

gpu_sentinel!();

use std::path::Path;

use common::{check_agreement, render_gpu, seed_scene};
use glint::buffers::{SceneBuffers, Specialisation};
use glint::compare::diff;
use glint::cpu::prims;
use glint::cpu::trace::{self, Camera, Globals, Hit};
use glint::scene::{Scene, TriangleAlgorithm};

/// A fresh folder for one test's files.
fn temp_dir(name: &str) -> common::Scratch {
    common::Scratch::new(&format!("smooth-{name}"))
}

/// Options of [`scene_text`].
struct Opts<'a> {
    obj: &'a str,
    smooth: bool,
    shadows: bool,
    samples: u32,
    algo: &'a str,
    light: [f32; 3],
    transform: &'a str,
    size: (u32, u32),
}

impl Default for Opts<'_> {
    fn default() -> Self {
        Opts {
            obj: "mesh.obj",
            smooth: true,
            shadows: true,
            samples: 1,
            algo: "watertight",
            light: [4.0, 3.0, 5.0],
            transform: "",
            size: (96, 72),
        }
    }
}

/// A unit-sized mesh in front of the camera, Phong-lit, over a floor.
fn scene_text(o: &Opts) -> String {
    format!(
        "ambient = [0.1, 0.1, 0.1]\nbackground = [0.0, 0.0, 0.0]\ntriangle = \"{}\"\nshadows = {}\n\
         [camera]\neye = [0.0, 0.4, 3.2]\nlook_at = [0.0, 0.0, 0.0]\nfov = 45.0\nwidth = {}\nheight = {}\nsamples = {}\n\
         [[lights]]\nposition = {:?}\ncolor = [0.9, 0.9, 0.9]\n\
         [materials.m]\nmodel = \"phong\"\nka = [0.3, 0.3, 0.3]\nkd = [0.7, 0.6, 0.5]\nks = [0.5, 0.5, 0.5]\nn = 20.0\n\
         [materials.floor]\nmodel = \"diffuse\"\nka = [0.2, 0.2, 0.2]\nkd = [0.5, 0.5, 0.5]\n\
         [[meshes]]\nfile = \"{}\"\nmaterial = \"m\"\nsmooth = {}\n{}\n\
         [[triangles]]\nvertices = [[-5.0, -1.01, -5.0], [5.0, -1.01, 5.0], [5.0, -1.01, -5.0]]\nmaterial = \"floor\"\n",
        o.algo, o.shadows, o.size.0, o.size.1, o.samples, o.light, o.obj, o.smooth, o.transform
    )
}

/// Writes `obj` and the scene of `o` into `dir` and loads it.
fn load(dir: &Path, obj: &str, o: &Opts) -> Scene {
    std::fs::write(dir.join(o.obj), obj).unwrap();
    let path = dir.join("scene.toml");
    std::fs::write(&path, scene_text(o)).unwrap();
    Scene::load(&path).unwrap_or_else(|e| panic!("{e}"))
}

fn buffers(scene: &Scene) -> (SceneBuffers, Specialisation) {
    let (w, h) = scene.size();
    let buf = SceneBuffers::new(scene, w, h, scene.triangle);
    let spec = Specialisation::for_scene(&buf);
    (buf, spec)
}

fn suzanne() -> String {
    std::fs::read_to_string(
        Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/meshes/suzanne.obj"),
    )
    .unwrap()
}

/// The GPU against the packet tracer, its baseline build and the scalar mirror, bit for bit
/// on lavapipe, with smooth normals (and shadows through Hanika's point) and with samples,
/// for every triangle algorithm, on a coarse icosphere and on Suzanne turned and squashed
/// (the inverse transpose at work).
#[test]
fn gpu_equals_cpu_with_smooth_and_samples() {
    let Some(gpu) = common::gpu() else { return };
    let lavapipe = common::bit_exact_expected(gpu);
    let dir = temp_dir("agree");
    let meshes = [
        ("ico2", glint::oracle::icosphere_obj(2), ""),
        (
            "suzanne",
            suzanne(),
            "scale = [0.9, 1.3, 0.7]\nrotate = [15.0, 30.0, 0.0]",
        ),
    ];
    for (name, obj, transform) in &meshes {
        for (smooth, samples, shadows) in [(true, 1, true), (true, 2, true), (false, 3, false)] {
            for algo in TriangleAlgorithm::ALL {
                let o = Opts {
                    smooth,
                    samples,
                    shadows,
                    algo: algo.name(),
                    transform,
                    ..Opts::default()
                };
                let scene = load(&dir, obj, &o);
                let (buf, spec) = buffers(&scene);
                assert_eq!(spec.smooth, smooth);
                assert_eq!(spec.antialias, samples > 1);
                let label = format!("{name} smooth={smooth} samples={samples} {algo}");
                let g = render_gpu(gpu, &buf, spec);
                let c = glint::cpu::render_f32(&buf, spec);
                assert!(c.hit_count() > 1000, "{label}: blank");
                check_agreement(&g, &c, lavapipe).unwrap_or_else(|e| panic!("{label}: {e}"));
                for simd in glint::cpu::packet::Simd::ALL {
                    let build = glint::cpu::render_f32_simd(&buf, spec, simd);
                    let name = simd.name();
                    assert!(diff(&c, &build).bit_exact(), "{label}: packet vs {name}");
                }
                let mirror = glint::cpu::render_f32_mirror(&buf, spec);
                assert!(diff(&c, &mirror).bit_exact(), "{label}: packet vs mirror");
            }
        }
    }
}

/// The twin: smooth and flat, or 2×2 samples and one, are different images, and the same
/// agreement check rejects each pair; so the check above would see a tracer that ignored
/// either option.
#[test]
fn the_options_change_the_image_and_the_check_sees_it() {
    let dir = temp_dir("twin");
    let obj = glint::oracle::icosphere_obj(2);
    let render = |o: &Opts| {
        let s = load(&dir, &obj, o);
        let (buf, spec) = buffers(&s);
        glint::cpu::render_f32(&buf, spec)
    };
    let smooth = render(&Opts::default());
    let flat = render(&Opts {
        smooth: false,
        ..Opts::default()
    });
    let aa = render(&Opts {
        samples: 2,
        ..Opts::default()
    });
    for (what, other) in [("flat", &flat), ("samples = 2", &aa)] {
        let d = diff(&smooth, other);
        assert!(d.differing_pixels > 100, "{what}: {d:?}");
        assert!(check_agreement(&smooth, other, true).is_err(), "{what}");
    }
}

/// `samples = 1` written out, and the pipeline with antialiasing and smooth shading
/// compiled in, give today's image to the bit, on every seed scene (CPU) and on the GPU.
#[test]
fn one_sample_is_todays_image() {
    for name in common::SEED_SCENES {
        let path = Path::new(env!("CARGO_MANIFEST_DIR")).join(format!("scenes/{name}.toml"));
        let text = std::fs::read_to_string(&path).unwrap();
        let with = text.replacen("[camera]\n", "[camera]\nsamples = 1\n", 1);
        assert_ne!(with, text);
        let a = seed_scene(name);
        let b = Scene::parse(&with, &path).unwrap();
        let (ba, sa) = common::buffers(&a, 160, 120, a.triangle);
        let (bb, sb) = common::buffers(&b, 160, 120, b.triangle);
        assert_eq!(
            (sa, &ba),
            (sb, &bb),
            "{name}: samples = 1 changed the buffers"
        );
        let today = glint::cpu::render_f32(&ba, sa);
        let compiled_in = Specialisation {
            smooth: true,
            antialias: true,
            ..sa
        };
        for img in [
            glint::cpu::render_f32(&bb, compiled_in),
            glint::cpu::render_f32_mirror(&bb, compiled_in),
        ] {
            assert!(diff(&today, &img).bit_exact(), "{name}");
        }
    }
    let Some(gpu) = common::gpu() else { return };
    let scene = seed_scene("bb8-shadows");
    let (buf, spec) = common::buffers(&scene, 160, 120, scene.triangle);
    let today = render_gpu(gpu, &buf, spec);
    let compiled_in = Specialisation {
        smooth: true,
        antialias: true,
        ..spec
    };
    assert!(diff(&today, &render_gpu(gpu, &buf, compiled_in)).bit_exact());
}

fn cross3(a: [f32; 3], b: [f32; 3]) -> [f32; 3] {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

fn unit3(a: [f32; 3]) -> [f32; 3] {
    let l = (a[0] * a[0] + a[1] * a[1] + a[2] * a[2]).sqrt();
    [a[0] / l, a[1] / l, a[2] / l]
}

/// At a vertex (barycentrics (1,0,0), (0,1,0), (0,0,1)) the interpolated normal is that
/// vertex's normal and of unit length, to f32 rounding; in between it is unit length too.
#[test]
fn interpolated_normals_at_the_vertices_are_the_vertex_normals() {
    let dir = temp_dir("vertices");
    let scene = load(&dir, &suzanne(), &Opts::default());
    let (buf, spec) = buffers(&scene);
    let g = Globals {
        cam: Camera::from_params(&buf.params),
        buf: &buf,
        spec,
        count: glint::cpu::count::NoCount,
    };
    let first = scene.smooth[0].first;
    let mut checked = 0;
    for k in (0..scene.smooth[0].normals.len()).step_by(7) {
        let id = (first + k) as u32;
        let tri = &buf.triangles[id as usize];
        let vn = &buf.normals[tri.normals as usize];
        let e1: [f32; 3] = std::array::from_fn(|i| tri.b[i] - tri.a[i]);
        let e2: [f32; 3] = std::array::from_fn(|i| tri.c[i] - tri.a[i]);
        let gn = cross3(e1, e2);
        if gn == [0.0; 3] {
            continue;
        }
        for (u, v, p, want) in [
            (0.0, 0.0, tri.a, vn.na),
            (1.0, 0.0, tri.b, vn.nb),
            (0.0, 1.0, tri.c, vn.nc),
            (0.25, 0.5, tri.a, [f32::NAN; 3]),
        ] {
            // The facing normal on the vertex normal's side, as `shade` would pass it.
            let side = if want[0].is_nan() { vn.na } else { want };
            let s = if gn[0] * side[0] + gn[1] * side[1] + gn[2] * side[2] < 0.0 {
                -1.0
            } else {
                1.0
            };
            let hit = Hit {
                t: 1.0,
                prim: id | glint::buffers::TRIANGLE_BIT,
                u,
                v,
                inst: 0,
            };
            let n = unit3([gn[0] * s, gn[1] * s, gn[2] * s]);
            let sh = prims::shading_at(&g, &hit, p.into(), n.into());
            let got: [f32; 3] = sh.n.into();
            let len = (got[0] * got[0] + got[1] * got[1] + got[2] * got[2]).sqrt();
            assert!((len - 1.0).abs() < 4e-7, "length {len}");
            if !want[0].is_nan() {
                for i in 0..3 {
                    assert!(
                        (got[i] - want[i]).abs() <= 2.5e-7,
                        "triangle {k}: {got:?} vs vertex normal {want:?}"
                    );
                }
            }
            checked += 1;
        }
    }
    assert!(checked > 1000, "{checked}");
}

/// The test's own vertex normals, as the docs describe them: area-weighted (Gouraud: each
/// triangle adds its unnormalised cross product), in f64, then each normalised and rounded
/// to f32. With `angle`, each triangle adds its unit normal times its angle at the vertex
/// (Thürmer and Wüthrich) instead: the twin.
fn vertex_normals(obj: &str, angle: bool) -> (Vec<[f32; 3]>, Vec<[usize; 3]>) {
    let mut v: Vec<[f64; 3]> = Vec::new();
    let mut f: Vec<[usize; 3]> = Vec::new();
    for line in obj.lines() {
        let w: Vec<&str> = line.split_whitespace().collect();
        match w.first() {
            Some(&"v") => v.push([1, 2, 3].map(|k| w[k].parse::<f32>().unwrap() as f64)),
            Some(&"f") => {
                let ix: Vec<usize> = w[1..]
                    .iter()
                    .map(|s| s.split('/').next().unwrap().parse::<usize>().unwrap() - 1)
                    .collect();
                for k in 2..ix.len() {
                    f.push([ix[0], ix[k - 1], ix[k]]);
                }
            }
            _ => {}
        }
    }
    let sub = |a: [f64; 3], b: [f64; 3]| [a[0] - b[0], a[1] - b[1], a[2] - b[2]];
    let cross = |a: [f64; 3], b: [f64; 3]| {
        [
            a[1] * b[2] - b[1] * a[2],
            a[2] * b[0] - b[2] * a[0],
            a[0] * b[1] - b[0] * a[1],
        ]
    };
    let dot = |a: [f64; 3], b: [f64; 3]| a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
    let len = |a: [f64; 3]| dot(a, a).sqrt();
    let corner = |a: [f64; 3], b: [f64; 3]| len(cross(a, b)).atan2(dot(a, b));
    let mut acc = vec![[0.0f64; 3]; v.len()];
    for t in &f {
        let [p0, p1, p2] = t.map(|k| v[k]);
        let n = cross(sub(p1, p0), sub(p2, p0));
        let l = len(n);
        for c in 0..3 {
            let add = if angle {
                if l == 0.0 {
                    continue;
                }
                let w = [
                    corner(sub(p1, p0), sub(p2, p0)),
                    corner(sub(p2, p1), sub(p0, p1)),
                    corner(sub(p0, p2), sub(p1, p2)),
                ][c];
                [n[0] / l * w, n[1] / l * w, n[2] / l * w]
            } else {
                n
            };
            for i in 0..3 {
                acc[t[c]][i] += add[i];
            }
        }
    }
    let out = acc
        .iter()
        .map(|a| {
            let l = len(*a);
            [(a[0] / l) as f32, (a[1] / l) as f32, (a[2] / l) as f32]
        })
        .collect();
    (out, f)
}

/// `obj`'s positions and triangles with `normals` written out as `vn`, each corner naming
/// its vertex's normal.
fn with_vn(obj: &str, normals: &[[f32; 3]], faces: &[[usize; 3]]) -> String {
    let mut s: String = obj
        .lines()
        .filter(|l| l.starts_with("v "))
        .map(|l| format!("{l}\n"))
        .collect();
    for n in normals {
        s += &format!("vn {} {} {}\n", n[0], n[1], n[2]);
    }
    for [a, b, c] in faces {
        s += &format!(
            "f {}//{} {}//{} {}//{}\n",
            a + 1,
            a + 1,
            b + 1,
            b + 1,
            c + 1,
            c + 1
        );
    }
    s
}

/// A mesh without `vn` gets exactly the normals of the same mesh with its area-weighted
/// normals written out as `vn`, under a transform that scales unevenly; the twin writes
/// angle-weighted normals and gets different ones, so the equality is about the weighting.
#[test]
fn computed_normals_equal_the_same_normals_written_out() {
    let dir = temp_dir("vn");
    let transform =
        "scale = [1.5, 0.5, 2.0]\nrotate = [30.0, -20.0, 45.0]\ntranslate = [0.1, 0.2, 0.3]";
    for (name, obj) in [
        ("ico1", glint::oracle::icosphere_obj(1)),
        ("suzanne", suzanne()),
    ] {
        let o = Opts {
            transform,
            ..Opts::default()
        };
        let computed = load(&dir, &obj, &o);
        let (n, faces) = vertex_normals(&obj, false);
        let written = load(&dir, &with_vn(&obj, &n, &faces), &o);
        assert_eq!(computed.triangles, written.triangles, "{name}");
        assert_eq!(computed.smooth, written.smooth, "{name}");
        let (n_angle, _) = vertex_normals(&obj, true);
        let angle = load(&dir, &with_vn(&obj, &n_angle, &faces), &o);
        if name == "suzanne" {
            assert_ne!(computed.smooth, angle.smooth, "{name}: the twin");
        }
        // The transform carried them: unit length, and not the file's.
        for tri in &written.smooth[0].normals {
            for m in tri {
                let l = (m[0] * m[0] + m[1] * m[1] + m[2] * m[2]).sqrt();
                assert!((l - 1.0).abs() < 4e-7, "{name}: {m:?}");
            }
        }
        assert_ne!(written.smooth[0].normals[0][0], n[faces[0][0]]);
    }
}

/// An OBJ with an MTL (read by tobj) gets the same smooth normals as the same geometry
/// read by glint's own reader: the normals line up with tobj's triangles.
#[test]
fn tobj_path_pairs_normals_with_its_triangles() {
    let dir = temp_dir("tobj");
    let obj = suzanne();
    let own = load(&dir, &obj, &Opts::default());
    std::fs::write(dir.join("m.mtl"), "newmtl red\nKd 0.8 0.1 0.1\n").unwrap();
    let with_mtl = format!("mtllib m.mtl\nusemtl red\n{obj}");
    std::fs::write(dir.join("mtl.obj"), &with_mtl).unwrap();
    let text = scene_text(&Opts {
        obj: "mtl.obj",
        ..Opts::default()
    })
    .replace("material = \"m\"\nsmooth", "smooth");
    std::fs::write(dir.join("scene.toml"), text).unwrap();
    let tobj = Scene::load(dir.join("scene.toml")).unwrap_or_else(|e| panic!("{e}"));
    let tris = |s: &Scene| s.triangles.iter().map(|t| t.vertices).collect::<Vec<_>>();
    assert_eq!(tris(&own), tris(&tobj));
    assert_eq!(own.smooth[0].normals, tobj.smooth[0].normals);
}

/// Bad input: the error names the file, the line and the key (and the OBJ's own line).
#[test]
fn bad_samples_and_normals_are_clear_errors() {
    let dir = temp_dir("errors");
    let tri = "v 0 0 0\nv 1 0 0\nv 0 1 0\n";
    let cases: Vec<(String, String, &[&str])> = vec![
        (
            tri.to_string() + "f 1 2 3\n",
            scene_text(&Opts::default()).replace("samples = 1", "samples = 0"),
            &["scene.toml:", ": camera.samples: 0 must be in 1..=16"],
        ),
        (
            tri.to_string() + "f 1 2 3\n",
            scene_text(&Opts::default()).replace("samples = 1", "samples = 100000"),
            &[": camera.samples: 100000 must be in 1..=16"],
        ),
        (
            tri.to_string() + "vn 0 0 1\nf 1//1 2//1 3//2\n",
            scene_text(&Opts::default()),
            &[
                ": meshes[0].file: mesh ",
                "line 5: face normal index 2 is out of range",
            ],
        ),
        (
            tri.to_string() + "vn 0 0 0\nf 1//1 2//1 3//1\n",
            scene_text(&Opts::default()),
            &[
                ": meshes[0].file: mesh ",
                "line 4: a normal (`vn`) has zero length",
            ],
        ),
        (
            tri.to_string() + "f 1 2 3\n",
            scene_text(&Opts {
                transform: "scale = [1.0, 0.0, 1.0]",
                ..Opts::default()
            }),
            &["face 0: its normal does not survive the transform"],
        ),
    ];
    for (obj, scene, wants) in cases {
        std::fs::write(dir.join("mesh.obj"), obj).unwrap();
        let path = dir.join("scene.toml");
        std::fs::write(&path, &scene).unwrap();
        let e = Scene::load(&path).expect_err(wants[0]).to_string();
        for w in wants {
            assert!(e.contains(w), "{e:?} lacks {w:?}");
        }
        assert!(e.contains(&path.display().to_string()), "{e}");
    }
    // The line of the key: samples is on line 10 of the scene text.
    let scene = scene_text(&Opts::default()).replace("samples = 1", "samples = 0");
    let line = scene.lines().position(|l| l == "samples = 0").unwrap() + 1;
    std::fs::write(dir.join("scene.toml"), scene).unwrap();
    let e = Scene::load(dir.join("scene.toml")).unwrap_err().to_string();
    assert!(
        e.contains(&format!("scene.toml:{line}: camera.samples")),
        "{e}"
    );
    // A flat mesh's bad normals are not looked at: files that load today still load.
    std::fs::write(
        dir.join("mesh.obj"),
        tri.to_string() + "vn 0 0 0\nf 1//1 2//1 3//1\n",
    )
    .unwrap();
    let flat = scene_text(&Opts {
        smooth: false,
        ..Opts::default()
    });
    std::fs::write(dir.join("scene.toml"), flat).unwrap();
    Scene::load(dir.join("scene.toml")).unwrap();
}

/// The shadow terminator, measured with the mirror's own functions on a coarse smooth
/// icosphere lit from the side: pixels whose smooth normal faces the light but whose shadow
/// ray is blocked by the sphere's own triangles. From the hit point itself (what a flat
/// renderer would do) the blocks of whole triangles appear along the terminator; from
/// Hanika's point they are a small fraction. The analytic sphere has none.
#[test]
fn hanikas_point_removes_most_of_the_shadow_terminator() {
    let dir = temp_dir("terminator");
    let mut counts = Vec::new();
    for k in [1u32, 2] {
        let scene = load(
            &dir,
            &glint::oracle::icosphere_obj(k),
            &Opts {
                light: [6.0, 0.5, -1.0],
                size: (240, 180),
                ..Opts::default()
            },
        );
        let (buf, spec) = buffers(&scene);
        let g = Globals {
            cam: Camera::from_params(&buf.params),
            buf: &buf,
            spec,
            count: glint::cpu::count::NoCount,
        };
        let light: glint::cpu::real::V3<f32> = buf.lights[0].position.into();
        let (mut plain, mut hanika, mut lit) = (0, 0, 0);
        for j in 0..buf.params.height {
            for i in 0..buf.params.width {
                let ray = trace::camera_ray(&g, i, j, 0.5, 0.5);
                let hit = trace::closest_hit(&g, ray, 0.0, f32::MAX);
                if hit.prim == glint::buffers::PRIM_NONE
                    || buf.triangles[(hit.prim & !glint::buffers::TRIANGLE_BIT) as usize].normals
                        == glint::buffers::FLAT
                {
                    continue;
                }
                let p = ray.origin + ray.dir * hit.t;
                let mut n = prims::prim_normal(&g, &hit, p);
                if n.dot(ray.dir) > 0.0 {
                    n = -n;
                }
                let sh = prims::shading_at(&g, &hit, p, n);
                if !(sh.n.dot((light - p).normalize()) > 0.0) {
                    continue;
                }
                lit += 1;
                let blocked = |from| {
                    let o = trace::shadow_origin(from, n);
                    let r = trace::Ray {
                        origin: o,
                        dir: light - o,
                    };
                    trace::occluded(&g, r, 0.0, 1.0, hit.prim, 0)
                };
                plain += blocked(p) as u32;
                hanika += blocked(sh.p) as u32;
            }
        }
        eprintln!(
            "icosphere k={k}: {lit} pixels face the light; self-shadowed from the hit point {plain}, from Hanika's point {hanika}"
        );
        counts.push((lit, plain, hanika));
    }
    for (lit, plain, hanika) in counts {
        assert!(lit > 2000);
        assert!(plain > 100, "the scene must show the artefact: {plain}");
        assert!(hanika * 5 <= plain, "Hanika's point: {hanika} vs {plain}");
    }
}

/// A frame with 16×16 samples a pixel is dispatched in several tiles (each with N² times
/// fewer pixels), reports progress per tile, and still equals the CPU image.
#[test]
fn many_samples_still_tile_and_report_progress() {
    let Some(gpu) = common::gpu() else { return };
    let lavapipe = common::bit_exact_expected(gpu);
    let mut scene = seed_scene("sphere");
    scene.camera.samples = 16;
    let (buf, spec) = common::buffers(&scene, 128, 160, scene.triangle);
    assert!(spec.antialias);
    let mut calls = Vec::new();
    let (g, _) = gpu
        .compute_kernel(spec)
        .expect("kernel")
        .render(&gpu.device, &gpu.queue, &buf, spec, &mut |done, all| {
            calls.push((done, all))
        })
        .expect("render");
    assert!(calls.len() >= 2, "{calls:?}");
    assert_eq!(calls.last(), Some(&(160, 160)));
    let c = glint::cpu::render_f32(&buf, spec);
    check_agreement(&g, &c, lavapipe).unwrap();
}
