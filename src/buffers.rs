//! The flattening of a [`Scene`] into the buffers both tracers read ([`SceneBuffers`]),
//! and the pipeline's specialisation ([`Specialisation`]). The structs themselves, their
//! codes and constants are the contract in [`crate::shared::layout`], re-exported here.

pub use crate::shared::layout::*;

use rayon::prelude::*;

use crate::bvh::Bvh;
use crate::scene::{Model, Scene, TriangleAlgorithm};
use crate::stages::{Stages, Timings};

/// Everything a tracer reads, flattened: what goes into the GPU's buffers.
#[derive(Clone, Debug, PartialEq)]
pub struct SceneBuffers {
    /// Per-frame constants (the tile fields cover the whole image).
    pub params: Params,
    /// Spheres, in scene order.
    pub spheres: Vec<Sphere>,
    /// Triangles: the scene's own, then each mesh's.
    pub triangles: Vec<Triangle>,
    /// Materials, in the order of their first definition.
    pub materials: Vec<Material>,
    /// Point lights.
    pub lights: Vec<Light>,
    /// BVH nodes over every sphere and triangle, depth-first.
    pub nodes: Vec<BvhNode>,
    /// Primitive ids in BVH leaf order.
    pub prim_ids: Vec<u32>,
    /// The instances of a scene with `[[instances]]` (then `nodes` is the two-level BVH of
    /// [`crate::two_level`]); empty for any other. On the GPU they follow the nodes in the
    /// node buffer ([`SceneBuffers::node_words`]).
    pub instances: Vec<Instance>,
    /// Vertex normals of the smooth triangles, entry 0 unused (`Triangle::normals` = `FLAT`
    /// names no entry); empty when no triangle is smooth, and then the pipeline's `SMOOTH`
    /// is off and the shader never reads it.
    pub normals: Vec<VertexNormals>,
    /// Texture coordinates of the textured triangles, entry 0 unused (`Triangle::uvs` =
    /// `NO_UVS` names no entry); empty when no triangle is textured, and then the
    /// pipeline's `TEXTURES` is off and the shader never reads it or `texels`.
    pub uvs: Vec<TriangleUvs>,
    /// The textures, in 32-bit words: first each texture's place, a [`Texture`] (four
    /// words) in the scene's order of textures, then every texture's linear RGB texels as
    /// f32 bit patterns, three words each, rows bottom (v = 0) to top. One buffer, not a
    /// table and a texel array, so that `render` binds ten storage buffers, within what
    /// WebGPU adapters offer a shader stage (`maxStorageBuffersPerShaderStage`: 10 on
    /// Chrome's SwiftShader and most desktop adapters, 8 by default).
    pub texels: Vec<u32>,
    /// [`SceneBuffers::leaf_triangles`], made on its first call.
    leaf_triangles: std::sync::OnceLock<Vec<Triangle>>,
    /// The triangle algorithm (`TRIANGLE_*`).
    pub triangle_algo: u32,
    /// Whether shadow rays are traced.
    pub shadows: bool,
    /// How long flattening and the BVH (built, or read from the cache) took; compares
    /// equal whatever it holds ([`Timings`]).
    pub stages: Timings,
}

/// The integer form of a Phong exponent for `Material::n_int`.
pub fn exponent_as_int(n: f32) -> i32 {
    if (0.0..=16_777_216.0).contains(&n) && n.fract() == 0.0 {
        n as i32
    } else {
        -1
    }
}

/// The camera basis of the scene format (docs/scene-format.md, "Camera, shading, mirrors and glass") in f32, evaluated left to right: (forward, right, up').
pub fn camera_basis(eye: [f32; 3], look_at: [f32; 3], up: [f32; 3]) -> [[f32; 3]; 3] {
    use crate::shared::real::V3;
    crate::shared::real::camera_basis::<f32>(V3::from(eye), V3::from(look_at), V3::from(up))
        .map(Into::into)
}

impl SceneBuffers {
    /// Flattens a validated scene at `width`×`height` pixels with the given triangle algorithm.
    pub fn new(scene: &Scene, width: u32, height: u32, algo: TriangleAlgorithm) -> Self {
        let stages = Stages::new();
        let flat = flat_triangles(&scene.triangles, &scene.smooth, &stages);
        Self::with_triangles(scene, flat, (width, height), algo, None, stages).0
    }

