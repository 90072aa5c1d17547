//! Instances: a named mesh placed again by `[[instances]]`, traced through the two-level
//! BVH. An identity instance is the mesh placed directly, in every bit, on every tracer;
//! the GPU is its mirror in every bit on lavapipe, scaled, rotated, mirrored, overlapping
//! and glass instances included; a transformed instance is the mesh transformed at load,
//! up to rounding; bad entries are errors naming the file, the line and the key.

mod common;

gpu_sentinel!();

use common::{check_agreement, render_gpu, same_bits};
use glint::buffers::{SceneBuffers, Specialisation};
use glint::image::Image;
use glint::scene::{Scene, TriangleAlgorithm};

/// A scene in `scenes/` (so that `suzanne.ply` is found): a floor, two lights with
/// shadows, a mirror and a glass material, and `body` (meshes and instances).
fn scene_text(body: &str) -> String {
    format!(
        r#"ambient = [0.1, 0.1, 0.12]
background = [0.06, 0.07, 0.1]
shadows = true
max_depth = 4

[camera]
eye = [0.0, 3.5, 7.0]
look_at = [0.0, -0.2, 0.0]
fov = 45.0
width = 160
height = 120

[[lights]]
position = [-3.0, 6.0, 5.0]
color = [0.8, 0.75, 0.7]

[[lights]]
position = [5.0, 3.0, 2.0]
color = [0.25, 0.3, 0.4]

[materials.gold]
model = "phong"
ka = [0.5, 0.38, 0.12]
kd = [0.75, 0.56, 0.18]
ks = [0.8, 0.75, 0.6]
n = 40.0

[materials.mirror]
model = "phong"
ka = [0.02, 0.02, 0.02]
kd = [0.05, 0.05, 0.05]
ks = [0.6, 0.6, 0.6]
n = 80.0
kr = [0.85, 0.85, 0.85]

[materials.glass]
model = "phong"
ka = [0.0, 0.0, 0.0]
kd = [0.02, 0.02, 0.02]
ks = [0.5, 0.5, 0.5]
n = 60.0
kt = [0.9, 0.9, 0.9]
ior = 1.5
fresnel = true

[materials.floor]
model = "diffuse"
ka = [0.35, 0.35, 0.4]
kd = [0.45, 0.45, 0.5]

[[triangles]]
vertices = [[-8.0, -1.0, -8.0], [8.0, -1.0, 8.0], [8.0, -1.0, -8.0]]
material = "floor"

[[triangles]]
vertices = [[-8.0, -1.0, -8.0], [-8.0, -1.0, 8.0], [8.0, -1.0, 8.0]]
material = "floor"

{body}"#
    )
}

fn parse(text: &str) -> Scene {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/instances-test.toml");
    Scene::parse(text, &path).unwrap_or_else(|e| panic!("{e}"))
}

fn buffers(scene: &Scene, algo: TriangleAlgorithm) -> (SceneBuffers, Specialisation) {
    common::buffers(scene, 160, 120, algo)
}

/// The mesh placed by its own entry, then the same mesh hidden and placed by an instance
/// with no transform, and the second moved by `nudge` in y.
fn direct_and_identity(nudge: f32) -> (Scene, Scene) {
    let mesh = |extra: &str| {
        format!(
            "[[meshes]]\nfile = \"suzanne.ply\"\nmaterial = \"gold\"\nsmooth = true\nrotate = [0.0, 20.0, 0.0]\n{extra}"
        )
    };
    let direct = parse(&scene_text(&mesh("")));
    let instance = if nudge == 0.0 {
        String::new()
    } else {
        format!("translate = [0.0, {nudge:?}, 0.0]\n")
    };
    let placed = parse(&scene_text(&format!(
        "{}\n[[instances]]\nmesh = \"suzanne\"\n{instance}",
        mesh("name = \"suzanne\"\nhidden = true\n")
    )));
    assert!(direct.instances.is_empty() && placed.instances.len() == 1);
    (direct, placed)
}

