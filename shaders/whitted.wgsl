// glint's kernel, part 6 of 8: Whitted's secondary rays (1980), compiled in only where a
// scene has a mirror or glass (`WHITTED`). CPU mirror: `src/cpu/whitted.rs`, function for
// function.
//
// The colour at a hit is its local shading plus kr·L(reflected) + kt·L(refracted), each L
// the same sum one level down, to `params.max_depth` levels. WGSL has no recursion, and the
// sum is linear in the children, so the tree is walked depth-first with a stack of rays
// that carry premultiplied weights (the product of the kr and kt factors along their path):
// each popped ray adds weight × its local colour (or the background) and pushes its own
// children. The sum's order is the pop order: at each hit the transmitted ray is pushed
// first and the reflected one last, so the reflected subtree is added first.
//
// - Entering or leaving is the sign of d·n with the geometric normal; the relative index
//   is ior entering, 1/ior leaving (the outside medium is 1; nested media are not modelled).
// - Fresnel (`fresnel = 1`): kr·F and kt·(1 − F), F the exact unpolarised dielectric
//   reflectance (pbrt-v4 `FrDielectric`). Total internal reflection: no transmitted ray,
//   its weight kt (kt·(1 − F) = 0 with Fresnel) joins the reflected one.
// - Directions turn about the shading normal (smooth meshes); a direction that would leave
//   on the wrong side of the geometric surface (a reflected ray under it, a transmitted
//   ray over it, which interpolated normals allow) is mirrored about the geometric plane.
// - Origins: the hit point pushed off the surface to the side the ray leaves by
//   (`spawn_origin`), by 16 ε of the largest coordinate of the point and of the ray's
//   origin: the hit point o + d·t is computed to a few ε of |o| + |p|, along the normal
//   too, and 16 ε stays small beside the smallest sphere worth tracing at that scale (its
//   radius a few tens of ulps). Reflected rays leave from the shadow rays' own (lifted)
//   point.
// - A ray whose weight's largest channel is 0 or below `params.min_weight` is not traced.
// - Shadow rays are blocked by transmissive surfaces too, as in Whitted's model.

/// The most rays waiting at once: the walk is depth-first and a hit leaves at most two
/// rays, so the stack holds one waiting sibling per level above the deepest hit plus that
/// hit's two rays: max_depth + 1 for the largest max_depth, 16.
const WHITTED_STACK: u32 = 17u;

/// A secondary ray waiting on the stack.
struct Pending {
    origin: vec3<f32>,
    /// The reflections and refractions that made it (1 for a primary hit's rays).
    depth: u32,
    dir: vec3<f32>,
    /// Its premultiplied weight.
    weight: vec3<f32>,
}

/// The unpolarised Fresnel reflectance of a dielectric boundary (pbrt-v4 `FrDielectric`)
/// at an incidence of cosine `cos_i` ≥ 0, relative index `eta` (the far side's over the
/// near side's), and `sin2_t`, the squared sine of the transmitted angle
/// ((1 − cos_i²) / eta²); 1 at and beyond the critical angle (`sin2_t >= 1`); 0 where
/// `eta` is 1 (no boundary: grazing rays included, which would otherwise meet 0/0).
fn fresnel_dielectric(cos_i: f32, eta: f32, sin2_t: f32) -> f32 {
    if eta == 1.0 {
        return 0.0;
    }
    if sin2_t >= 1.0 {
        return 1.0;
    }
    let cos_t = sqrt_rn(max0(1.0 - sin2_t));
    let r_parl = div_rn(eta * cos_i - cos_t, eta * cos_i + cos_t);
    let r_perp = div_rn(cos_i - eta * cos_t, cos_i + eta * cos_t);
    return flush(div_rn(flush(r_parl * r_parl) + flush(r_perp * r_perp), 2.0));
}

/// The origin of a secondary ray leaving the hit `p` of a ray from `o`, on the side of the
/// unit normal `n`: 16 ε of the largest coordinate of `o`, `p` (and 1) along `n`.
fn spawn_origin(o: vec3<f32>, p: vec3<f32>, n: vec3<f32>) -> vec3<f32> {
    let scale_p = max2(max2(abs(p.x), abs(p.y)), max2(abs(p.z), 1.0));
    let scale = max2(scale_p, max2(max2(abs(o.x), abs(o.y)), abs(o.z)));
    return p + n * (scale * SHADOW_EPSILON * 16.0);
}

