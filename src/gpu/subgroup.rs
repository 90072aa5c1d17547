//! The packet traversal's shader module (`shaders/trace_subgroup.wgsl`), for devices with
//! subgroups: trace.wgsl with `closest_hit_bvh` renamed `closest_hit_bvh_ray` (kept as the
//! fallback) and the packet version in its place.

/// The packet traversal's part of the shader.
pub const SUBGROUP_SOURCE: &str = include_str!("../../shaders/trace_subgroup.wgsl");

/// The binding of the BVH nodes seen as dwords.
pub const NODE_WORDS_BINDING: u32 = 12;
/// The binding of the triangles seen as dwords.
pub const TRIANGLE_WORDS_BINDING: u32 = 13;

/// The whole module: trace.wgsl with its per-ray `closest_hit_bvh` renamed
/// `closest_hit_bvh_ray`, then `trace_subgroup.wgsl`, whose `closest_hit_bvh` takes the
/// name (so `closest_hit`, and through it both entry points, trace in packets).
pub fn shader_source() -> String {
    let from = "fn closest_hit_bvh(";
    let src = super::SHADER_SOURCE;
    assert_eq!(
        src.matches(from).count(),
        1,
        "trace.wgsl must define `closest_hit_bvh` exactly once"
    );
    format!(
        "{}\n{SUBGROUP_SOURCE}",
        src.replace(from, "fn closest_hit_bvh_ray(")
    )
}
