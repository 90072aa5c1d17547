//! The shader parses and validates with naga, and every struct shared with it has the size
//! and field offsets that naga gives the WGSL struct of the same name. No GPU needed.

use std::mem::{offset_of, size_of};

use glint::buffers::{
    AovOut, BvhNode, HitOut, Light, Material, Params, RayIn, Sphere, Texture, Triangle,
    TriangleUvs, VertexNormals,
};
use glint::gpu::SHADER_SOURCE;

fn module() -> naga::Module {
    naga::front::wgsl::parse_str(SHADER_SOURCE)
        .unwrap_or_else(|e| panic!("{}", e.emit_to_string(SHADER_SOURCE)))
}

/// (size, [(field, offset)]) of WGSL struct `name`, by naga's layouter.
fn wgsl_layout(module: &naga::Module, name: &str) -> (u32, Vec<(String, u32)>) {
    let mut layouter = naga::proc::Layouter::default();
    layouter.update(module.to_ctx()).expect("layout");
    for (handle, ty) in module.types.iter() {
        if ty.name.as_deref() == Some(name)
            && let naga::TypeInner::Struct { members, .. } = &ty.inner
        {
            let fields = members
                .iter()
                .map(|m| (m.name.clone().unwrap_or_default(), m.offset))
                .collect();
            return (layouter[handle].size, fields);
        }
    }
    panic!("no WGSL struct {name}");
}

macro_rules! check_struct {
    ($module:expr, $ty:ty, $wgsl:literal, [$($field:ident),* $(,)?]) => {{
        let (size, fields) = wgsl_layout($module, $wgsl);
        assert_eq!(size as usize, size_of::<$ty>(), "size of {} vs WGSL {}", stringify!($ty), $wgsl);
        let rust: Vec<(String, u32)> = vec![$((stringify!($field).to_string(), offset_of!($ty, $field) as u32)),*];
        assert_eq!(fields, rust, "fields and offsets of {} vs WGSL {}", stringify!($ty), $wgsl);
    }};
}

#[test]
fn shader_parses_and_validates() {
    let module = module();
    naga::valid::Validator::new(
        naga::valid::ValidationFlags::all(),
        naga::valid::Capabilities::default(),
    )
    .validate(&module)
    .unwrap_or_else(|e| panic!("{}", e.emit_to_string(SHADER_SOURCE)));
    for entry in ["render", "render_rgba8", "render_aov", "query"] {
        assert!(
            module.entry_points.iter().any(|e| e.name == entry),
            "no entry point {entry}"
        );
    }
}

#[test]
fn shared_structs_match_wgsl() {
    let m = module();
    check_struct!(
        &m,
        Params,
        "Params",
        [
            eye,
            width,
            forward,
            height,
            right,
            tan_half,
            up,
            aspect,
            ambient,
            n_spheres,
            background,
            n_triangles,
            n_lights,
            tile_x,
            tile_y,
            tile_width,
            tile_height,
            n_nodes,
            samples,
            max_depth,
            min_weight,
            n_instances,
            _pad1,
            _pad2
        ]
    );
    check_struct!(
        &m,
        Sphere,
        "Sphere",
        [center, radius, material, _pad0, _pad1, _pad2]
    );
    check_struct!(&m, Triangle, "Triangle", [a, material, b, normals, c, uvs]);
    check_struct!(
        &m,
        TriangleUvs,
        "TriangleUvs",
        [uv_a, uv_b, uv_c, map_kd, map_ka]
    );
    check_struct!(&m, Texture, "Texture", [offset, width, height, _pad0]);
    check_struct!(
        &m,
        VertexNormals,
        "VertexNormals",
        [na, _pad0, nb, _pad1, nc, _pad2]
    );
    check_struct!(
        &m,
        Material,
        "Material",
        [ka, model, kd, n, ks, n_int, kr, ior, kt, fresnel]
    );
    check_struct!(&m, BvhNode, "BvhNode", [lo, first, hi, count_axis]);
    // An instance is read from four node slots (WGSL `instance_at`): the size is four
    // nodes, and each integer sits at a slot's `first` (word 3 of 8) or `count_axis` (7).
    {
        use glint::buffers::Instance;
        use std::mem::{offset_of, size_of};
        assert_eq!(size_of::<Instance>(), 4 * size_of::<BvhNode>());
        let node = size_of::<BvhNode>();
        assert_eq!(
            offset_of!(Instance, root),
            3 * node + offset_of!(BvhNode, first)
        );
        assert_eq!(
            offset_of!(Instance, material),
            3 * node + offset_of!(BvhNode, count_axis)
        );
        assert_eq!(offset_of!(Instance, to_world), node + 16);
    }
    check_struct!(
        &m,
        Light,
        "Light",
        [position, kind, color, cos_outer, direction, cos_inner]
    );
    check_struct!(&m, RayIn, "RayIn", [origin, t_min, dir, t_max]);
    check_struct!(&m, HitOut, "HitOut", [t, prim, u, v]);
    check_struct!(
        &m,
        AovOut,
        "AovOut",
        [
            position, t, geo_normal, depth, normal, prim, albedo, material
        ]
    );
}