    /// [`SceneBuffers::new`] for a scene that replaces the one `old` was made from (a file
    /// saved again): where its spheres and flattened triangles are `old`'s, `old`'s BVH is
    /// kept instead of built (the `bool`), so changed lights, materials, textures or camera
    /// cost no BVH. The same buffers as [`SceneBuffers::new`] either way.
    pub fn new_reusing(
        scene: &Scene,
        width: u32,
        height: u32,
        algo: TriangleAlgorithm,
        old: SceneBuffers,
    ) -> (Self, bool) {
        let stages = Stages::new();
        let flat = flat_triangles(&scene.triangles, &scene.smooth, &stages);
        Self::with_triangles(scene, flat, (width, height), algo, Some(old), stages)
    }

    /// The camera and frame size in `params` made `cam`'s at `width`×`height`, exactly as
    /// [`SceneBuffers::new`] sets them; everything else kept. Moving a camera needs no other
    /// buffer.
    pub fn set_camera(&mut self, cam: &crate::scene::Camera, width: u32, height: u32) {
        self.params = Params {
            samples: cam.samples.max(1),
            ..camera_params(self.params, cam, width, height)
        };
    }

    /// [`SceneBuffers::new`] for a scene that is not needed afterwards: its triangles (and
    /// smooth normals) are taken, and freed as soon as they are flattened, before the BVH
    /// is built, so the scene's copy of a large mesh and the builder's work are never in
    /// memory at once. The rest of `scene` is left as it was.
    pub fn from_scene_taking(
        scene: &mut Scene,
        width: u32,
        height: u32,
        algo: TriangleAlgorithm,
    ) -> Self {
        let (scene_triangles, smooth) = (
            std::mem::take(&mut scene.triangles),
            std::mem::take(&mut scene.smooth),
        );
        let stages = Stages::new();
        let flat = flat_triangles(&scene_triangles, &smooth, &stages);
        drop((scene_triangles, smooth));
        Self::with_triangles(scene, flat, (width, height), algo, None, stages).0
    }

    /// The buffers of `scene` whose triangles (and normals) are already flat; the BVH
    /// taken from `old` where it was made from the same primitives (then `true`).
    /// Its stages (flatten, BVH) are timed into `stages`, which the buffers keep.
    fn with_triangles(
        scene: &Scene,
        (mut triangles, normals): (Vec<Triangle>, Vec<VertexNormals>),
        (width, height): (u32, u32),
        algo: TriangleAlgorithm,
        old: Option<SceneBuffers>,
        stages: Stages,
    ) -> (Self, bool) {
        let t_flat = web_time::Instant::now();
        let uvs = triangle_uvs(&mut triangles, &scene.uvs, &scene.materials);
        let cam = &scene.camera;
        let params = Params {
            ambient: flush_colour(scene.ambient),
            background: flush_colour(scene.background),
            samples: cam.samples,
            max_depth: scene.max_depth,
            min_weight: scene.min_weight,
            ..camera_params(Params::default(), cam, width, height)
        };
        let materials: Vec<Material> = scene
            .materials
            .iter()
            .map(|m| Material {
                ka: flush_colour(m.ka),
                model: match m.model {
                    Model::Ambient => MODEL_AMBIENT,
                    Model::Diffuse => MODEL_DIFFUSE,
                    Model::Phong => MODEL_PHONG,
                },
                kd: flush_colour(m.kd),
                n: m.n,
                ks: flush_colour(m.ks),
                n_int: exponent_as_int(m.n),
                kr: flush_colour(m.optics.kr),
                ior: m.optics.ior,
                kt: flush_colour(m.optics.kt),
                fresnel: m.optics.fresnel as u32,
            })
            .collect();
        let spheres: Vec<Sphere> = scene
            .spheres
            .iter()
            .map(|s| Sphere {
                center: s.center,
                radius: s.radius,
                material: s.material,
                ..Sphere::default()
            })
            .collect();
        let lights: Vec<Light> = scene.lights.iter().map(light).collect();
        let texels = texture_buffers(&scene.textures);
        stages.record("flatten", t_flat.elapsed());
        let kept = old.filter(|o| {
            scene.instances.is_empty() && o.spheres == spheres && o.triangles == triangles
        });
        let reused = kept.is_some();
        let tree = match kept {
            Some(old) => (old.nodes, old.prim_ids, Vec::new()),
            None if !scene.instances.is_empty() => {
                let cache = scene.cache.as_deref();
                let two = crate::two_level::build(scene, &spheres, &triangles, &|s, t| {
                    cached_bvh(cache, &stages, s, t)
                });
                (two.nodes, two.prim_ids, two.instances)
            }
            None => {
                let bvh = cached_bvh(scene.cache.as_deref(), &stages, &spheres, &triangles);
                (bvh.nodes, bvh.prim_ids, Vec::new())
            }
        };
        let buf = SceneBuffers {
            normals,
            uvs,
            texels,
            stages: Timings(stages.into_times()),
            ..SceneBuffers::with_bvh(
                params,
                spheres,
                triangles,
                materials,
                lights,
                tree,
                algo,
                scene.shadows,
            )
        };
        (buf, reused)
    }

