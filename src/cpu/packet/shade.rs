//! The packet twin of `trace.rs`'s `shade`: the shading of a packet's hits, lane by lane
//! (`shade_lanes`), and the Phong exponent's powers as lane loops.

#![allow(clippy::needless_range_loop)]

use super::common::{
    Build, InstLanes, LANES, Mask, Origins, choose, dot_lane, flush_nonneg, mask_of,
    normalize_lanes,
};
use super::instance::occluded_top_lanes;
use super::prims::{prim_material, prim_normal, triangle_normal};
use super::trace::{NO_SLOT, PacketHits, occluded_lanes};
use crate::buffers::{
    Light, MODEL_AMBIENT, MODEL_PHONG, Material, PRIM_NONE, TRIANGLE_BIT, Triangle,
};
use crate::cpu::common::{Globals, clamp01, max0};
use crate::cpu::instance::triangle_of;
use crate::cpu::prims::shading_at;
use crate::cpu::trace::{phong_power, shadow_origin};
use crate::shared::real::V3;

/// What [`shade_lanes`] found of each lane's hit on its way to the colour: the values the
/// mirror's `aov_of` computes for the same hit, in every bit (the same operations).
pub(super) struct HitLanes {
    /// The hit point, origin + dir · t.
    pub p: [[f32; LANES]; 3],
    /// The unit geometric normal, turned to face the ray.
    pub n: [[f32; LANES]; 3],
    /// The shading normal (`shading_at`'s).
    pub ns: [[f32; LANES]; 3],
    /// The material index.
    pub material: [u32; LANES],
}

/// Where [`shade_lanes`] puts what it found of the hits: nowhere (`()`, the colour alone:
/// no code at all), or a [`HitLanes`].
pub(super) trait Facts {
    /// Takes the hits' points, facing geometric normals, shading normals and materials.
    fn put(
        &mut self,
        p: &[[f32; LANES]; 3],
        n: &[[f32; LANES]; 3],
        ns: &[[f32; LANES]; 3],
        material: &[u32; LANES],
    );
}

impl Facts for () {
    #[inline(always)]
    fn put(
        &mut self,
        _: &[[f32; LANES]; 3],
        _: &[[f32; LANES]; 3],
        _: &[[f32; LANES]; 3],
        _: &[u32; LANES],
    ) {
    }
}

impl Facts for HitLanes {
    #[inline(always)]
    fn put(
        &mut self,
        p: &[[f32; LANES]; 3],
        n: &[[f32; LANES]; 3],
        ns: &[[f32; LANES]; 3],
        material: &[u32; LANES],
    ) {
        (self.p, self.n, self.ns, self.material) = (*p, *n, *ns, *material);
    }
}