#[test]
fn an_identity_instance_is_the_mesh_placed_directly_in_every_bit() {
    let (direct, placed) = direct_and_identity(0.0);
    let gpu = common::gpu();
    for algo in TriangleAlgorithm::ALL {
        let (a, sa) = buffers(&direct, algo);
        let (b, sb) = buffers(&placed, algo);
        assert!(!sa.instances && sb.instances);
        let ca = glint::cpu::render_f32(&a, sa);
        assert!(ca.hit_count() > 5000, "{algo}: the mesh is in view");
        same_bits(&ca, &glint::cpu::render_f32(&b, sb))
            .unwrap_or_else(|e| panic!("{algo} f32: {e}"));
        same_bits(
            &glint::cpu::render_f64(&direct, &a, sa),
            &glint::cpu::render_f64(&placed, &b, sb),
        )
        .unwrap_or_else(|e| panic!("{algo} f64: {e}"));
        if let Some(gpu) = gpu {
            same_bits(&render_gpu(gpu, &a, sa), &render_gpu(gpu, &b, sb))
                .unwrap_or_else(|e| panic!("{algo} gpu: {e}"));
        }
    }
}

/// The twin: an instance moved by a thousandth is a different picture.
#[test]
fn a_nudged_instance_is_not_the_mesh_placed_directly() {
    let (direct, placed) = direct_and_identity(1e-3);
    let algo = TriangleAlgorithm::Watertight;
    let (a, sa) = buffers(&direct, algo);
    let (b, sb) = buffers(&placed, algo);
    assert!(
        same_bits(
            &glint::cpu::render_f32(&a, sa),
            &glint::cpu::render_f32(&b, sb)
        )
        .is_err()
    );
}

/// Suzanne placed seven times: scaled, rotated, mirrored (negative scale), overlapping
/// (two at one place), touching the floor, a mirror and a glass instance (total internal
/// reflection inside it), and the named mesh drawn where its entry puts it.
const MANY: &str = r#"
[[meshes]]
name = "suzanne"
file = "suzanne.ply"
material = "gold"
smooth = true

[[instances]]
mesh = "suzanne"
translate = [-2.5, 0.0, -1.0]
rotate = [0.0, 30.0, 0.0]
material = "mirror"

[[instances]]
mesh = "suzanne"
translate = [2.5, 0.0, -1.0]
scale = [-1.0, 1.0, 1.0]

[[instances]]
mesh = "suzanne"
translate = [2.5, 0.0, -1.0]
rotate = [0.0, 90.0, 0.0]
scale = [0.9, 0.9, 0.9]

[[instances]]
mesh = "suzanne"
translate = [-1.2, -0.5, 2.0]
scale = [0.5, 0.5, 0.5]
material = "glass"

[[instances]]
mesh = "suzanne"
translate = [1.2, -0.2, 2.0]
scale = [0.8, -0.8, 0.8]
rotate = [10.0, -40.0, 5.0]

[[instances]]
mesh = "suzanne"
translate = [0.0, 0.0, -4.0]
scale = [3.0, 1.5, 1.0]
"#;

fn many(nudge: &str) -> Scene {
    parse(&scene_text(&MANY.replacen("[-2.5, 0.0, -1.0]", nudge, 1)))
}

#[test]
fn instanced_scenes_on_the_gpu_are_the_mirror_in_every_bit() {
    let Some(gpu) = common::gpu() else { return };
    let lavapipe = common::bit_exact_expected(gpu);
    let scene = many("[-2.5, 0.0, -1.0]");
    for algo in TriangleAlgorithm::ALL {
        let (buf, spec) = buffers(&scene, algo);
        assert!(spec.instances && spec.whitted && spec.smooth);
        let g = render_gpu(gpu, &buf, spec);
        let c = glint::cpu::render_f32(&buf, spec);
        assert!(c.hit_count() > 10_000, "{algo}: the instances are in view");
        let d = check_agreement(&g, &c, lavapipe).unwrap_or_else(|e| panic!("{algo}: {e}"));
        eprintln!(
            "{algo}: {} differing pixels, {} hit/miss",
            d.differing_pixels, d.hit_miss
        );
        // The packets' path and the mirror's own are one image.
        same_bits(&c, &glint::cpu::render_f32_mirror(&buf, spec)).unwrap();
    }
}

/// The twin: the GPU's picture is not the mirror's of a scene with one instance moved.
#[test]
fn the_gpu_comparison_sees_a_moved_instance() {
    let Some(gpu) = common::gpu() else { return };
    let algo = TriangleAlgorithm::Watertight;
    let (buf, spec) = buffers(&many("[-2.5, 0.0, -1.0]"), algo);
    let (moved, _) = buffers(&many("[-2.5, 0.001, -1.0]"), algo);
    let g = render_gpu(gpu, &buf, spec);
    assert!(check_agreement(&g, &glint::cpu::render_f32(&moved, spec), true).is_err());
}

