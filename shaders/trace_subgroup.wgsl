// glint's packet traversal for adapters with subgroups: `shaders/trace.wgsl` with its
// `closest_hit_bvh` and `occluded_bvh` renamed `closest_hit_bvh_ray` and `occluded_bvh_ray`
// (the per-ray traversals, kept as the fallbacks) and this file's `closest_hit_bvh` and
// `trace_subgroup_shadows.wgsl`'s `occluded_bvh` in their place (the second only where
// shadow rays go in packets: `Kernel::new_packet_with`).
// `src/gpu/subgroup.rs` assembles the module; the pipeline is made from it only where the
// device has `Features::SUBGROUP`.
//
// One packet per subgroup: the node index and the stack are the same in every lane, the
// visits decided by `subgroupAny` (the nearer child first, by a vote of the lanes' entry
// distances for the nearest hit, by the split axis and lane 0's direction for shadow rays,
// whose answer no order can change), and each BVH node and leaf triangle fetched
// cooperatively: lane r < 8 loads the node's dword r through a plain `array<u32>` view of the same buffer, and
// eight constant-index shuffles hand every lane the whole node (on lavapipe a per-lane load
// inside a loop is a per-lane loop with a bounds check per dword; a constant shuffle is one
// vector shuffle). The child the packet enters is the node fetched for its box test,
// carried into the next step; only a node popped from the stack is fetched again (one
// fetch a descent less: lavapipe 25, peers 1M 0.70 with shadows, 0.80 without; level on
// 22.3, which runs the pop's fetch masked either way). Each packet loop is a descent loop
// inside a leaf loop, so that lavapipe 22.3, which runs both sides of every `if`, does not
// run a leaf's triangle tests, masked, on every descent step. Each lane keeps a `live` flag, pushed with every stack entry: it tests
// a box or accepts a hit only where its own traversal would have gone (the CPU packet
// tracer's masks). The nearest hit is the smallest t, then the lowest id; a lane's answer
// is `closest_hit_bvh_ray`'s, bit for bit, wherever every primitive's computed hit lies in
// its box's computed interval (see the vote below for where it need not). Shadow rays go
// the same way (`occluded_bvh`), each lane done at its first hit: whether some primitive
// blocks the ray in (t_min, t_max) does not depend on the order, nor do the box tests,
// whose bound is t_max throughout.

/// The BVH nodes (the `nodes` buffer) as dwords, 8 per node.
@group(0) @binding(12) var<storage, read> node_words: array<u32>;
/// The triangles (the `triangles` buffer) as dwords, 12 per triangle.
@group(0) @binding(13) var<storage, read> triangle_words: array<u32>;

/// Node k, fetched by the whole subgroup: lane r loads dword r (r = its rank mod 8).
/// Every lane of 0..7 must be active.
fn fetch_node(k: u32, r: u32) -> BvhNode {
    let w = node_words[k * 8u + r];
    return BvhNode(
        vec3<f32>(bitcast<f32>(subgroupShuffle(w, 0u)), bitcast<f32>(subgroupShuffle(w, 1u)), bitcast<f32>(subgroupShuffle(w, 2u))),
        subgroupShuffle(w, 3u),
        vec3<f32>(bitcast<f32>(subgroupShuffle(w, 4u)), bitcast<f32>(subgroupShuffle(w, 5u)), bitcast<f32>(subgroupShuffle(w, 6u))),
        subgroupShuffle(w, 7u),
    );
}

/// Triangle k, fetched by the whole subgroup: lane r loads dwords r and r + 8 (the
/// second only below 12). Every lane of 0..7 must be active.
fn fetch_triangle(k: u32, r: u32) -> Triangle {
    let w0 = triangle_words[k * 12u + r];
    let w1 = triangle_words[k * 12u + 8u + (r & 3u)];
    return Triangle(
        vec3<f32>(bitcast<f32>(subgroupShuffle(w0, 0u)), bitcast<f32>(subgroupShuffle(w0, 1u)), bitcast<f32>(subgroupShuffle(w0, 2u))),
        subgroupShuffle(w0, 3u),
        vec3<f32>(bitcast<f32>(subgroupShuffle(w0, 4u)), bitcast<f32>(subgroupShuffle(w0, 5u)), bitcast<f32>(subgroupShuffle(w0, 6u))),
        subgroupShuffle(w0, 7u),
        vec3<f32>(bitcast<f32>(subgroupShuffle(w1, 0u)), bitcast<f32>(subgroupShuffle(w1, 1u)), bitcast<f32>(subgroupShuffle(w1, 2u))),
        subgroupShuffle(w1, 3u),
    );
}