    /// The node buffer as the kernel binds it: the nodes, then each instance as four node
    /// slots (WGSL `instance_at`).
    pub fn node_words(&self) -> Vec<BvhNode> {
        let mut words = self.nodes.clone();
        words.extend_from_slice(bytemuck::cast_slice::<Instance, BvhNode>(&self.instances));
        words
    }

    /// For the CPU's packet tracer only: `triangles[prim_ids[k]]` at k (a zeroed triangle
    /// where a sphere is), so that it reads a leaf's triangles from consecutive memory.
    /// Made on the first call (by the CPU tracer before its first row, so its time is
    /// the trace's), so that a render on the GPU, which never reads it, never holds this
    /// second copy of the triangles (40 MB for the dragon).
    pub fn leaf_triangles(&self) -> &[Triangle] {
        self.leaf_triangles.get_or_init(|| {
            self.prim_ids
                .par_iter()
                .map(|&id| {
                    if (id & TRIANGLE_BIT) != 0 {
                        self.triangles[(id & !TRIANGLE_BIT) as usize]
                    } else {
                        Triangle::default()
                    }
                })
                .collect()
        })
    }

    /// Frees the geometry: the triangles, the BVH, the primitive ids, the vertex normals
    /// and the CPU's leaf-order copy. The parameters keep the counts (`params.n_triangles`,
    /// `n_nodes`); nothing can be traced from these buffers any more. For a caller whose
    /// device holds its own copy (`Kernel::render_bands_rgba8_releasing`).
    pub fn release_geometry(&mut self) {
        self.triangles = Vec::new();
        self.nodes = Vec::new();
        self.prim_ids = Vec::new();
        self.instances = Vec::new();
        self.normals = Vec::new();
        self.uvs = Vec::new();
        self.texels = Vec::new();
        self.leaf_triangles = std::sync::OnceLock::new();
    }

    /// Puts buffers together from their parts and builds the BVH over the primitives;
    /// `params.n_spheres`, `n_triangles`, `n_lights` and `n_nodes` are set from the parts,
    /// `params.samples` is at least 1, and no triangle is smooth (`normals` is empty).
    pub fn assemble(
        params: Params,
        spheres: Vec<Sphere>,
        triangles: Vec<Triangle>,
        materials: Vec<Material>,
        lights: Vec<Light>,
        algo: TriangleAlgorithm,
        shadows: bool,
    ) -> Self {
        let stages = Stages::new();
        let bvh = cached_bvh(None, &stages, &spheres, &triangles);
        SceneBuffers {
            stages: Timings(stages.into_times()),
            ..SceneBuffers::with_bvh(
                params,
                spheres,
                triangles,
                materials,
                lights,
                (bvh.nodes, bvh.prim_ids, Vec::new()),
                algo,
                shadows,
            )
        }
    }