/// The twin: a struct that drifted (a field moved) is caught by the same comparison.
#[test]
#[should_panic(expected = "fields and offsets")]
fn layout_check_catches_drift() {
    #[repr(C)]
    struct Drifted {
        center: [f32; 3],
        material: u32,
        radius: f32,
        _pad0: u32,
        _pad1: u32,
        _pad2: u32,
    }
    let m = module();
    check_struct!(
        &m,
        Drifted,
        "Sphere",
        [center, material, radius, _pad0, _pad1, _pad2]
    );
}

/// The WGSL constants that name Rust constants carry the same values.
#[test]
fn shader_constants_match_rust() {
    let m = module();
    let find = |name: &str| -> naga::Literal {
        let (_, c) = m
            .constants
            .iter()
            .find(|(_, c)| c.name.as_deref() == Some(name))
            .unwrap_or_else(|| panic!("no const {name}"));
        match m.global_expressions[c.init] {
            naga::Expression::Literal(l) => l,
            ref e => panic!("{name}: not a literal: {e:?}"),
        }
    };
    use glint::buffers::*;
    assert_eq!(find("MODEL_AMBIENT"), naga::Literal::U32(MODEL_AMBIENT));
    assert_eq!(find("MODEL_DIFFUSE"), naga::Literal::U32(MODEL_DIFFUSE));
    assert_eq!(find("MODEL_PHONG"), naga::Literal::U32(MODEL_PHONG));
    assert_eq!(find("TRIANGLE_NAIVE"), naga::Literal::U32(TRIANGLE_NAIVE));
    assert_eq!(
        find("TRIANGLE_MOLLER_TRUMBORE"),
        naga::Literal::U32(TRIANGLE_MOLLER_TRUMBORE)
    );
    assert_eq!(
        find("TRIANGLE_WATERTIGHT"),
        naga::Literal::U32(TRIANGLE_WATERTIGHT)
    );
    assert_eq!(find("PRIM_NONE"), naga::Literal::U32(PRIM_NONE));
    assert_eq!(find("FLAT"), naga::Literal::U32(FLAT));
    assert_eq!(find("NO_UVS"), naga::Literal::U32(glint::buffers::NO_UVS));
    assert_eq!(
        find("NO_TEXTURE"),
        naga::Literal::U32(glint::buffers::NO_TEXTURE)
    );
    assert_eq!(find("TRIANGLE_BIT"), naga::Literal::U32(TRIANGLE_BIT));
    assert_eq!(find("INFINITY"), naga::Literal::F32(INFINITY));
    assert_eq!(find("SHADOW_EPSILON"), naga::Literal::F32(SHADOW_EPSILON));
    assert_eq!(find("SPLITTER"), naga::Literal::F32(SPLITTER));
    assert_eq!(find("BOX_SLACK"), naga::Literal::F32(BOX_SLACK));
    assert_eq!(find("NAIVE_MIN_SIN2"), naga::Literal::F32(NAIVE_MIN_SIN2));
    assert_eq!(find("FLUSH_BELOW"), naga::Literal::F32(FLUSH_BELOW));
    assert_eq!(
        find("INSTANCE_IDENTITY"),
        naga::Literal::U32(glint::buffers::INSTANCE_IDENTITY)
    );
    assert_eq!(
        find("NO_MATERIAL"),
        naga::Literal::U32(glint::buffers::NO_MATERIAL)
    );
    assert_eq!(
        find("NO_INSTANCE"),
        naga::Literal::U32(glint::buffers::NO_INSTANCE)
    );
    assert_eq!(
        find("TOP_STACK"),
        naga::Literal::U32(glint::cpu::instance::TOP_STACK as u32)
    );
    assert_eq!(
        find("BVH_STACK"),
        naga::Literal::U32(glint::bvh::MAX_DEPTH as u32)
    );
    // Every override the pipeline sets exists in the shader.
    let spec = Specialisation {
        has_spheres: true,
        has_triangles: true,
        triangle_algo: 0,
        uses_diffuse: true,
        uses_phong: true,
        shadows: false,
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
    for (name, _) in spec.constants() {
        assert!(
            m.overrides
                .iter()
                .any(|(_, o)| o.name.as_deref() == Some(name)),
            "no override {name}"
        );
    }
}

/// The assembled variants parse and validate too: the packet traversal (subgroup
/// operations) with and without its shadow rays, and the ray-query tracer, each with the
/// capability its device must have.
#[test]
fn variant_modules_parse_and_validate() {
    for (name, src, caps) in [
        (
            "trace_subgroup",
            glint::gpu::subgroup::shader_source(false),
            naga::valid::Capabilities::SUBGROUP,
        ),
        (
            "trace_subgroup + shadows",
            glint::gpu::subgroup::shader_source(true),
            naga::valid::Capabilities::SUBGROUP,
        ),
        (
            "trace_rq",
            glint::gpu::rq::shader_source(),
            naga::valid::Capabilities::RAY_QUERY,
        ),
    ] {
        let m = naga::front::wgsl::parse_str(&src)
            .unwrap_or_else(|e| panic!("{name}: {}", e.emit_to_string(&src)));
        let mut v = naga::valid::Validator::new(naga::valid::ValidationFlags::all(), caps);
        v.subgroup_stages(naga::valid::ShaderStages::COMPUTE);
        v.subgroup_operations(naga::valid::SubgroupOperationSet::all());
        v.validate(&m)
            .unwrap_or_else(|e| panic!("{name}: {}", e.emit_to_string(&src)));
        for entry in ["render", "query"] {
            assert!(
                m.entry_points.iter().any(|e| e.name == entry),
                "{name}: no {entry}"
            );
        }
    }
}

/// The storage buffers each entry point uses, by naga's analysis of the shader.
fn storage_buffers_used(entry: &str) -> u32 {
    let module = module();
    let info = naga::valid::Validator::new(
        naga::valid::ValidationFlags::all(),
        naga::valid::Capabilities::default(),
    )
    .validate(&module)
    .unwrap_or_else(|e| panic!("{}", e.emit_to_string(SHADER_SOURCE)));
    let index = module
        .entry_points
        .iter()
        .position(|e| e.name == entry)
        .unwrap_or_else(|| panic!("no entry point {entry}"));
    let uses = info.get_entry_point(index);
    module
        .global_variables
        .iter()
        .filter(|(h, g)| {
            matches!(g.space, naga::AddressSpace::Storage { .. }) && !uses[*h].is_empty()
        })
        .count() as u32
}

/// `render` and `render_rgba8` bind `RENDER_STORAGE_BUFFERS` storage buffers, the number a
/// device must offer per stage (WebGPU adapters offer 8 to 10); the twin: `query` binds
/// fewer, so the count tells entry points apart.
#[test]
fn render_binds_the_storage_buffers_it_declares() {
    use glint::gpu::RENDER_STORAGE_BUFFERS;
    assert_eq!(RENDER_STORAGE_BUFFERS, 10);
    for entry in ["render", "render_rgba8"] {
        assert_eq!(
            storage_buffers_used(entry),
            RENDER_STORAGE_BUFFERS,
            "{entry}"
        );
    }
    assert!(storage_buffers_used("query") < RENDER_STORAGE_BUFFERS);
}
