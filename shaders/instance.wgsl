// glint's kernel, part 5 of 8: instances, a mesh placed again by an affine map (after
// `trace.wgsl`; see `common.wgsl`'s header for how the parts are joined and mirrored).
// The two-level search (a top-level BVH whose leaves are instances, each entering its
// mesh's own BVH with the ray taken into object space) and the hit's triangle carried
// back to world space for shading. Compiled only where the scene has instances
// (`INSTANCES`); a scene without keeps the one-level search of `trace.wgsl`, unchanged.
// Mirror: `src/cpu/instance.rs`.
//
// The layout (`src/buffers.rs`, `src/bvh.rs::build_top`): `nodes` holds the top-level BVH
// from node 0 (each leaf one instance: count 1, `first` its index), then every mesh's BVH,
// then, from node `params.n_nodes`, each instance as four node slots (`instance_at`).
// Instance 0 is the scene's own primitives (spheres, triangles, meshes placed once), the
// identity. The ray keeps its t: its direction is mapped and never renormalised, so t is
// the world-space distance in either space, and the bounds (t_min, t_max) hold in both.

/// An instance (Rust: `buffers::Instance`): world-to-object rows `o0..o2`, object-to-world
/// rows `w0..w2` (each `[m0, m1, m2, t]`), the root of its mesh's BVH with
/// `INSTANCE_IDENTITY` where both maps are the identity (then neither is applied), and the
/// material that replaces the mesh's (`NO_MATERIAL`: none).
struct InstanceX {
    o0: vec4<f32>,
    o1: vec4<f32>,
    o2: vec4<f32>,
    w0: vec4<f32>,
    w1: vec4<f32>,
    w2: vec4<f32>,
    root: u32,
    material: u32,
}

/// Instance `k`, read from its four node slots: the words of `buffers::Instance` in order
/// (the maps' rows, then `root` at word 27 and `material` at word 31, the slots' `first`
/// and `count_axis` of the fourth, so that no integer is read as a float).
fn instance_at(k: u32) -> InstanceX {
    let at = params.n_nodes + 4u * k;
    let a = nodes[at];
    let b = nodes[at + 1u];
    let c = nodes[at + 2u];
    let d = nodes[at + 3u];
    return InstanceX(
        vec4<f32>(a.lo, bitcast<f32>(a.first)),
        vec4<f32>(a.hi, bitcast<f32>(a.count_axis)),
        vec4<f32>(b.lo, bitcast<f32>(b.first)),
        vec4<f32>(b.hi, bitcast<f32>(b.count_axis)),
        vec4<f32>(c.lo, bitcast<f32>(c.first)),
        vec4<f32>(c.hi, bitcast<f32>(c.count_axis)),
        d.first,
        d.count_axis,
    );
}

/// The point `p` mapped by the rows r0..r2: ((m0·x + m1·y) + m2·z) + t each.
fn map_point(r0: vec4<f32>, r1: vec4<f32>, r2: vec4<f32>, p: vec3<f32>) -> vec3<f32> {
    return vec3<f32>(
        r0.x * p.x + r0.y * p.y + r0.z * p.z + r0.w,
        r1.x * p.x + r1.y * p.y + r1.z * p.z + r1.w,
        r2.x * p.x + r2.y * p.y + r2.z * p.z + r2.w,
    );
}

/// The vector `v` mapped by the linear part of the rows r0..r2.
fn map_vector(r0: vec4<f32>, r1: vec4<f32>, r2: vec4<f32>, v: vec3<f32>) -> vec3<f32> {
    return vec3<f32>(
        r0.x * v.x + r0.y * v.y + r0.z * v.z,
        r1.x * v.x + r1.y * v.y + r1.z * v.z,
        r2.x * v.x + r2.y * v.y + r2.z * v.z,
    );
}

/// The normal `n` mapped by the transpose of the linear part of the rows r0..r2 (by the
/// world-to-object rows, the inverse transpose of the object-to-world map).
fn map_normal(r0: vec4<f32>, r1: vec4<f32>, r2: vec4<f32>, n: vec3<f32>) -> vec3<f32> {
    return vec3<f32>(
        r0.x * n.x + r1.x * n.y + r2.x * n.z,
        r0.y * n.x + r1.y * n.y + r2.y * n.z,
        r0.z * n.x + r1.z * n.y + r2.z * n.z,
    );
}