/// The share of pixels whose 8-bit values differ between the two f64 pictures.
fn share_off(a: &Image, b: &Image) -> f64 {
    let d = glint::compare::diff(a, b);
    d.differing_pixels as f64 / d.pixels as f64
}

/// One mesh transformed by its `[[meshes]]` entry (at load, in f64, vertices rounded to
/// f32) and by an instance of the untransformed mesh (rays into object space at render
/// time), with `scale` and `rotate`: the f64 truths of the two.
fn at_load_and_instanced(scale: &str, rotate: &str) -> (Image, Image) {
    let xf = format!("scale = {scale}\nrotate = {rotate}\ntranslate = [0.3, 0.2, 0.5]\n");
    let loaded = parse(&scene_text(&format!(
        "[[meshes]]\nfile = \"suzanne.ply\"\nmaterial = \"gold\"\nsmooth = true\n{xf}"
    )));
    let instanced = parse(&scene_text(&format!(
        "[[meshes]]\nname = \"m\"\nhidden = true\nfile = \"suzanne.ply\"\nmaterial = \"gold\"\nsmooth = true\n\n[[instances]]\nmesh = \"m\"\n{xf}"
    )));
    let algo = TriangleAlgorithm::Watertight;
    let (a, sa) = buffers(&loaded, algo);
    let (b, sb) = buffers(&instanced, algo);
    (
        glint::cpu::render_f64(&loaded, &a, sa),
        glint::cpu::render_f64(&instanced, &b, sb),
    )
}

#[test]
fn a_transformed_instance_is_the_mesh_transformed_at_load() {
    for (scale, rotate) in [
        ("[1.5, 1.5, 1.5]", "[0.0, 35.0, 0.0]"),
        ("[-1.0, 1.0, 1.0]", "[0.0, 0.0, 0.0]"),
        ("[0.7, 1.3, -0.9]", "[20.0, -50.0, 10.0]"),
        ("[0.05, 0.05, 0.05]", "[0.0, 90.0, 0.0]"),
    ] {
        let (a, b) = at_load_and_instanced(scale, rotate);
        assert!(a.hit_count() > 1000);
        let off = share_off(&a, &b);
        eprintln!(
            "scale {scale} rotate {rotate}: {:.4} % of pixels off in 8 bits",
            off * 100.0
        );
        assert!(off < 0.005, "scale {scale} rotate {rotate}: {off}");
    }
}

/// The twin: a degree of rotation more is seen.
#[test]
fn the_transform_comparison_sees_a_degree() {
    let xf = |r: f32| {
        format!(
            "scale = [1.5, 1.5, 1.5]\nrotate = [0.0, {r:?}, 0.0]\ntranslate = [0.3, 0.2, 0.5]\n"
        )
    };
    let loaded = parse(&scene_text(&format!(
        "[[meshes]]\nfile = \"suzanne.ply\"\nmaterial = \"gold\"\nsmooth = true\n{}",
        xf(35.0)
    )));
    let instanced = parse(&scene_text(&format!(
        "[[meshes]]\nname = \"m\"\nhidden = true\nfile = \"suzanne.ply\"\nmaterial = \"gold\"\nsmooth = true\n\n[[instances]]\nmesh = \"m\"\n{}",
        xf(36.0)
    )));
    let algo = TriangleAlgorithm::Watertight;
    let (a, sa) = buffers(&loaded, algo);
    let (b, sb) = buffers(&instanced, algo);
    let off = share_off(
        &glint::cpu::render_f64(&loaded, &a, sa),
        &glint::cpu::render_f64(&instanced, &b, sb),
    );
    assert!(off >= 0.005, "{off}");
}

/// `body` parsed, expecting an error at `line` of the scene naming `key` and saying `what`.
fn bad(body: &str, line_of: &str, key: &str, what: &str) {
    let text = scene_text(body);
    let line = text
        .lines()
        .position(|l| l.contains(line_of))
        .unwrap_or_else(|| panic!("{line_of:?} not in the scene"))
        + 1;
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/bad.toml");
    let e = Scene::parse(&text, &path)
        .expect_err("accepted")
        .to_string();
    assert!(e.contains(&format!("bad.toml:{line}: {key}")), "{e}");
    assert!(e.contains(what), "{e}");
}

