// glint's kernel, part 4 of 8: rays through the scene (after `common.wgsl` and
// `prims.wgsl`; see the first's header for how the parts are joined and mirrored). The
// camera, the searches for the nearest hit and for a blocker (every primitive, or the
// BVH), shading, and the entry points. Mirror: `src/cpu/trace.rs`.

// ---- the camera ------------------------------------------------------------------------

/// The primary ray through the point (dx, dy) of pixel (i, j), each in [0, 1) from its
/// top-left corner; the camera formula of docs/scene-format.md, left to right (the centre is (0.5, 0.5)).
fn camera_ray(i: u32, j: u32, dx: f32, dy: f32) -> Ray {
    let x = (div_rn(f32(i) + dx, f32(params.width)) * 2.0 - 1.0) * params.tan_half * params.aspect;
    let y = (1.0 - div_rn(f32(j) + dy, f32(params.height)) * 2.0) * params.tan_half;
    let dir = normalize_rn(params.forward + params.right * x + params.up * y);
    return Ray(params.eye, dir);
}

// ---- the scene ---------------------------------------------------------------------------

/// `best`, or the nearest sphere hit in (t_min, best.t) if there is one; the first sphere
/// wins ties. Every sphere is tested (also by the ray-query tracer, `trace_rq.wgsl`).
fn closest_sphere(ray: Ray, t_min: f32, best: Hit) -> Hit {
    var b = best;
    for (var k = 0u; k < params.n_spheres; k = k + 1u) {
        let t = hit_sphere(ray, spheres[k], t_min, b.t);
        if t < b.t {
            b = Hit(t, k, 0.0, 0.0, 0u);
        }
    }
    return b;
}

/// Whether a sphere other than primitive `skip` lies on the ray in (t_min, t_max), testing
/// every sphere; stops at the first hit.
fn sphere_blocks(ray: Ray, t_min: f32, t_max: f32, skip: u32) -> bool {
    for (var k = 0u; k < params.n_spheres; k = k + 1u) {
        if k != skip && hit_sphere(ray, spheres[k], t_min, t_max) < t_max {
            return true;
        }
    }
    return false;
}

/// The nearest hit in (t_min, t_max) over every sphere, then every triangle; the first
/// primitive wins ties. `prim` is PRIM_NONE on a miss.
fn closest_hit_all(ray: Ray, t_min: f32, t_max: f32) -> Hit {
    var best = Hit(t_max, PRIM_NONE, 0.0, 0.0, 0u);
    if HAS_SPHERES {
        best = closest_sphere(ray, t_min, best);
    }
    if HAS_TRIANGLES {
        let sh = ray_shear(ray.dir);
        for (var k = 0u; k < params.n_triangles; k = k + 1u) {
            let h = hit_triangle(ray, sh, triangles[k], t_min, best.t);
            if h.x < best.t {
                best = Hit(h.x, k | TRIANGLE_BIT, h.y, h.z, 0u);
            }
        }
    }
    return best;
}

/// Whether anything but primitive `skip` lies on the ray in (t_min, t_max), testing every
/// primitive; stops at the first hit.
fn occluded_all(ray: Ray, t_min: f32, t_max: f32, skip: u32) -> bool {
    if HAS_SPHERES && sphere_blocks(ray, t_min, t_max, skip) {
        return true;
    }
    if HAS_TRIANGLES {
        let sh = ray_shear(ray.dir);
        for (var k = 0u; k < params.n_triangles; k = k + 1u) {
            if (k | TRIANGLE_BIT) != skip && hit_triangle(ray, sh, triangles[k], t_min, t_max).x < t_max {
                return true;
            }
        }
    }
    return false;
}

// ---- the BVH -----------------------------------------------------------------------------