/// The world ray in instance `x`'s object space (itself for the identity).
fn ray_into(x: InstanceX, ray: Ray) -> Ray {
    if (x.root & INSTANCE_IDENTITY) != 0u {
        return ray;
    }
    return Ray(map_point(x.o0, x.o1, x.o2, ray.origin), map_vector(x.o0, x.o1, x.o2, ray.dir));
}

/// The hit's triangle in world space, of the material it is shaded with: its corners
/// mapped by the instance's object-to-world map, its material the instance's where it
/// has one. Where the scene has no instances, the triangle as stored.
fn triangle_of(hit: Hit) -> Triangle {
    var tri = triangles[hit.prim & ~TRIANGLE_BIT];
    if INSTANCES {
        let x = instance_at(hit.inst);
        if (x.root & INSTANCE_IDENTITY) == 0u {
            tri.a = map_point(x.w0, x.w1, x.w2, tri.a);
            tri.b = map_point(x.w0, x.w1, x.w2, tri.b);
            tri.c = map_point(x.w0, x.w1, x.w2, tri.c);
        }
        if x.material != NO_MATERIAL {
            tri.material = x.material;
        }
    }
    return tri;
}

/// The hit triangle's vertex normals in world space: each mapped by the inverse transpose
/// and made unit again (Hanika's lift projects onto their planes), unless the instance is
/// the identity.
fn normals_of(hit: Hit, tri: Triangle) -> VertexNormals {
    var vn = normals[tri.normals];
    if INSTANCES {
        let x = instance_at(hit.inst);
        if (x.root & INSTANCE_IDENTITY) == 0u {
            vn.na = normalize_rn(map_normal(x.o0, x.o1, x.o2, vn.na));
            vn.nb = normalize_rn(map_normal(x.o0, x.o1, x.o2, vn.nb));
            vn.nc = normalize_rn(map_normal(x.o0, x.o1, x.o2, vn.nc));
        }
    }
    return vn;
}

/// Whether a hit at t on primitive `id` of instance `inst` beats `best`: nearer, or as
/// near with a lower (instance, primitive) pair.
fn nearer_in(t: f32, inst: u32, id: u32, best: Hit) -> bool {
    if t < best.t {
        return true;
    }
    if !(t == best.t) || best.prim == PRIM_NONE {
        return false;
    }
    return inst < best.inst || (inst == best.inst && id < best.prim);
}