/// `shade` for the lanes in `mask`, which must all hit something: the same operations in
/// the same order, lane by lane, with the square roots, divisions and the exponent's
/// squarings as lane loops. Shadow rays and non-integer exponents go lane by lane
/// through the mirror's own `occluded` and `phong_power`. `dir` holds the rays'
/// directions as lane arrays. Lanes outside `mask` compute values that are not used: the
/// point on their own ray (far off or infinite for a miss), the material and normal of
/// the primitive of lane `mask`'s first lane. The hits' points, normals and materials go
/// to `facts` too (not where `mask` is empty).
#[inline(always)]
pub(super) fn shade_lanes<B: Build, O: Origins, F: Facts>(
    b: B,
    g: &Globals<f32>,
    origins: &O,
    dir: &[[f32; LANES]; 3],
    found: &PacketHits<B::Inst>,
    mask: Mask,
    facts: &mut F,
) -> [[f32; LANES]; 3] {
    let mut color = [[0.0f32; LANES]; 3];
    if mask == 0 {
        return color;
    }
    let first = mask.trailing_zeros() as usize;
    let src = |l: usize| if (mask >> l) & 1 != 0 { l } else { first };
    // The hit triangle, from where the traversal read it when it can (a cache hit).
    let tri_of = |l: usize| -> &Triangle {
        let slot = found.slots[l];
        if slot != NO_SLOT {
            return &g.buf.leaf_triangles()[slot as usize];
        }
        &g.buf.triangles[(found.prim[l] & !TRIANGLE_BIT) as usize]
    };
    // One primitive under every lane (a large triangle or sphere in view, the common
    // case): its material, and a triangle's normal, are found once and copied to every
    // lane, the values the lane loops would have found lane by lane. Copied lane by lane
    // (16 scalar stores read back as vectors) they were a third of the 2-triangle frame.
    let prim0 = found.prim[first];
    // An instance's triangle is mapped to world space and may take the instance's
    // material: gathered lane by lane below.
    let mut one_prim = !B::INSTANCES;
    for l in 0..LANES {
        one_prim &= (mask >> l) & 1 == 0 || found.prim[l] == prim0;
    }
    // Each lane's own origin, direction and t (a miss's point is far off or infinite: not
    // used).
    let mut p = [[0.0f32; LANES]; 3];
    for l in 0..LANES {
        let t = found.t[l];
        let o = origins.at(l);
        p[0][l] = o[0] + dir[0][l] * t;
        p[1][l] = o[1] + dir[1][l] * t;
        p[2][l] = o[2] + dir[2][l] * t;
    }
    // Each lane's material and its normal before the normalize (`prim_normal`).
    let mut material = [0u32; LANES];
    let mut nv = [[0.0f32; LANES]; 3];
    if one_prim {
        material = [prim_material(g, &found.hit(first), || tri_of(first)); LANES];
        if (prim0 & TRIANGLE_BIT) != 0 {
            // `prim_normal` of a triangle does not depend on the point.
            let v = prim_normal(g, &found.hit(first), [0.0; 3], || tri_of(first));
            for k in 0..3 {
                nv[k] = [v[k]; LANES];
            }
        } else {
            // `prim_normal` of a sphere: the point less the centre, as a lane loop.
            let c = g.buf.spheres[prim0 as usize].center;
            for l in 0..LANES {
                for k in 0..3 {
                    nv[k][l] = p[k][l] - c[k];
                }
            }
        }
    } else {
        // Several primitives: each lane's triangle's corners (or sphere's centre) gathered
        // into lane arrays with its material, one pass, and `prim_normal` from them as lane
        // loops, its operations in its order: (b - a) × (c - a) for a triangle, p - centre
        // for a sphere. (Through `prim_normal` a lane at a time it was scalar code, sixteen
        // cross products a packet on a fine mesh.)
        let mut corners = [[[0.0f32; LANES]; 3]; 3];
        let mut centre = [[0.0f32; LANES]; 3];
        let mut is_tri = [false; LANES];
        for l in 0..LANES {
            let s = src(l);
            let prim = found.prim[s];
            if (prim & TRIANGLE_BIT) != 0 && B::INSTANCES {
                // `triangle_of`: the corners in world space, the instance's material.
                let tri = triangle_of(g, &found.hit(s));
                let (a, bb, c): ([f32; 3], [f32; 3], [f32; 3]) =
                    (tri.a.into(), tri.b.into(), tri.c.into());
                for k in 0..3 {
                    corners[0][k][l] = a[k];
                    corners[1][k][l] = bb[k];
                    corners[2][k][l] = c[k];
                }
                material[l] = tri.material;
                is_tri[l] = true;
            } else if (prim & TRIANGLE_BIT) != 0 {
                let tri = tri_of(s);
                for k in 0..3 {
                    corners[0][k][l] = tri.a[k];
                    corners[1][k][l] = tri.b[k];
                    corners[2][k][l] = tri.c[k];
                }
                material[l] = tri.material;
                is_tri[l] = true;
            } else {
                let sphere = &g.buf.spheres[prim as usize];
                for k in 0..3 {
                    centre[k][l] = sphere.center[k];
                }
                material[l] = sphere.material;
            }
        }
        let [a, b, c] = &corners;
        for l in 0..LANES {
            let cross: [f32; 3] = triangle_normal(
                V3::new(a[0][l], a[1][l], a[2][l]),
                V3::new(b[0][l], b[1][l], b[2][l]),
                V3::new(c[0][l], c[1][l], c[2][l]),
            )
            .into();
            for k in 0..3 {
                let radial = p[k][l] - centre[k][l];
                nv[k][l] = if is_tri[l] { cross[k] } else { radial };
            }
        }
    }
    // A loop, not `array::from_fn`: that was left a call of its own (5 % of the frame).
    // The terms are copied into lane arrays here, the one gather a lane, so that the lane
    // loops below read them in step and vectorise (through `mats[l]` each was a gather);
    // splatted where every lane has the same material.
    let mut mats: [&Material; LANES] = [&g.buf.materials[0]; LANES];
    let mut ka = [[0.0f32; LANES]; 3];
    let mut kd = [[0.0f32; LANES]; 3];
    let mut ks = [[0.0f32; LANES]; 3];
    let mut model = [0u32; LANES];
    if material.iter().all(|&m| m == material[0]) {
        let m = &g.buf.materials[material[0] as usize];
        mats = [m; LANES];
        for c in 0..3 {
            ka[c] = [m.ka[c]; LANES];
            kd[c] = [m.kd[c]; LANES];
            ks[c] = [m.ks[c]; LANES];
        }
        model = [m.model; LANES];
    } else {
        for l in 0..LANES {
            let m = &g.buf.materials[material[l] as usize];
            mats[l] = m;
            for c in 0..3 {
                ka[c][l] = m.ka[c];
                kd[c][l] = m.kd[c];
                ks[c][l] = m.ks[c];
            }
            model[l] = m.model;
        }
    }
    let mut n = normalize_lanes(&nv);
    let ambient = g.buf.params.ambient;
    let mut diffuse_flags = [false; LANES];
    for l in 0..LANES {
        if dot_lane(&n, dir, l) > 0.0 {
            n[0][l] = -n[0][l];
            n[1][l] = -n[1][l];
            n[2][l] = -n[2][l];
        }
        for k in 0..3 {
            color[k][l] = flush_nonneg(ambient[k] * ka[k][l]);
        }
        diffuse_flags[l] = model[l] != MODEL_AMBIENT;
    }
    let diffuse = mask_of(&diffuse_flags) & mask;
    // `shading_at`, lane by lane through the mirror's own function: the shading normal
    // `ns` and the shadow rays' start `ps` (`n` and `p` themselves for a flat hit).
    let mut ns = n;
    let mut ps = p;
    if g.spec.smooth {
        for l in 0..LANES {
            let pl = V3::new(p[0][l], p[1][l], p[2][l]);
            let nl = V3::new(n[0][l], n[1][l], n[2][l]);
            let sh = shading_at(g, &found.hit(src(l)), pl, nl);
            [ns[0][l], ns[1][l], ns[2][l]] = [sh.n.x, sh.n.y, sh.n.z];
            [ps[0][l], ps[1][l], ps[2][l]] = [sh.p.x, sh.p.y, sh.p.z];
        }
    }
    facts.put(&p, &n, &ns, &material);
    if g.spec.uses_diffuse && diffuse != 0 {
        let mut to_eye = [[0.0f32; LANES]; 3];
        for l in 0..LANES {
            to_eye[0][l] = -dir[0][l];
            to_eye[1][l] = -dir[1][l];
            to_eye[2][l] = -dir[2][l];
        }
        let v = normalize_lanes(&to_eye);
        for k in 0..g.buf.params.n_lights {
            let light: &Light = &g.buf.lights[k as usize];
            let position = light.position;
            let light_color = light.color;
            let mut to_light = [[0.0f32; LANES]; 3];
            for l in 0..LANES {
                to_light[0][l] = position[0] - p[0][l];
                to_light[1][l] = position[1] - p[1][l];
                to_light[2][l] = position[2] - p[2][l];
            }
            let lv = normalize_lanes(&to_light);
            let mut ndl = [0.0f32; LANES];
            let mut on_flags = [false; LANES];
            for l in 0..LANES {
                ndl[l] = dot_lane(&ns, &lv, l);
                on_flags[l] = ndl[l] > 0.0;
            }
            let mut on = mask_of(&on_flags) & diffuse;
            if g.spec.shadows && on != 0 {
                let mut so = [[0.0f32; LANES]; 3];
                let mut sd = [[0.0f32; LANES]; 3];
                let mut skip = [PRIM_NONE; LANES];
                for l in 0..LANES {
                    let pl = V3::new(ps[0][l], ps[1][l], ps[2][l]);
                    let nl = V3::new(n[0][l], n[1][l], n[2][l]);
                    let o = shadow_origin(pl, nl);
                    let d = V3::from(position) - o;
                    [so[0][l], so[1][l], so[2][l]] = [o.x, o.y, o.z];
                    [sd[0][l], sd[1][l], sd[2][l]] = [d.x, d.y, d.z];
                    skip[l] = found.prim[l];
                }
                on &= !if B::INSTANCES {
                    let mut skip_inst = [0u32; LANES];
                    for l in 0..LANES {
                        skip_inst[l] = found.inst.lane(l);
                    }
                    occluded_top_lanes::<B>(b, g, so, &sd, &skip, &skip_inst, on)
                } else {
                    occluded_lanes::<B>(b, g, so, &sd, &skip, on)
                };
            }
            // Each lit lane's sum, chosen per lane by bit selects (`choose`: the same value
            // the branch gave; with the flush inside, LLVM made the branch a scalar loop).
            for c in 0..3 {
                for l in 0..LANES {
                    let lit = color[c][l] + flush_nonneg(light_color[c] * kd[c][l] * ndl[l]);
                    color[c][l] = choose(on, l, lit, color[c][l]);
                }
            }
            let mut phong_flags = [false; LANES];
            for l in 0..LANES {
                phong_flags[l] = model[l] == MODEL_PHONG;
            }
            let phong = mask_of(&phong_flags) & on;
            if g.spec.uses_phong && phong != 0 {
                let two = 1.0f32 + 1.0;
                let mut rv = [0.0f32; LANES];
                for l in 0..LANES {
                    let rx = ns[0][l] * (two * ndl[l]) - lv[0][l];
                    let ry = ns[1][l] * (two * ndl[l]) - lv[1][l];
                    let rz = ns[2][l] * (two * ndl[l]) - lv[2][l];
                    rv[l] = max0(rx * v[0][l] + ry * v[1][l] + rz * v[2][l]);
                }
                let pw = phong_power_lanes(&rv, &mats, phong);
                for c in 0..3 {
                    for l in 0..LANES {
                        let lit = color[c][l]
                            + flush_nonneg(light_color[c] * ks[c][l] * flush_nonneg(pw[l]));
                        color[c][l] = choose(phong, l, lit, color[c][l]);
                    }
                }
            }
        }
    }
    for c in 0..3 {
        for l in 0..LANES {
            color[c][l] = clamp01(color[c][l]);
        }
    }
    color
}

/// `phong_power` of every lane in `mask`: integer exponents by squaring as lane loops (a
/// lane whose exponent is spent multiplies no further, as the scalar loop stops), not yet
/// flushed (the caller flushes each lane where it reads it, as the scalar `phong_power`
/// flushes its result); other exponents through `phong_power` itself.
#[inline(always)]
pub(super) fn phong_power_lanes(
    base: &[f32; LANES],
    mats: &[&Material; LANES],
    mask: Mask,
) -> [f32; LANES] {
    let mut result = [1.0f32; LANES];
    let mut b = *base;
    let mut e = [0u32; LANES];
    for l in 0..LANES {
        if (mask >> l) & 1 != 0 {
            if mats[l].n_int < 0 {
                result[l] = phong_power(base[l], mats[l]);
            } else {
                e[l] = mats[l].n_int as u32;
            }
        }
    }
    for _ in 0..32 {
        if e.iter().all(|&x| x == 0) {
            break;
        }
        for l in 0..LANES {
            result[l] = if (e[l] & 1) != 0 {
                result[l] * b[l]
            } else {
                result[l]
            };
            b[l] = b[l] * b[l];
            e[l] >>= 1;
        }
    }
    result
}
