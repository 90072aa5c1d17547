// glint's packet traversal for shadow rays: appended after `trace_subgroup.wgsl` (whose
// `fetch_node` and `hit_prim_packet` it uses) where shadow rays go in packets, with
// trace.wgsl's `occluded_bvh` renamed `occluded_bvh_ray`. `src/gpu/subgroup.rs` assembles
// the module. Left out, shadow rays go each on its own and no dead code is compiled
// (lavapipe 22.3, where packets of shadow rays measured slower, compiles the module per
// pipeline).

/// `occluded_bvh` for the subgroup as one packet: shadow rays to a point light leave
/// neighbouring hits together, so they go down the tree together as camera rays do, each
/// node and leaf triangle fetched once for the packet. A lane is done at its first hit
/// (`blocked`), the packet when every lane is. Whether a lane is blocked does not depend
/// on the order, and a lane tests a box or a primitive only where its own traversal would
/// have gone: `occluded_bvh_ray`'s answer, bit for bit. Falls back to the per-ray
/// traversal when lanes 0..7 are not all active (a lane whose hit missed, faced away from
/// the light or had no diffuse term does not call it). It repeats `closest_hit_bvh`'s
/// packet loop rather than sharing a descent helper, for trace.wgsl's reason: one push
/// and one pop site per loop (a shared helper measured 40% slower on lavapipe, per ray).
fn occluded_bvh(ray: Ray, t_min: f32, t_max: f32, skip: u32) -> bool {
    if (subgroupBallot(true).x & 0xffu) != 0xffu {
        return occluded_bvh_ray(ray, t_min, t_max, skip);
    }
    let r = subgroupExclusiveAdd(1u) & 7u;
    let sh = ray_shear(ray.dir);
    let inv_dir = div3_rn(vec3<f32>(1.0), ray.dir);
    if params.n_nodes == 0u {
        return false;
    }
    var node = fetch_node(0u, r);
    let root = box_interval(node, ray.origin, inv_dir, t_min, t_max);
    var live = root.x <= root.y;
    if !subgroupAny(live) {
        return false;
    }
    let dir0 = subgroupShuffle(ray.dir, 0u);
    var blocked = false;
    var stack: array<u32, BVH_STACK>;
    var sp = 0u;
    var at = 0u;
    // A descent loop inside a leaf loop, as `closest_hit_bvh`'s (see there).
    var step = 0u;
    loop {
        var at_leaf = false;
        for (; step < params.n_nodes; step = step + 1u) {
            if (node.count_axis >> 2u) != 0u {
                at_leaf = true;
                break;
            }
            let left_node = fetch_node(at + 1u, r);
            let right_node = fetch_node(node.first, r);
            let left = box_interval(left_node, ray.origin, inv_dir, t_min, t_max);
            let right = box_interval(right_node, ray.origin, inv_dir, t_min, t_max);
            let hit_left = live && !blocked && left.x <= left.y;
            let hit_right = live && !blocked && right.x <= right.y;
            // Both votes in one reduction (on lavapipe each vote is a loop over the lanes).
            let any = subgroupOr(select(0u, 1u, hit_left) | select(0u, 2u, hit_right));
            let any_left = (any & 1u) != 0u;
            let any_right = (any & 2u) != 0u;
            if any_left && any_right {
                let axis = node.count_axis & 3u;
                let d = select(select(dir0.x, dir0.y, axis == 1u), dir0.z, axis == 2u);
                if d < 0.0 {
                    stack[sp] = (at + 1u) | select(0u, 0x80000000u, hit_left);
                    at = node.first;
                    node = right_node;
                    live = hit_right;
                } else {
                    stack[sp] = node.first | select(0u, 0x80000000u, hit_right);
                    at = at + 1u;
                    node = left_node;
                    live = hit_left;
                }
                sp = sp + 1u;
                continue;
            }
            if any_left {
                at = at + 1u;
                node = left_node;
                live = hit_left;
                continue;
            }
            if any_right {
                at = node.first;
                node = right_node;
                live = hit_right;
                continue;
            }
            if sp == 0u {
                break;
            }
            sp = sp - 1u;
            let e = stack[sp];
            at = e & 0x7fffffffu;
            node = fetch_node(at, r);
            live = (e >> 31u) != 0u;
        }
        if !at_leaf {
            break;
        }
        let count = node.count_axis >> 2u;
        for (var k = node.first; k < node.first + count; k = k + 1u) {
            let id = prim_ids[k];
            let h = hit_prim_packet(ray, sh, id, r, t_min, t_max).x;
            if live && id != skip && h < t_max {
                blocked = true;
            }
        }
        if !subgroupAny(!blocked) {
            return true;
        }
        step = step + 1u;
        if sp == 0u || step >= params.n_nodes {
            break;
        }
        sp = sp - 1u;
        let e = stack[sp];
        at = e & 0x7fffffffu;
        node = fetch_node(at, r);
        live = (e >> 31u) != 0u;
    }
    return blocked;
}