/// The part (t0, t1) of the ray's interval (t_min, t_max) inside the node's box; the box
/// is hit when t0 <= t1. The slab test, the exit distance widened by 2γ(3) of itself
/// (pbrt), so rounding never loses a box that the exact ray enters: the nearest exit,
/// then widened once (x + |x|·2γ(3) never decreases as x grows, so that is each exit
/// widened, then the nearest). NaN slabs (a zero direction component at a slab's plane)
/// constrain nothing. `inv_dir` is 1 / dir per component (±inf for a zero component).
fn box_interval(node: BvhNode, origin: vec3<f32>, inv_dir: vec3<f32>, t_min: f32, t_max: f32) -> vec2<f32> {
    let t_lo = (node.lo - origin) * inv_dir;
    let t_hi = (node.hi - origin) * inv_dir;
    let swap = t_hi < t_lo;
    let near = select(t_lo, t_hi, swap);
    let far = select(t_hi, t_lo, swap);
    var t0 = t_min;
    t0 = select(t0, near.x, near.x > t0);
    t0 = select(t0, near.y, near.y > t0);
    t0 = select(t0, near.z, near.z > t0);
    var f = INFINITY;
    f = select(f, far.x, far.x < f);
    f = select(f, far.y, far.y < f);
    f = select(f, far.z, far.z < f);
    // An exit at -∞ (a slab the ray runs parallel to, outside it) is raised to -INFINITY,
    // the largest finite f32 below 0, which widens to a negative number: a miss. Widened
    // itself it would be NaN, which the select below would pass over, keeping the box.
    f = max2(f, -INFINITY);
    f = f + abs(f) * BOX_SLACK;
    let t1 = select(t_max, f, f < t_max);
    return vec2<f32>(t0, t1);
}

/// The bound to test against when `best` is the nearest hit so far: one ULP past best.t,
/// so that a tie is seen and the lower id can win it, whatever order the BVH visits in.
fn tie_bound(best: Hit) -> f32 {
    if best.prim != PRIM_NONE && best.t > 0.0 && best.t <= INFINITY {
        return bitcast<f32>(bitcast<u32>(best.t) + 1u);
    }
    return best.t;
}

/// Whether a hit at t on primitive `id` beats `best`: nearer, or as near with a lower id
/// (the rule that `closest_hit_all` keeps by visiting in id order).
fn nearer(t: f32, id: u32, best: Hit) -> bool {
    return t < best.t || (t == best.t && id < best.prim && best.prim != PRIM_NONE);
}

/// `closest_hit` through the BVH, depth first: at an interior node both children's boxes
/// are tested, the nearer entered first and the other pushed. A fixed stack (the builder
/// bounds the depth) and at most one step per node, so a NaN ray cannot loop. Same result
/// as `closest_hit_all`.
fn closest_hit_bvh(ray: Ray, t_min: f32, t_max: f32) -> Hit {
    var best = Hit(t_max, PRIM_NONE, 0.0, 0.0, 0u);
    let sh = ray_shear(ray.dir);
    let inv_dir = div3_rn(vec3<f32>(1.0), ray.dir);
    if params.n_nodes == 0u {
        return best;
    }
    let root = box_interval(nodes[0], ray.origin, inv_dir, t_min, t_max);
    if !(root.x <= root.y) {
        return best;
    }
    var stack: array<u32, BVH_STACK>;
    var sp = 0u;
    var at = 0u;
    for (var step = 0u; step < params.n_nodes; step = step + 1u) {
        let node = nodes[at];
        let count = node.count_axis >> 2u;
        if count == 0u {
            let bound = tie_bound(best);
            let left = box_interval(nodes[at + 1u], ray.origin, inv_dir, t_min, bound);
            let right = box_interval(nodes[node.first], ray.origin, inv_dir, t_min, bound);
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
        } else {
            for (var k = node.first; k < node.first + count; k = k + 1u) {
                let id = prim_ids[k];
                let h = hit_prim(ray, sh, id, t_min, tie_bound(best));
                if nearer(h.x, id, best) {
                    best = Hit(h.x, id, h.y, h.z, 0u);
                }
            }
        }
        if sp == 0u {
            break;
        }
        sp = sp - 1u;
        at = stack[sp];
    }
    return best;
}