#[test]
fn bad_instances_are_errors_naming_the_line_and_the_key() {
    let mesh = "[[meshes]]\nname = \"m\"\nfile = \"suzanne.ply\"\nmaterial = \"gold\"\n";
    bad(
        &format!("{mesh}[[instances]]\nmesh = \"n\"\n"),
        "mesh = \"n\"",
        "instances[0].mesh",
        "no mesh is named \"n\" (named meshes: m)",
    );
    bad(
        "[[instances]]\nmesh = \"n\"\n",
        "mesh = \"n\"",
        "instances[0].mesh",
        "give a [[meshes]] entry",
    );
    bad(
        &format!(
            "{mesh}{}",
            mesh.replace("name = \"m\"", "name = \"m\" # again")
        ),
        "# again",
        "meshes[1].name",
        "a second mesh named \"m\"",
    );
    bad(
        "[[meshes]]\nfile = \"suzanne.ply\"\nmaterial = \"gold\"\nhidden = true\n",
        "hidden = true",
        "meshes[0].hidden",
        "needs a name",
    );
    bad(
        &format!("{mesh}hidden = true\n"),
        "hidden = true",
        "meshes[0].hidden",
        "no [[instances]] entry places it",
    );
    bad(
        &format!("{mesh}[[instances]]\nmesh = \"m\"\nscale = [1.0, 0.0, 1.0]\n"),
        "scale = [1.0, 0.0",
        "instances[0].scale",
        "zero component",
    );
    bad(
        &format!("{mesh}[[instances]]\nmesh = \"m\"\nmaterial = \"chrome\"\n"),
        "material = \"chrome\"",
        "instances[0].material",
        "chrome",
    );
    bad(
        &format!("{mesh}[[instances]]\nmesh = \"m\"\ntranslate = [1.0, nan, 1.0]\n"),
        "translate = [1.0, nan",
        "instances[0].translate",
        "",
    );
    bad(
        &format!(
            "{mesh}[[instances]]\nmesh = \"m\"\nscale = [2.0, 2.0, 2.0]\nmatrix = [[1.0, 0.0, 0.0, 0.0], [0.0, 1.0, 0.0, 0.0], [0.0, 0.0, 1.0, 0.0]]\n"
        ),
        "matrix = [[1.0",
        "instances[0].matrix",
        "takes no `scale` beside it",
    );
    bad(
        &format!(
            "{mesh}[[instances]]\nmesh = \"m\"\nmatrix = [[1.0, 2.0, 3.0, 0.0], [2.0, 4.0, 6.0, 0.0], [0.0, 0.0, 1.0, 0.0]]\n"
        ),
        "matrix = [[1.0, 2.0",
        "instances[0].matrix",
        "singular",
    );
    bad(
        &format!("{mesh}[[instances]]\nmesh = \"m\"\nshear = 1.0\n"),
        "shear = 1.0",
        "",
        "shear",
    );
}

/// The README's picture of `scenes/suzanne-instances.toml` is what the code renders now
/// (regenerate: `cargo run --release -- render scenes/suzanne-instances.toml -o
/// docs/images/suzanne-instances.png --backend cpu`).
#[test]
fn the_readme_picture_of_instances_is_what_the_code_renders() {
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
    let scene = Scene::load(root.join("scenes/suzanne-instances.toml")).unwrap();
    assert_eq!(scene.instances.len(), 8);
    let (w, h) = scene.size();
    let buf = SceneBuffers::new(&scene, w, h, scene.triangle);
    let img = glint::cpu::render_f32(&buf, Specialisation::for_scene(&buf));
    let png = image::open(root.join("docs/images/suzanne-instances.png"))
        .unwrap()
        .to_rgb8();
    assert_eq!((png.width(), png.height()), (w, h));
    let ours = img.to_rgb8_encoded(scene.encoding);
    let off = ours
        .chunks(3)
        .zip(png.as_raw().chunks(3))
        .filter(|(a, b)| a != b)
        .count();
    assert_eq!(off, 0, "{off} pixels differ from the committed picture");
    // The twin: without its last instance the scene is not the picture.
    let mut fewer = scene.clone();
    fewer.instances.pop();
    let buf = SceneBuffers::new(&fewer, w, h, fewer.triangle);
    let img = glint::cpu::render_f32(&buf, Specialisation::for_scene(&buf));
    let ours = img.to_rgb8_encoded(fewer.encoding);
    assert!(
        ours.chunks(3)
            .zip(png.as_raw().chunks(3))
            .any(|(a, b)| a != b)
    );
}

/// A row of `matrix` numbers as TOML.
fn rows(m: &[[f64; 4]; 3]) -> String {
    let row = |r: &[f64; 4]| format!("[{:?}, {:?}, {:?}, {:?}]", r[0], r[1], r[2], r[3]);
    format!("[{}, {}, {}]", row(&m[0]), row(&m[1]), row(&m[2]))
}

