//! The packet traversal's shader module (`shaders/trace_subgroup.wgsl`), for devices with
//! subgroups: trace.wgsl with `closest_hit_bvh` and `occluded_bvh` renamed
//! `closest_hit_bvh_ray` and `occluded_bvh_ray` (kept as the fallbacks) and the packet
//! versions in their place.

/// The packet traversal's part of the shader.
pub const SUBGROUP_SOURCE: &str = include_str!("../../shaders/trace_subgroup.wgsl");

/// The binding of the BVH nodes seen as dwords.
pub const NODE_WORDS_BINDING: u32 = 12;
/// The binding of the triangles seen as dwords.
pub const TRIANGLE_WORDS_BINDING: u32 = 13;

/// The whole module: trace.wgsl with its per-ray `closest_hit_bvh` and `occluded_bvh`
/// renamed `closest_hit_bvh_ray` and `occluded_bvh_ray`, then `trace_subgroup.wgsl`, whose
/// `closest_hit_bvh` and `occluded_bvh` take the names (so `closest_hit` and `occluded`,
/// and through them every entry point, trace in packets).
pub fn shader_source() -> String {
    let mut src = super::SHADER_SOURCE.to_string();
    for name in ["closest_hit_bvh", "occluded_bvh"] {
        let from = format!("fn {name}(");
        assert_eq!(
            src.matches(&from).count(),
            1,
            "trace.wgsl must define `{name}` exactly once"
        );
        src = src.replace(&from, &format!("fn {name}_ray("));
    }
    format!("{src}\n{SUBGROUP_SOURCE}")
}