/// `occluded` through the BVH, in `closest_hit_bvh`'s order; stops at the first hit.
/// It repeats `closest_hit_bvh`'s loop rather than sharing a helper: with one push and one
/// pop site per loop, lavapipe runs fewer per-lane stack accesses (a shared `descend`
/// helper measured 40% slower; docs/bench/meshes.md).
fn occluded_bvh(ray: Ray, t_min: f32, t_max: f32, skip: u32) -> bool {
    let sh = ray_shear(ray.dir);
    let inv_dir = div3_rn(vec3<f32>(1.0), ray.dir);
    if params.n_nodes == 0u {
        return false;
    }
    let root = box_interval(nodes[0], ray.origin, inv_dir, t_min, t_max);
    if !(root.x <= root.y) {
        return false;
    }
    var stack: array<u32, BVH_STACK>;
    var sp = 0u;
    var at = 0u;
    for (var step = 0u; step < params.n_nodes; step = step + 1u) {
        let node = nodes[at];
        let count = node.count_axis >> 2u;
        if count == 0u {
            let left = box_interval(nodes[at + 1u], ray.origin, inv_dir, t_min, t_max);
            let right = box_interval(nodes[node.first], ray.origin, inv_dir, t_min, t_max);
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
        } else {
            for (var k = node.first; k < node.first + count; k = k + 1u) {
                let id = prim_ids[k];
                if id != skip && hit_prim(ray, sh, id, t_min, t_max).x < t_max {
                    return true;
                }
            }
        }
        if sp == 0u {
            break;
        }
        sp = sp - 1u;
        at = stack[sp];
    }
    return false;
}

/// t_max with +inf lowered to INFINITY (f32::MAX), the miss value of every intersection
/// test: a miss must never be nearer than the bound. NaN stays NaN (nothing is hit).
fn finite_bound(t_max: f32) -> f32 {
    return select(t_max, INFINITY, t_max > INFINITY);
}

/// The nearest hit in (t_min, t_max); of hits at the same t, the lowest primitive id
/// (spheres before triangles). `prim` is PRIM_NONE on a miss.
fn closest_hit(ray: Ray, t_min: f32, t_max: f32) -> Hit {
    let t_hi = finite_bound(t_max);
    if INSTANCES {
        return closest_hit_top(ray, t_min, t_hi);
    }
    if USE_BVH {
        return closest_hit_bvh(ray, t_min, t_hi);
    }
    return closest_hit_all(ray, t_min, t_hi);
}

/// Whether anything but primitive `skip` (of instance `skip_inst`) lies on the ray in
/// (t_min, t_max); stops at the first hit. A convex primitive (a sphere, a flat triangle)
/// cannot shadow a point of its own where N·L > 0, so skipping the one that was hit loses
/// no shadow and removes all self-shadowing, whatever the rounding of the hit point.
fn occluded(ray: Ray, t_min: f32, t_max: f32, skip: u32, skip_inst: u32) -> bool {
    let t_hi = finite_bound(t_max);
    if INSTANCES {
        return occluded_top(ray, t_min, t_hi, skip, skip_inst);
    }
    if USE_BVH {
        return occluded_bvh(ray, t_min, t_hi, skip);
    }
    return occluded_all(ray, t_min, t_hi, skip);
}

// ---- shading -----------------------------------------------------------------------------

/// `base^n` for the material's exponent: by squaring when `n_int >= 0` (0^0 = 1), else
/// `pow_det` (exact.wgsl: never the driver's `exp2` and `log2`); 0 where
/// the power is subnormal (`flush`: base ≤ 1, so every product on the way is at most the
/// last, and a driver that flushes a subnormal step ends at 0 too).
fn phong_power(base: f32, m: Material) -> f32 {
    // POWERS is off only where no material has `n_int < 0`: the guard changes no result.
    if POWERS && m.n_int < 0 {
        return flush(pow_det(base, m.n));
    }
    var result = 1.0;
    var b = base;
    var e = u32(m.n_int);
    for (var k = 0u; k < 32u; k = k + 1u) {
        if e == 0u {
            break;
        }
        if (e & 1u) != 0u {
            result = result * b;
        }
        b = b * b;
        e = e >> 1u;
    }
    return flush(result);
}

