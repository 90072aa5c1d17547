//! The packet traversal's shader module (`shaders/trace_subgroup.wgsl`), for devices with
//! subgroups: trace.wgsl with `closest_hit_bvh` (and, where shadow rays go in packets,
//! `occluded_bvh`) renamed `..._ray` (kept as the fallbacks) and the packet versions in
//! their place.

/// The packet traversal's part of the shader.
pub const SUBGROUP_SOURCE: &str = include_str!("../../shaders/trace_subgroup.wgsl");
/// Its shadow rays' part (`occluded_bvh`), added where shadow rays go in packets.
pub const SUBGROUP_SHADOWS_SOURCE: &str = include_str!("../../shaders/trace_subgroup_shadows.wgsl");

// `trace_subgroup.wgsl` counts a step's votes in one `subgroupAdd`, a byte each.
const _: () = assert!(
    wgpu::MAXIMUM_SUBGROUP_MAX_SIZE < 256,
    "a subgroup's vote count must fit in a byte"
);

/// The binding of the BVH nodes seen as dwords.
pub const NODE_WORDS_BINDING: u32 = 12;
/// The binding of the triangles seen as dwords.
pub const TRIANGLE_WORDS_BINDING: u32 = 13;

/// The whole module: trace.wgsl with its per-ray `closest_hit_bvh` renamed
/// `closest_hit_bvh_ray`, then `trace_subgroup.wgsl`, whose `closest_hit_bvh` takes the
/// name (so `closest_hit`, and through it every entry point, traces in packets). With
/// `shadows_in_packets`, the same for `occluded_bvh` and `trace_subgroup_shadows.wgsl`.
pub fn shader_source(shadows_in_packets: bool) -> String {
    let mut src = super::SHADER_SOURCE.to_string();
    let mut renamed = vec!["closest_hit_bvh"];
    if shadows_in_packets {
        renamed.push("occluded_bvh");
    }
    for name in renamed {
        let from = format!("fn {name}(");
        assert_eq!(
            src.matches(&from).count(),
            1,
            "trace.wgsl must define `{name}` exactly once"
        );
        src = src.replace(&from, &format!("fn {name}_ray("));
    }
    src.push('\n');
    src.push_str(SUBGROUP_SOURCE);
    if shadows_in_packets {
        src.push('\n');
        src.push_str(SUBGROUP_SHADOWS_SOURCE);
    }
    src
}