/// Whether a ray of weight `w` is traced: its largest channel is positive and reaches
/// `params.min_weight`.
fn worth_tracing(w: vec3<f32>) -> bool {
    let m = max2(max2(w.x, w.y), w.z);
    return m > 0.0 && m >= params.min_weight;
}

/// `dir`, mirrored about the plane of unit normal `n` when it does not leave on the side
/// that `side` (+1 the normal's, −1 the other) says.
fn keep_side(dir: vec3<f32>, n: vec3<f32>, side: f32) -> vec3<f32> {
    let along = dot(dir, n);
    if along * side > 0.0 {
        return dir;
    }
    return dir - n * (2.0 * along);
}

/// Pushes the rays that leave the hit `hit` of `ray`, a ray of weight `weight` made by
/// `depth` bounces, onto `stack` above `sp`: the transmitted ray, then the reflected one,
/// each where the material has it and its weight is worth tracing. Returns the new top.
fn push_children(stack: ptr<function, array<Pending, WHITTED_STACK>>, sp: u32, ray: Ray, hit: Hit, weight: vec3<f32>, depth: u32) -> u32 {
    let m = materials[prim_material(hit)];
    let reflects = max2(max2(m.kr.x, m.kr.y), m.kr.z) > 0.0;
    let transmits = max2(max2(m.kt.x, m.kt.y), m.kt.z) > 0.0;
    if !reflects && !transmits {
        return sp;
    }
    let p = ray.origin + ray.dir * hit.t;
    var n = prim_normal(hit, p);
    let entering = !(dot(n, ray.dir) > 0.0);
    if !entering {
        n = -n;
    }
    let sh = shading_at(hit, p, n);
    let d = normalize_rn(ray.dir);
    let cos_i = max0(-dot(d, sh.n));
    var eta = m.ior;
    if !entering {
        eta = div_rn(1.0, m.ior);
    }
    let sin2_t = div_rn(max0(1.0 - cos_i * cos_i), eta * eta);
    let tir = transmits && sin2_t >= 1.0;
    var wr = m.kr;
    var wt = m.kt;
    if m.fresnel != 0u {
        let f = fresnel_dielectric(cos_i, eta, sin2_t);
        wr = m.kr * f;
        wt = m.kt * (1.0 - f);
    }
    if tir {
        wr = wr + wt;
    }
    var top = sp;
    let w_t = flush3(weight * wt);
    if transmits && !tir && worth_tracing(w_t) {
        let cos_t = sqrt_rn(max0(1.0 - sin2_t));
        let t = keep_side(div3s_rn(d, eta) + sh.n * (div_rn(cos_i, eta) - cos_t), n, -1.0);
        (*stack)[top] = Pending(spawn_origin(ray.origin, p, -n), depth + 1u, t, w_t);
        top = top + 1u;
    }
    let w_r = flush3(weight * wr);
    if (reflects || tir) && worth_tracing(w_r) {
        let r = keep_side(d + sh.n * (2.0 * cos_i), n, 1.0);
        (*stack)[top] = Pending(spawn_origin(ray.origin, sh.p, n), depth + 1u, r, w_r);
        top = top + 1u;
    }
    return top;
}

/// The colour at the first hit `hit` of `ray` whose local shading is `local`, with every
/// reflection and refraction below it to `params.max_depth`: `local` + Σ weight × colour
/// in the order the rays leave the stack, clamped to [0, 1].
fn secondary(ray: Ray, hit: Hit, local: vec3<f32>) -> vec3<f32> {
    var stack: array<Pending, WHITTED_STACK>;
    var color = local;
    var sp = 0u;
    if params.max_depth > 0u {
        sp = push_children(&stack, 0u, ray, hit, vec3<f32>(1.0, 1.0, 1.0), 0u);
    }
    loop {
        if sp == 0u {
            break;
        }
        sp = sp - 1u;
        let next = stack[sp];
        let r = Ray(next.origin, next.dir);
        let h = closest_hit(r, 0.0, INFINITY);
        if h.prim == PRIM_NONE {
            color = color + flush3(next.weight * params.background);
            continue;
        }
        color = color + flush3(next.weight * shade(r, h));
        if next.depth < params.max_depth {
            sp = push_children(&stack, sp, r, h, next.weight, next.depth);
        }
    }
    return vec3<f32>(clamp01(color.x), clamp01(color.y), clamp01(color.z));
}
