//! The packet twin of `whitted.rs`: every lane walks its own tree of secondary rays in
//! the mirror's order (its own stack, pushes, pops and sums, through the mirror's own
//! `push_children`), and the lanes step together: at each step every lane with a ray left
//! pops one, and the popped rays, each from its own origin, are traced and shaded as one
//! packet (`closest_hit_lanes`, `shade_lanes`). A lane's sum is the mirror's sum, term for
//! term in the same order, so the image is the mirror's bit for bit. Once fewer than
//! `PACKET_MIN_LANES` lanes have rays left, each finishes alone (the mirror's `walk`).

// Lane loops index several arrays in step, `for l in 0..LANES`, the form LLVM vectorises.
#![allow(clippy::needless_range_loop)]

use super::common::{Build, LANES, Lanes, Mask, PerLane};
use super::prims::shear_lanes;
use super::shade::shade_lanes;
use super::trace::{NO_SLOT, PacketHits, closest_hit_lanes};
use crate::buffers::{PRIM_NONE, TRIANGLE_WATERTIGHT};
use crate::cpu::common::{Globals, Ray, clamp01, flush3};
use crate::cpu::prims::prim_material;
use crate::cpu::whitted::{Pending, WHITTED_STACK, push_children, walk};
use crate::shared::real::V3;

/// The fewest lanes with a ray left for which a step goes as a packet.
const PACKET_MIN_LANES: u32 = 8;

/// `secondary` for the lanes in `mask` (each of which hit something: `rays[l]`'s hit is
/// `found`'s lane l), whose local colours are in `out` (rgb; t is left): `out` becomes
/// each lane's `secondary` colour.
#[inline(always)]
pub(super) fn secondary_lanes<B: Build>(
    b: B,
    g: &Globals<f32>,
    rays: &[Ray<f32>; LANES],
    found: &PacketHits<B::Inst>,
    mask: Mask,
    out: &mut [[f32; 4]; LANES],
) {
    // Only lanes whose material reflects or transmits have rays to walk; the others keep
    // their local colour, which `secondary` would return as it is (already in [0, 1]).
    let mut walks: Mask = 0;
    for l in 0..LANES {
        if (mask >> l) & 1 != 0 {
            let m = &g.buf.materials[prim_material(g, &found.hit(l)) as usize];
            let optics = m.kr.iter().chain(&m.kt).any(|&k| k > 0.0);
            walks |= (optics as Mask) << l;
        }
    }
    if walks == 0 || g.buf.params.max_depth == 0 {
        return;
    }
    let zero = Pending {
        origin: V3::splat(0.0),
        depth: 0,
        dir: V3::splat(0.0),
        weight: V3::splat(0.0),
    };
    let mut stacks = [[zero; WHITTED_STACK]; LANES];
    let mut sp = [0usize; LANES];
    let mut color = [V3::splat(0.0f32); LANES];
    for l in 0..LANES {
        color[l] = V3::new(out[l][0], out[l][1], out[l][2]);
        if (walks >> l) & 1 != 0 {
            sp[l] = push_children(
                g,
                &mut stacks[l],
                0,
                rays[l],
                &found.hit(l),
                V3::splat(1.0),
                0,
            );
        }
    }
    let background = V3::<f32>::from_f32(g.buf.params.background);
    let watertight = g.spec.triangle_algo == TRIANGLE_WATERTIGHT;
    loop {
        let mut live: Mask = 0;
        for l in 0..LANES {
            live |= ((sp[l] != 0) as Mask) << l;
        }
        if live == 0 {
            break;
        }
        // Few lanes left: a packet step would cost sixteen lanes' work for them, so each
        // finishes its walk on its own, through the mirror's loop.
        if live.count_ones() < PACKET_MIN_LANES {
            for l in 0..LANES {
                if (live >> l) & 1 != 0 {
                    color[l] = walk(g, &mut stacks[l], sp[l], color[l]);
                    sp[l] = 0;
                }
            }
            break;
        }
        // Each live lane's next ray; a lane with none borrows the first live lane's, so
        // that its arithmetic stays finite (its results are not read).
        let first = live.trailing_zeros() as usize;
        let mut next = [zero; LANES];
        for l in 0..LANES {
            if (live >> l) & 1 != 0 {
                sp[l] -= 1;
                next[l] = stacks[l][sp[l]];
            }
        }
        let mut o = [[0.0f32; LANES]; 3];
        let mut d = [[0.0f32; LANES]; 3];
        let mut lane_rays = [rays[0]; LANES];
        for l in 0..LANES {
            let s = if (live >> l) & 1 != 0 { l } else { first };
            let (origin, dir) = (next[s].origin, next[s].dir);
            [o[0][l], o[1][l], o[2][l]] = [origin.x, origin.y, origin.z];
            [d[0][l], d[1][l], d[2][l]] = [dir.x, dir.y, dir.z];
            lane_rays[l] = Ray { origin, dir };
        }
        let r = Lanes::new(PerLane(o), &d);
        let sh = shear_lanes(&d, watertight);
        let none = PacketHits {
            t: [f32::MAX; LANES],
            prim: [PRIM_NONE; LANES],
            u: [0.0; LANES],
            v: [0.0; LANES],
            inst: B::Inst::default(),
            slots: [NO_SLOT; LANES],
        };
        let hits = closest_hit_lanes::<B, _>(b, g, &lane_rays, &r, &sh, live, 0.0, none);
        let mut hit: Mask = 0;
        for l in 0..LANES {
            hit |= (((live >> l) & 1 != 0 && hits.prim[l] != PRIM_NONE) as Mask) << l;
        }
        let shaded = shade_lanes::<B, _, _>(b, g, &r.origin, &d, &hits, hit, &mut ());
        for l in 0..LANES {
            if (live >> l) & 1 == 0 {
                continue;
            }
            let w = next[l].weight;
            if (hit >> l) & 1 == 0 {
                color[l] = color[l] + flush3(w * background);
                continue;
            }
            let c = V3::new(shaded[0][l], shaded[1][l], shaded[2][l]);
            color[l] = color[l] + flush3(w * c);
            if next[l].depth < g.buf.params.max_depth {
                let h = hits.hit(l);
                sp[l] = push_children(g, &mut stacks[l], sp[l], lane_rays[l], &h, w, next[l].depth);
            }
        }
    }
    for l in 0..LANES {
        if (walks >> l) & 1 != 0 {
            let c = color[l];
            out[l][0] = clamp01(c.x);
            out[l][1] = clamp01(c.y);
            out[l][2] = clamp01(c.z);
        }
    }
}