/// A `matrix` that scale, rotate and translate round to the same f32 maps places the mesh
/// in the same bits; `Scene::add_instances` with the same rows is the same scene as the
/// file's `[[instances]]` tables.
#[test]
fn a_matrix_and_bulk_instances_place_as_the_tables_do() {
    let mesh =
        "[[meshes]]\nname = \"m\"\nhidden = true\nfile = \"suzanne.ply\"\nmaterial = \"gold\"\n";
    let maps = [
        [
            [2.0, 0.0, 0.0, 1.0],
            [0.0, 2.0, 0.0, -0.5],
            [0.0, 0.0, 2.0, -1.0],
        ],
        [
            [-1.0, 0.0, 0.0, -1.5],
            [0.0, 0.5, 0.0, -0.5],
            [0.0, 0.0, 1.0, 1.0],
        ],
    ];
    let by_srt = parse(&scene_text(&format!(
        "{mesh}[[instances]]\nmesh = \"m\"\nscale = [2.0, 2.0, 2.0]\ntranslate = [1.0, -0.5, -1.0]\n\n[[instances]]\nmesh = \"m\"\nscale = [-1.0, 0.5, 1.0]\ntranslate = [-1.5, -0.5, 1.0]\nmaterial = \"mirror\"\n"
    )));
    let by_matrix = parse(&scene_text(&format!(
        "{mesh}[[instances]]\nmesh = \"m\"\nmatrix = {}\n\n[[instances]]\nmesh = \"m\"\nmatrix = {}\nmaterial = \"mirror\"\n",
        rows(&maps[0]),
        rows(&maps[1])
    )));
    assert_eq!(by_srt.instances, by_matrix.instances);
    let mut bulk = parse(&scene_text(&format!(
        "{mesh}[[instances]]\nmesh = \"m\"\nmatrix = {}\n",
        rows(&maps[0])
    )));
    bulk.add_instances("m", &maps[1..], Some("mirror")).unwrap();
    assert_eq!(bulk.instances, by_matrix.instances);
    let algo = TriangleAlgorithm::MollerTrumbore;
    let (a, sa) = buffers(&by_srt, algo);
    let (b, sb) = buffers(&bulk, algo);
    let img = glint::cpu::render_f32(&a, sa);
    assert!(img.hit_count() > 5000);
    same_bits(&img, &glint::cpu::render_f32(&b, sb)).unwrap();
    // The twin: without the bulk instance the picture is another.
    bulk.instances.pop();
    let (c, sc) = buffers(&bulk, algo);
    assert!(same_bits(&img, &glint::cpu::render_f32(&c, sc)).is_err());
    // Refusals name what and where; nothing is added.
    let n = bulk.instances.len();
    let e = bulk
        .add_instances("x", &maps, None)
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("no mesh is named \"x\" (named meshes: m)"),
        "{e}"
    );
    let flat = [
        [1.0, 2.0, 3.0, 0.0],
        [2.0, 4.0, 6.0, 0.0],
        [0.0, 0.0, 1.0, 0.0],
    ];
    let e = bulk
        .add_instances("m", &[maps[0], flat], None)
        .unwrap_err()
        .to_string();
    assert!(e.starts_with("map 1: the map is singular"), "{e}");
    let e = bulk
        .add_instances("m", &maps, Some("chrome"))
        .unwrap_err()
        .to_string();
    assert!(e.contains("no material is named \"chrome\""), "{e}");
    assert_eq!(bulk.instances.len(), n);
}

/// The fuzzers' seed with instances (a hidden named mesh, a mirrored one, a `matrix`, a
/// drawn named mesh, a sphere and a triangle) is a valid scene, so that their mutants reach
/// the two-level build and traversal (the mesh is served from memory).
#[test]
fn the_fuzz_seed_with_instances_reaches_the_two_levels() {
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
    for target in ["scene_parse", "dict_load"] {
        let d = std::fs::read(root.join("fuzz/seeds").join(target).join("instances.toml")).unwrap();
        assert_eq!(glint::fuzzing::scene_parse(&d), Ok(()), "{target}");
        let text = std::str::from_utf8(&d).unwrap();
        let scene = Scene::parse_with(text, "fuzz.toml".as_ref(), &|p| {
            std::fs::read(root.join("scenes").join(p.file_name().unwrap()))
                .or_else(|_| Ok(glint::fuzzing::FUZZ_MESH_OBJ.as_bytes().to_vec()))
        })
        .unwrap();
        assert_eq!(scene.instances.len(), 3);
    }
}