    /// The buffers of these parts over the BVH `(nodes, prim_ids, instances)` built for them: the
    /// counts in `params` set from the parts, `samples` at least 1, no triangle smooth or
    /// textured.
    #[allow(clippy::too_many_arguments)]
    fn with_bvh(
        params: Params,
        spheres: Vec<Sphere>,
        triangles: Vec<Triangle>,
        materials: Vec<Material>,
        lights: Vec<Light>,
        (nodes, prim_ids, instances): (Vec<BvhNode>, Vec<u32>, Vec<Instance>),
        algo: TriangleAlgorithm,
        shadows: bool,
    ) -> Self {
        SceneBuffers {
            params: Params {
                n_instances: instances.len() as u32,
                n_spheres: spheres.len() as u32,
                n_triangles: triangles.len() as u32,
                n_lights: lights.len() as u32,
                n_nodes: nodes.len() as u32,
                samples: params.samples.max(1),
                ..params
            },
            spheres,
            triangles,
            materials,
            lights,
            nodes,
            prim_ids,
            instances,
            normals: Vec::new(),
            uvs: Vec::new(),
            texels: Vec::new(),
            leaf_triangles: std::sync::OnceLock::new(),
            triangle_algo: algo.code(),
            shadows,
            stages: Timings::default(),
        }
    }
}

/// `params` with the camera fields and the frame's size (its tile the whole frame) made
/// `cam`'s at `width`×`height`: the basis in f32 left to right, tan(fov / 2), the aspect.
fn camera_params(params: Params, cam: &crate::scene::Camera, width: u32, height: u32) -> Params {
    let [forward, right, up] = camera_basis(cam.eye, cam.look_at, cam.up);
    Params {
        eye: cam.eye,
        width,
        forward,
        height,
        right,
        tan_half: (cam.fov.to_radians() / 2.0).tan(),
        up,
        aspect: width as f32 / height as f32,
        tile_x: 0,
        tile_y: 0,
        tile_width: width,
        tile_height: height,
        ..params
    }
}

/// A colour as the shaders read it: a component below the smallest normal f32
/// ([`FLUSH_BELOW`]) is 0, as a driver that flushes subnormal operands would read it (a
/// product of it with a colour up to `MAX_COLOUR` can be normal, so the shading's own
/// flush could not make the drivers agree).
pub fn flush_colour(c: [f32; 3]) -> [f32; 3] {
    c.map(|x| if x.abs() < FLUSH_BELOW { 0.0 } else { x })
}

/// The pipeline's override constants: what the compiled shader contains. Must match the
/// `override` declarations at the top of `shaders/trace.wgsl`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct Specialisation {
    /// WGSL `HAS_SPHERES`.
    pub has_spheres: bool,
    /// WGSL `HAS_TRIANGLES`.
    pub has_triangles: bool,
    /// WGSL `TRIANGLE_ALGO` (`TRIANGLE_*`).
    pub triangle_algo: u32,
    /// WGSL `USES_DIFFUSE`.
    pub uses_diffuse: bool,
    /// WGSL `USES_PHONG`.
    pub uses_phong: bool,
    /// WGSL `SHADOWS`.
    pub shadows: bool,
    /// WGSL `USE_BVH`: traverse the BVH (else test every primitive).
    pub use_bvh: bool,
    /// WGSL `SMOOTH`: some triangle has vertex normals.
    pub smooth: bool,
    /// WGSL `ANTIALIAS`: `params.samples`² rays per pixel (else one through the centre).
    pub antialias: bool,
    /// WGSL `WHITTED`: some material has kr or kt and `params.max_depth` > 0, so secondary
    /// rays are traced.
    pub whitted: bool,
    /// WGSL `LIGHT_KINDS`: some light is directional or a spot.
    pub light_kinds: bool,
    /// WGSL `TEXTURES`: some triangle is textured.
    pub textures: bool,
    /// WGSL `POWERS`: some Phong material has a non-integer exponent (`pow_det` compiled
    /// in).
    pub powers: bool,
    /// WGSL `INSTANCES`: the scene has `[[instances]]`; rays go through the two-level BVH.
    pub instances: bool,
    /// WGSL `EXACT_MATH` and `INEXACT_DRIVER`: how the kernel divides and takes square
    /// roots. The CPU tracers ignore it: they divide as IEEE 754 does.
    pub math: MathMode,
}