/// The offset origin of a shadow ray from `p` with facing normal `n` (buffers::SHADOW_EPSILON).
fn shadow_origin(p: vec3<f32>, n: vec3<f32>) -> vec3<f32> {
    let scale = max2(max2(abs(p.x), abs(p.y)), max2(abs(p.z), 1.0));
    return p + n * (scale * SHADOW_EPSILON * 64.0);
}

/// A spot light's weight for a point whose direction from the light makes cosine `c` with
/// the spot's axis: 0 at or beyond `cos_outer`, 1 from `cos_inner` in, and between them
/// the smoothstep s²(3 − 2s) of s = (c − cos_outer) / (cos_inner − cos_outer).
fn spot_factor(light: Light, c: f32) -> f32 {
    if !(c > light.cos_outer) {
        return 0.0;
    }
    if c >= light.cos_inner {
        return 1.0;
    }
    let s = div_rn(c - light.cos_outer, light.cos_inner - light.cos_outer);
    return s * s * (3.0 - 2.0 * s);
}

/// The Phong model (docs/scene-format.md) at a hit: I = Ia·ka + Σ Ip·kd·max(0, N·L) + Ip·ks·max(0, R·V)^n,
/// each term only if the material's model has it, clamped to [0, 1]. A term below the
/// smallest normal f32 is 0 (`flush`), so that drivers that flush subnormals agree.
fn shade(ray: Ray, hit: Hit) -> vec3<f32> {
    let m = materials[prim_material(hit)];
    let a = albedo(hit, m);
    let p = ray.origin + ray.dir * hit.t;
    var n = prim_normal(hit, p);
    if dot(n, ray.dir) > 0.0 {
        n = -n;
    }
    let sh = shading_at(hit, p, n);
    var color = flush3(params.ambient * a.ka);
    if USES_DIFFUSE && m.model != MODEL_AMBIENT {
        // The view vector is the reversed ray. Not `normalize(ray.origin - p)`: that is
        // origin − (origin + dir·t), which loses low bits to cancellation, and which
        // lavapipe's compiler folds to −dir·t while Rust rounds p first, so the two
        // tracers disagreed in low bits under sharp highlights.
        let v = normalize_rn(-ray.dir);
        for (var k = 0u; k < params.n_lights; k = k + 1u) {
            let light = lights[k];
            var to_light = light.position - p;
            if LIGHT_KINDS && light.kind == LIGHT_DIRECTIONAL {
                to_light = -light.direction;
            }
            let l = normalize_rn(to_light);
            let ndl = dot(sh.n, l);
            if !(ndl > 0.0) {
                continue;
            }
            var ip = light.color;
            if LIGHT_KINDS && light.kind == LIGHT_SPOT {
                let s = spot_factor(light, -dot(l, light.direction));
                if !(s > 0.0) {
                    continue;
                }
                ip = ip * s;
            }
            if SHADOWS {
                let o = shadow_origin(sh.p, n);
                if LIGHT_KINDS && light.kind == LIGHT_DIRECTIONAL {
                    // Towards the light without end.
                    if occluded(Ray(o, l), 0.0, INFINITY, hit.prim, hit.inst) {
                        continue;
                    }
                } else {
                    let d = light.position - o;
                    if occluded(Ray(o, d), 0.0, 1.0, hit.prim, hit.inst) {
                        continue;
                    }
                }
            }
            color = color + flush3(ip * a.kd * ndl);
            if USES_PHONG && m.model == MODEL_PHONG {
                let r = sh.n * (2.0 * ndl) - l;
                let rv = max0(dot(r, v));
                color = color + flush3(ip * m.ks * phong_power(rv, m));
            }
        }
    }
    return vec3<f32>(clamp01(color.x), clamp01(color.y), clamp01(color.z));
}

/// The colour seen through the point (dx, dy) of pixel (i, j) and, in w, the hit
/// distance (−1 for a miss).
fn trace_sample(i: u32, j: u32, dx: f32, dy: f32) -> vec4<f32> {
    let ray = camera_ray(i, j, dx, dy);
    let hit = closest_hit(ray, 0.0, INFINITY);
    if hit.prim == PRIM_NONE {
        return vec4<f32>(params.background, -1.0);
    }
    let local = shade(ray, hit);
    if WHITTED {
        return vec4<f32>(secondary(ray, hit, local), hit.t);
    }
    return vec4<f32>(local, hit.t);
}