/// A scene edited in memory is checked as a file is: an instance of no mesh, a named mesh
/// outside the triangles, a map that is not finite are errors naming the field, not panics.
#[test]
fn instances_edited_in_memory_are_validated() {
    let good = many("[-2.5, 0.0, -1.0]");
    good.validate().unwrap();
    let mut s = good.clone();
    s.instances[1].mesh = 7;
    assert!(
        s.validate()
            .unwrap_err()
            .to_string()
            .contains("instances[1].mesh")
    );
    let mut s = good.clone();
    s.instances[0].to_object[2][3] = f32::NAN;
    assert!(
        s.validate()
            .unwrap_err()
            .to_string()
            .contains("instances[0].to_object")
    );
    let mut s = good.clone();
    s.named[0].triangles = 0..s.triangles.len() + 1;
    assert!(
        s.validate()
            .unwrap_err()
            .to_string()
            .contains("named[0].triangles")
    );
    let mut s = good.clone();
    s.instances[2].material = Some(99);
    assert!(
        s.validate()
            .unwrap_err()
            .to_string()
            .contains("instances[2].material")
    );
}

/// `count` small Suzannes in a grid over the floor, each turned and scaled its own way
/// (every third mirrored), neighbours touching: a top-level tree of some depth.
fn grid(count: usize) -> Scene {
    let mut body = String::from(
        "[[meshes]]\nname = \"suzanne\"\nfile = \"suzanne.ply\"\nmaterial = \"gold\"\nhidden = true\n",
    );
    let side = (count as f64).sqrt().ceil() as usize;
    for k in 0..count {
        let (i, j) = ((k % side) as f64, (k / side) as f64);
        let s = 0.3 + 0.05 * (k % 4) as f64;
        let sx = if k % 3 == 0 { -s } else { s };
        body.push_str(&format!(
            "[[instances]]\nmesh = \"suzanne\"\ntranslate = [{:?}, -0.6, {:?}]\nscale = [{sx:?}, {s:?}, {s:?}]\nrotate = [{:?}, {:?}, 0.0]\n{}",
            (i - side as f64 / 2.0) * 0.6,
            (j - side as f64 / 2.0) * 0.6,
            (k * 7 % 30) as f64,
            (k * 37 % 360) as f64,
            if k % 5 == 0 { "material = \"mirror\"\n" } else { "" },
        ));
    }
    parse(&scene_text(&body))
}

/// The CPU's packet tracer against its mirror on instanced scenes: the same f32 bits in
/// every pixel, with every triangle algorithm and every build of the packets this CPU
/// runs, at a size that leaves partial packets, on the seven instances of `MANY` (smooth,
/// mirrored, mirror and glass: Whitted rays through the two levels) and on a grid of 64.
#[test]
fn instanced_packets_equal_the_mirror_with_every_algorithm_and_build() {
    for (what, scene) in [("many", many("[-2.5, 0.0, -1.0]")), ("grid", grid(64))] {
        for algo in TriangleAlgorithm::ALL {
            let buf = SceneBuffers::new(&scene, 67, 45, algo);
            let spec = Specialisation::for_scene(&buf);
            assert!(spec.instances && spec.shadows);
            let mirror = glint::cpu::render_f32_mirror(&buf, spec);
            assert!(mirror.hit_count() > 1_000, "{what} {algo}: in view");
            for simd in glint::cpu::packet::Simd::ALL {
                let packets = glint::cpu::render_f32_simd(&buf, spec, simd);
                same_bits(&packets, &mirror)
                    .unwrap_or_else(|e| panic!("{what} {algo} {}: {e}", simd.name()));
            }
        }
    }
}

/// The twin: the packets' picture of the grid is not the mirror's of the grid with one
/// instance fewer.
#[test]
fn the_packet_comparison_sees_an_instance_fewer() {
    let algo = TriangleAlgorithm::Watertight;
    let full = SceneBuffers::new(&grid(64), 67, 45, algo);
    let fewer = SceneBuffers::new(&grid(63), 67, 45, algo);
    let spec = Specialisation::for_scene(&full);
    let packets = glint::cpu::render_f32_simd(&full, spec, glint::cpu::packet::Simd::Best);
    assert!(same_bits(&packets, &glint::cpu::render_f32_mirror(&fewer, spec)).is_err());
}