/// How the kernel divides and takes square roots (`shaders/exact.wgsl`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum Math {
    /// Correctly rounded, whatever the driver: the GPU image is the mirror's in every bit
    /// on every conformant Vulkan driver that takes glint's SPIR-V. The kernel runs the
    /// corrections of `shaders/exact.wgsl` (WGSL `EXACT_MATH` on), except on a driver whose
    /// own `/` and `sqrt` are correctly rounded already ([`crate::gpu::rounds_correctly`]:
    /// lavapipe), where they would cost time and change no bit.
    #[default]
    Exact,
    /// The corrections always, even on a driver that rounds correctly: the same bits as
    /// [`Math::Exact`]; for the tests and for measuring what the corrections cost.
    Corrected,
    /// The driver's own `/` and `sqrt`: within Vulkan's 2.5 and 3 ULP, not always the
    /// mirror's bits (WGSL `EXACT_MATH` off).
    Fast,
}

impl std::fmt::Display for Math {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

impl std::str::FromStr for Math {
    type Err = String;
    fn from_str(s: &str) -> Result<Math, String> {
        match s {
            "exact" => Ok(Math::Exact),
            "corrected" => Ok(Math::Corrected),
            "fast" => Ok(Math::Fast),
            _ => Err(format!(
                "unknown math {s:?}: expected exact, corrected or fast"
            )),
        }
    }
}

impl Math {
    /// "exact" or "fast", as the command line spells it.
    pub fn name(self) -> &'static str {
        match self {
            Math::Exact => "exact",
            Math::Corrected => "corrected",
            Math::Fast => "fast",
        }
    }
}

/// The kernel's arithmetic mode: [`Math`], and whether the driver's first approximations
/// are made deliberately inexact (a test of the exact path on an exact driver).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub struct MathMode {
    /// Exact or fast division and square root.
    pub math: Math,
    /// WGSL `INEXACT_DRIVER`: the shader's raw `/` and `sqrt` are moved by up to ±2 ULP,
    /// differently from operation to operation and pixel to pixel, as a driver with
    /// Vulkan's 2.5-ULP allowance may round (`glint compare --inexact-driver`).
    pub inexact_driver: bool,
}

impl MathMode {
    /// What the kernel compiles on a driver that does (`native`) or does not round `/`
    /// and `sqrt` correctly: [`Math::Exact`] needs no corrections on the first, unless the
    /// driver is made inexact on purpose.
    pub fn on_driver(self, native: bool) -> MathMode {
        if native && self.math == Math::Exact && !self.inexact_driver {
            MathMode {
                math: Math::Fast,
                inexact_driver: false,
            }
        } else {
            self
        }
    }
}

/// Scenes with at most this many primitives are traced by testing every primitive: a
/// handful of intersection tests costs less than a traversal.
pub const BRUTE_FORCE_MAX: usize = 16;

impl Specialisation {
    /// Only what `buf` uses: "model only what a scene needs".
    pub fn for_scene(buf: &SceneBuffers) -> Self {
        Specialisation {
            has_spheres: !buf.spheres.is_empty(),
            has_triangles: !buf.triangles.is_empty(),
            triangle_algo: buf.triangle_algo,
            uses_diffuse: buf.materials.iter().any(|m| m.model != MODEL_AMBIENT),
            uses_phong: buf.materials.iter().any(|m| m.model == MODEL_PHONG),
            shadows: buf.shadows,
            use_bvh: buf.spheres.len() + buf.triangles.len() > BRUTE_FORCE_MAX,
            smooth: !buf.normals.is_empty(),
            antialias: buf.params.samples > 1,
            whitted: buf.params.max_depth > 0
                && buf
                    .materials
                    .iter()
                    .any(|m| m.kr.iter().chain(&m.kt).any(|&k| k > 0.0)),
            light_kinds: buf.lights.iter().any(|l| l.kind != LIGHT_POINT),
            textures: !buf.uvs.is_empty(),
            powers: buf
                .materials
                .iter()
                .any(|m| m.model == MODEL_PHONG && m.n_int < 0),
            instances: !buf.instances.is_empty(),
            math: MathMode::default(),
        }
    }