/// The position of sample s of n along a pixel side: (s + 0.5) / n.
fn sample_offset(s: u32, n: u32) -> f32 {
    return div_rn(f32(s) + 0.5, f32(n));
}

/// The colour of pixel (i, j) and, in w, the hit distance (−1 for a miss). With
/// antialiasing, N = params.samples: the N×N points ((sx + 0.5) / N, (sy + 0.5) / N), rows
/// sy top to bottom, each row sx left to right; their colours summed in that order and
/// divided by N² (a box filter), a quotient below the smallest normal f32 flushed to 0 as
/// the shading terms are; w is the nearest hit's t (−1 when every sample misses).
/// One sample is one ray through the centre, the image without antialiasing to the bit.
fn trace_pixel(i: u32, j: u32) -> vec4<f32> {
    if !ANTIALIAS {
        return trace_sample(i, j, 0.5, 0.5);
    }
    let n = params.samples;
    var sum = vec3<f32>(0.0, 0.0, 0.0);
    var t_near = -1.0;
    for (var sy = 0u; sy < n; sy = sy + 1u) {
        let dy = sample_offset(sy, n);
        for (var sx = 0u; sx < n; sx = sx + 1u) {
            let dx = sample_offset(sx, n);
            let s = trace_sample(i, j, dx, dy);
            sum = sum + s.xyz;
            if s.w >= 0.0 && (t_near < 0.0 || s.w < t_near) {
                t_near = s.w;
            }
        }
    }
    return vec4<f32>(flush3(div3s_rn(sum, f32(n * n))), t_near);
}

// ---- entry points ------------------------------------------------------------------------

/// The pixel (in the tile) of invocation `local` of workgroup `group` (8×8 pixels): each
/// run of eight consecutive invocations, a subgroup on lavapipe, covers a 4×2 block, so a
/// packet of the subgroup traversal is as compact as the CPU's; 32 consecutive ones (an
/// NVIDIA subgroup) cover 8×4.
fn pixel_of(group: vec3<u32>, local: u32) -> vec2<u32> {
    let block = local / 8u;
    let lane = local % 8u;
    let x = (block % 2u) * 4u + lane % 4u;
    let y = (block / 2u) * 2u + lane / 4u;
    return group.xy * 8u + vec2<u32>(x, y);
}

/// One invocation per pixel of the current tile.
@compute @workgroup_size(64, 1, 1)
fn render(@builtin(workgroup_id) group: vec3<u32>, @builtin(local_invocation_index) local: u32) {
    let gid = pixel_of(group, local);
    if gid.x >= params.tile_width || gid.y >= params.tile_height {
        return;
    }
    image[gid.y * params.tile_width + gid.x] = trace_pixel(params.tile_x + gid.x, params.tile_y + gid.y);
}

/// `render` for an 8-bit image (PNG output): a quarter of the bytes written and read back,
/// each pixel `pack_rgba8` of its colour.
@compute @workgroup_size(64, 1, 1)
fn render_rgba8(@builtin(workgroup_id) group: vec3<u32>, @builtin(local_invocation_index) local: u32) {
    let gid = pixel_of(group, local);
    if gid.x >= params.tile_width || gid.y >= params.tile_height {
        return;
    }
    let c = trace_pixel(params.tile_x + gid.x, params.tile_y + gid.y);
    image_rgba8[gid.y * params.tile_width + gid.x] = pack_rgba8(c);
}

/// One invocation per query ray: the nearest hit, as `closest_hit` gives it.
@compute @workgroup_size(64, 1, 1)
fn query(@builtin(global_invocation_id) gid: vec3<u32>) {
    if gid.x >= arrayLength(&rays) {
        return;
    }
    let r = rays[gid.x];
    let h = closest_hit(Ray(r.origin, r.dir), r.t_min, r.t_max);
    hits[gid.x] = HitOut(h.t, h.prim, h.u, h.v);
}