/// `closest_hit` through the two levels, depth first as `closest_hit_bvh`. At a top-level
/// leaf the ray is taken into the instance's object space and the search goes on at its
/// mesh's root; when the stack is back at the depth it had there, the mesh is done and
/// the world ray is restored. One stack holds both levels (each at most `BVH_STACK` deep).
fn closest_hit_top(ray: Ray, t_min: f32, t_max: f32) -> Hit {
    var best = Hit(t_max, PRIM_NONE, 0.0, 0.0, 0u);
    if params.n_nodes == 0u {
        return best;
    }
    let world_inv = div3_rn(vec3<f32>(1.0), ray.dir);
    let world_sh = ray_shear(ray.dir);
    let root = box_interval(nodes[0], ray.origin, world_inv, t_min, t_max);
    if !(root.x <= root.y) {
        return best;
    }
    var r = ray;
    var inv_dir = world_inv;
    var sh = world_sh;
    var inst = NO_INSTANCE;
    var inst_sp = 0u;
    var stack: array<u32, TOP_STACK>;
    var sp = 0u;
    var at = 0u;
    loop {
        let node = nodes[at];
        let count = node.count_axis >> 2u;
        if count == 0u {
            let bound = tie_bound(best);
            let left = box_interval(nodes[at + 1u], r.origin, inv_dir, t_min, bound);
            let right = box_interval(nodes[node.first], r.origin, inv_dir, t_min, bound);
            let hit_left = left.x <= left.y;
            let hit_right = right.x <= right.y;
            if hit_left && hit_right {
                if right.x < left.x {
                    stack[sp] = at + 1u;
                    at = node.first;
                } else {
                    stack[sp] = node.first;
                    at = at + 1u;
                }
                sp = sp + 1u;
                continue;
            }
            if hit_left {
                at = at + 1u;
                continue;
            }
            if hit_right {
                at = node.first;
                continue;
            }
        } else if inst == NO_INSTANCE {
            inst = node.first;
            inst_sp = sp;
            let x = instance_at(inst);
            r = ray_into(x, ray);
            inv_dir = div3_rn(vec3<f32>(1.0), r.dir);
            sh = ray_shear(r.dir);
            at = x.root & ~INSTANCE_IDENTITY;
            continue;
        } else {
            for (var k = node.first; k < node.first + count; k = k + 1u) {
                let id = prim_ids[k];
                let h = hit_prim(r, sh, id, t_min, tie_bound(best));
                if nearer_in(h.x, inst, id, best) {
                    best = Hit(h.x, id, h.y, h.z, inst);
                }
            }
        }
        if inst != NO_INSTANCE && sp == inst_sp {
            inst = NO_INSTANCE;
            r = ray;
            inv_dir = world_inv;
            sh = world_sh;
        }
        if sp == 0u {
            break;
        }
        sp = sp - 1u;
        at = stack[sp];
    }
    return best;
}

/// `occluded` through the two levels, in `closest_hit_top`'s order; stops at the first
/// hit. `skip` is primitive `skip` of instance `skip_inst` only: the same triangle placed
/// elsewhere shadows as any other.
fn occluded_top(ray: Ray, t_min: f32, t_max: f32, skip: u32, skip_inst: u32) -> bool {
    if params.n_nodes == 0u {
        return false;
    }
    let world_inv = div3_rn(vec3<f32>(1.0), ray.dir);
    let world_sh = ray_shear(ray.dir);
    let root = box_interval(nodes[0], ray.origin, world_inv, t_min, t_max);
    if !(root.x <= root.y) {
        return false;
    }
    var r = ray;
    var inv_dir = world_inv;
    var sh = world_sh;
    var inst = NO_INSTANCE;
    var inst_sp = 0u;
    var stack: array<u32, TOP_STACK>;
    var sp = 0u;
    var at = 0u;
    loop {
        let node = nodes[at];
        let count = node.count_axis >> 2u;
        if count == 0u {
            let left = box_interval(nodes[at + 1u], r.origin, inv_dir, t_min, t_max);
            let right = box_interval(nodes[node.first], r.origin, inv_dir, t_min, t_max);
            let hit_left = left.x <= left.y;
            let hit_right = right.x <= right.y;
            if hit_left && hit_right {
                if right.x < left.x {
                    stack[sp] = at + 1u;
                    at = node.first;
                } else {
                    stack[sp] = node.first;
                    at = at + 1u;
                }
                sp = sp + 1u;
                continue;
            }
            if hit_left {
                at = at + 1u;
                continue;
            }
            if hit_right {
                at = node.first;
                continue;
            }
        } else if inst == NO_INSTANCE {
            inst = node.first;
            inst_sp = sp;
            let x = instance_at(inst);
            r = ray_into(x, ray);
            inv_dir = div3_rn(vec3<f32>(1.0), r.dir);
            sh = ray_shear(r.dir);
            at = x.root & ~INSTANCE_IDENTITY;
            continue;
        } else {
            for (var k = node.first; k < node.first + count; k = k + 1u) {
                let id = prim_ids[k];
                if !(id == skip && inst == skip_inst) && hit_prim(r, sh, id, t_min, t_max).x < t_max {
                    return true;
                }
            }
        }
        if inst != NO_INSTANCE && sp == inst_sp {
            inst = NO_INSTANCE;
            r = ray;
            inv_dir = world_inv;
            sh = world_sh;
        }
        if sp == 0u {
            break;
        }
        sp = sp - 1u;
        at = stack[sp];
    }
    return false;
}