    /// Everything compiled in (the one triangle algorithm still chosen): the general
    /// pipeline that the benchmark sets beside the specialised one. It gives the same
    /// image: a flat triangle takes the geometric normal and one sample a pixel is one ray
    /// through its centre whether or not `SMOOTH` and `ANTIALIAS` are compiled in.
    pub fn general(buf: &SceneBuffers) -> Self {
        Specialisation {
            has_spheres: true,
            has_triangles: true,
            triangle_algo: buf.triangle_algo,
            uses_diffuse: true,
            uses_phong: true,
            shadows: buf.shadows,
            use_bvh: true,
            smooth: true,
            antialias: true,
            whitted: true,
            light_kinds: true,
            textures: true,
            powers: true,
            instances: !buf.instances.is_empty(),
            math: MathMode::default(),
        }
    }

    /// The same pipeline with the BVH on or off.
    pub fn with_bvh(self, use_bvh: bool) -> Self {
        Specialisation { use_bvh, ..self }
    }

    /// The same pipeline with the kernel's arithmetic `math`.
    pub fn with_math(self, math: MathMode) -> Self {
        Specialisation { math, ..self }
    }

    /// The `(name, value)` pairs for `PipelineCompilationOptions::constants`.
    pub fn constants(&self) -> [(&'static str, f64); 16] {
        let b = |x: bool| if x { 1.0 } else { 0.0 };
        [
            ("HAS_SPHERES", b(self.has_spheres)),
            ("HAS_TRIANGLES", b(self.has_triangles)),
            ("TRIANGLE_ALGO", self.triangle_algo as f64),
            ("USES_DIFFUSE", b(self.uses_diffuse)),
            ("USES_PHONG", b(self.uses_phong)),
            ("SHADOWS", b(self.shadows)),
            ("USE_BVH", b(self.use_bvh)),
            ("SMOOTH", b(self.smooth)),
            ("ANTIALIAS", b(self.antialias)),
            ("WHITTED", b(self.whitted)),
            ("LIGHT_KINDS", b(self.light_kinds)),
            ("TEXTURES", b(self.textures)),
            ("POWERS", b(self.powers)),
            ("INSTANCES", b(self.instances)),
            ("EXACT_MATH", b(self.math.math != Math::Fast)),
            ("INEXACT_DRIVER", b(self.math.inexact_driver)),
        ]
    }
}

/// A scene light as the shader reads it: the direction made a unit vector and a spot's
/// angles made cosines, in f64, each rounded once to f32.
fn light(l: &crate::scene::Light) -> Light {
    use crate::scene::LightKind;
    let unit = |d: [f32; 3]| {
        let v = glam::DVec3::new(d[0] as f64, d[1] as f64, d[2] as f64);
        (v / v.length()).as_vec3().to_array()
    };
    let (kind, direction, cos_outer, cos_inner) = match l.kind {
        LightKind::Point => (LIGHT_POINT, [0.0; 3], 0.0, 0.0),
        LightKind::Directional { direction } => (LIGHT_DIRECTIONAL, unit(direction), 0.0, 0.0),
        LightKind::Spot {
            direction,
            angle,
            falloff,
        } => (
            LIGHT_SPOT,
            unit(direction),
            (angle as f64).to_radians().cos() as f32,
            ((angle - falloff) as f64).to_radians().cos() as f32,
        ),
    };
    Light {
        position: l.position,
        kind,
        color: flush_colour(l.color),
        cos_outer,
        direction,
        cos_inner,
    }
}

/// The BVH over `spheres` and `triangles`: from `cache` when it holds this scene's tree
/// (keyed by the primitives' bytes, see [`crate::cache`]), else built (and stored, when
/// there is a cache and the scene is large enough to be worth it).
fn cached_bvh(
    cache: Option<&crate::cache::Cache>,
    stages: &Stages,
    spheres: &[Sphere],
    triangles: &[Triangle],
) -> Bvh {
    let n = spheres.len() + triangles.len();
    let Some(cache) = cache.filter(|c| c.worth(n)) else {
        return stages.time("BVH build", || Bvh::build(spheres, triangles));
    };
    let key = crate::cache::Key::new(
        "bvh",
        &[
            bytemuck::cast_slice(spheres),
            bytemuck::cast_slice(triangles),
        ],
    );
    let hit = stages.time("cache read", || {
        let mut s = cache.load("bvh", &key)?.into_iter();
        let (nodes, prim_ids, stats) = (s.next()?, s.next()?, s.next()?);
        Some(Bvh {
            nodes: crate::cache::section_as(nodes),
            prim_ids,
            depth: *stats.first()? as usize,
            largest_leaf: *stats.get(1)? as usize,
        })
    });
    if let Some(bvh) = hit.filter(|b| b.prim_ids.len() == n) {
        return bvh;
    }
    let bvh = stages.time("BVH build", || Bvh::build(spheres, triangles));
    stages.time("cache write", || {
        let stats = [bvh.depth as u32, bvh.largest_leaf as u32];
        cache.store(
            "bvh",
            &key,
            &[bytemuck::cast_slice(&bvh.nodes), &bvh.prim_ids, &stats],
        )
    });
    bvh
}

/// The records of the textured triangles (entry 0 stands for "untextured"; empty when no
/// triangle is): a triangle with coordinates whose material has a map gets its own entry,
/// named in its `uvs`.
fn triangle_uvs(
    triangles: &mut [Triangle],
    runs: &[crate::scene::TextureCoords],
    materials: &[crate::scene::Material],
) -> Vec<TriangleUvs> {
    let mut out = Vec::new();
    for run in runs {
        for (k, uv) in run.uvs.iter().enumerate() {
            let t = &mut triangles[run.first + k];
            let (ka, kd) = materials[t.material as usize].maps();
            if (ka, kd) == (None, None) {
                continue;
            }
            if out.is_empty() {
                out.push(TriangleUvs::default());
            }
            t.uvs = out.len() as u32;
            out.push(TriangleUvs {
                uv_a: uv[0],
                uv_b: uv[1],
                uv_c: uv[2],
                map_kd: kd.unwrap_or(NO_TEXTURE),
                map_ka: ka.unwrap_or(NO_TEXTURE),
            });
        }
    }
    out
}

/// The scene's textures as the shader reads them ([`SceneBuffers::texels`]): each one's
/// place, then all their texels, in one list of words.
fn texture_buffers(textures: &[crate::scene::Texture]) -> Vec<u32> {
    let table = TEXTURE_WORDS * textures.len();
    let mut words =
        Vec::with_capacity(table + textures.iter().map(|t| t.texels.len()).sum::<usize>());
    let mut offset = table;
    for t in textures {
        let place = Texture {
            offset: offset as u32,
            width: t.width,
            height: t.height,
            _pad0: 0,
        };
        words.extend_from_slice(bytemuck::cast_slice(std::slice::from_ref(&place)));
        offset += t.texels.len();
    }
    for t in textures {
        words.extend(t.texels.iter().map(|x| x.to_bits()));
    }
    words
}

/// Words of one [`Texture`] in [`SceneBuffers::texels`].
pub const TEXTURE_WORDS: usize = std::mem::size_of::<Texture>() / 4;

/// The scene's triangles as the shader's, and the vertex normals they name (entry 0 stands
/// for "flat"; empty when no mesh is smooth).
fn flat_triangles(
    scene_triangles: &[crate::scene::Triangle],
    smooth: &[crate::scene::SmoothNormals],
    stages: &Stages,
) -> (Vec<Triangle>, Vec<VertexNormals>) {
    stages.time("flatten", || {
        let mut triangles: Vec<Triangle> = scene_triangles
            .par_iter()
            .map(|t| Triangle {
                a: t.vertices[0],
                material: t.material,
                b: t.vertices[1],
                c: t.vertices[2],
                ..Triangle::default()
            })
            .collect();
        // Entry 0 stands for "flat"; each smooth triangle names its own entry.
        let mut normals = Vec::new();
        for mesh in smooth {
            if normals.is_empty() {
                normals.push(VertexNormals::default());
            }
            for (k, n) in mesh.normals.iter().enumerate() {
                triangles[mesh.first + k].normals = normals.len() as u32;
                normals.push(VertexNormals {
                    na: n[0],
                    nb: n[1],
                    nc: n[2],
                    ..VertexNormals::default()
                });
            }
        }
        (triangles, normals)
    })
}