/// `hit_prim` for the subgroup: primitive `id`'s (t, u, v), t = INFINITY on a miss, its
/// triangle fetched cooperatively (`fetch_triangle`). `id` must be the same in every lane,
/// and every lane of 0..7 active.
fn hit_prim_packet(ray: Ray, sh: Shear, id: u32, r: u32, t_min: f32, t_max: f32) -> vec3<f32> {
    var h = vec3<f32>(INFINITY, 0.0, 0.0);
    if (id & TRIANGLE_BIT) != 0u {
        if HAS_TRIANGLES {
            let tri = fetch_triangle(id & ~TRIANGLE_BIT, r);
            h = hit_triangle(ray, sh, tri, t_min, t_max);
        }
    } else if HAS_SPHERES {
        h = vec3<f32>(hit_sphere(ray, spheres[id], t_min, t_max), 0.0, 0.0);
    }
    return h;
}

/// `closest_hit_bvh` for the subgroup as one packet (see the top of this file). Falls
/// back to the per-ray traversal when lanes 0..7 are not all active (the edge of a tile,
/// the last rays of a query, a subgroup narrower than 8).
fn closest_hit_bvh(ray: Ray, t_min: f32, t_max: f32) -> Hit {
    if (subgroupBallot(true).x & 0xffu) != 0xffu {
        return closest_hit_bvh_ray(ray, t_min, t_max);
    }
    let r = subgroupExclusiveAdd(1u) & 7u;
    var best = Hit(t_max, PRIM_NONE, 0.0, 0.0, 0u);
    let sh = ray_shear(ray.dir);
    let inv_dir = div3_rn(vec3<f32>(1.0), ray.dir);
    if params.n_nodes == 0u {
        return best;
    }
    var node = fetch_node(0u, r);
    let root = box_interval(node, ray.origin, inv_dir, t_min, t_max);
    var live = root.x <= root.y;
    if !subgroupAny(live) {
        return best;
    }
    var stack: array<u32, BVH_STACK>;
    var sp = 0u;
    var at = 0u;
    // Two loops: the inner one descends through interior nodes (popping where the packet
    // enters neither child) to the next leaf the packet enters, the outer one tests that
    // leaf and pops. Lavapipe 22.3 runs both sides of every `if`, masked: in one loop with
    // a branch for each kind of node, every descent step paid for the leaf's triangle
    // tests too. Every step (a descent or a leaf) counts against `n_nodes`, as in one loop.
    var step = 0u;
    loop {
        var at_leaf = false;
        for (; step < params.n_nodes; step = step + 1u) {
            if (node.count_axis >> 2u) != 0u {
                at_leaf = true;
                break;
            }
            let bound = tie_bound(best);
            let left_node = fetch_node(at + 1u, r);
            let right_node = fetch_node(node.first, r);
            let left = box_interval(left_node, ray.origin, inv_dir, t_min, bound);
            let right = box_interval(right_node, ray.origin, inv_dir, t_min, bound);
            let hit_left = live && left.x <= left.y;
            let hit_right = live && right.x <= right.y;
            // Every vote of the step in one reduction: the lanes entering the left child,
            // the right, both with the right nearer, both with the left not farther, one
            // byte each (a count is at most the subgroup's width: 8 on lavapipe, at most
            // wgpu's MAXIMUM_SUBGROUP_MAX_SIZE, 128, anywhere; `src/gpu/subgroup.rs`
            // checks it). On lavapipe each vote or ballot is a loop over the lanes; two
            // `subgroupAny` and two ballots were four.
            let both = hit_left && hit_right;
            let right_nearer = right.x < left.x;
            let counts = subgroupAdd(
                select(0u, 1u, hit_left) | select(0u, 0x100u, hit_right)
                    | select(0u, 0x10000u, both && right_nearer)
                    | select(0u, 0x1000000u, both && !right_nearer),
            );
            let any_left = (counts & 0xffu) != 0u;
            let any_right = (counts & 0xff00u) != 0u;
            if any_left && any_right {
                // The nearer child by a vote of the lanes that enter both, each by its own
                // entry distances, as `closest_hit_bvh_ray` orders them. Not by the split
                // axis and lane 0's direction (cheaper, 0.92-0.93 on lavapipe 22.3): where a
                // primitive's computed hit lies outside its box's computed interval (the
                // naive test far from the origin, rays with non-finite parts), the order
                // decides which hit the bound culls, and 4 of 100000 query rays differed
                // from the mirror. A lane alone in both children gets its own order.
                let right_first = ((counts >> 16u) & 0xffu) > (counts >> 24u);
                if right_first {
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
            let h = hit_prim_packet(ray, sh, id, r, t_min, tie_bound(best));
            if live && nearer(h.x, id, best) {
                best = Hit(h.x, id, h.y, h.z, 0u);
            }
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
    return best;
}
