//! The packet twins of `instance.rs`: the two-level searches for a packet of rays. The
//! top-level tree is traversed with the lanes' world rays; at an instance the lanes that
//! reach it go into its object space together, each lane's ray mapped by the mirror's own
//! `ray_into` (the same f32 operations, so the same object ray), and its mesh's tree is
//! searched as the one-level packet search does, with the lanes' bounds carried in and
//! out.
//!
//! As for one level (`mod.rs`), only the order in which leaves are reached differs from
//! each lane's own `closest_hit_top` and `occluded_top`, and their answers do not depend
//! on it: the nearest hit, of equal t the lowest (instance, primitive) pair
//! (`nearer_in`), and whether any primitive but the skipped one of the skipped instance
//! blocks the ray. Each level keeps its own stack here, where the mirror shares one.

// Lane loops index several arrays in step, `for l in 0..LANES`, the form LLVM vectorises.
#![allow(clippy::needless_range_loop)]

use super::common::{Build, InstLanes, LANES, Lanes, Mask, Origins, PerLane};
use super::prims::{ShearLanes, leaf_triangle, prim_lanes, shear_lanes};
use super::trace::{PacketHits, blocking_lanes, box_lanes, descend};
use crate::buffers::{INSTANCE_IDENTITY, PRIM_NONE, TRIANGLE_WATERTIGHT};
use crate::cpu::common::{BVH_STACK, Globals, Hit, Ray};
use crate::cpu::instance::{InstanceX, instance_at, nearer_in, ray_into};
use crate::cpu::trace::tie_bound;

/// The lanes' rays in instance `x`'s object space: `ray_into` of each lane's ray, as
/// lane arrays with their shears, and as rays (for the primitives tested a lane at a
/// time). `None` for the identity, whose object rays are the world rays themselves.
#[allow(clippy::type_complexity)]
#[inline(always)]
fn object_lanes<O: Origins>(
    g: &Globals<f32>,
    x: &InstanceX<f32>,
    rays: &[Ray<f32>; LANES],
    r: &Lanes<O>,
) -> Option<([Ray<f32>; LANES], Lanes<O>, ShearLanes)> {
    if (x.root & INSTANCE_IDENTITY) != 0 {
        return None;
    }
    let mut obj = *rays;
    let mut dir = [[0.0f32; LANES]; 3];
    for l in 0..LANES {
        obj[l] = ray_into(x, rays[l]);
        let d = obj[l].dir;
        [dir[0][l], dir[1][l], dir[2][l]] = [d.x, d.y, d.z];
    }
    let origin = r.origin.mapped(&x.o);
    let sh = shear_lanes(&dir, g.spec.triangle_algo == TRIANGLE_WATERTIGHT);
    Some((obj, Lanes::new(origin, &dir), sh))
}

/// Each lane's nearest hit so far in a two-level search, and its box-test bound.
struct Best {
    t: [f32; LANES],
    prim: [u32; LANES],
    u: [f32; LANES],
    v: [f32; LANES],
    inst: [u32; LANES],
    slots: [u32; LANES],
    bound: [f32; LANES],
}

/// The bottom-level step of `closest_hit_top` for the lanes in `mask`: instance `inst`'s
/// tree from its root `root` (whose box the top level has tested), the rays in its object
/// space.
#[allow(clippy::too_many_arguments)]
#[inline(always)]
fn closest_in_instance<B: Build, O: Origins>(
    b: B,
    g: &Globals<f32>,
    root: u32,
    inst: u32,
    rays: &[Ray<f32>; LANES],
    r: &Lanes<O>,
    sh: &ShearLanes,
    mask: Mask,
    t_min: f32,
    best: &mut Best,
) {
    let nodes = &g.buf.nodes;
    let mut stack = [(0u32, 0 as Mask); BVH_STACK];
    let mut sp = 0usize;
    let (mut at, mut mask) = (root, mask);
    for _step in 0..g.buf.params.n_nodes {
        let node = &nodes[at as usize];
        let count = node.count_axis >> 2;
        if count == 0 {
            let next = descend::<B, _>(
                b,
                g,
                at,
                node,
                r,
                t_min,
                &best.bound,
                mask,
                &mut stack,
                &mut sp,
            );
            if let Some(next) = next {
                (at, mask) = next;
                continue;
            }
        } else {
            for k in node.first..node.first + count {
                let id = g.buf.prim_ids[k as usize];
                let tri = leaf_triangle(g, id, k);
                let h = prim_lanes(g, |l| rays[l], r, sh, id, tri, mask, t_min, &best.bound);
                for l in 0..LANES {
                    let cur = Hit {
                        t: best.t[l],
                        prim: best.prim[l],
                        u: 0.0,
                        v: 0.0,
                        inst: best.inst[l],
                    };
                    let take = (mask >> l) & 1 != 0 && nearer_in(h.t[l], inst, id, &cur);
                    let new = Hit {
                        t: h.t[l],
                        prim: id,
                        u: 0.0,
                        v: 0.0,
                        inst,
                    };
                    let tb = tie_bound(&new);
                    best.t[l] = if take { h.t[l] } else { best.t[l] };
                    best.prim[l] = if take { id } else { best.prim[l] };
                    best.u[l] = if take { h.u[l] } else { best.u[l] };
                    best.v[l] = if take { h.v[l] } else { best.v[l] };
                    best.inst[l] = if take { inst } else { best.inst[l] };
                    best.slots[l] = if take { k } else { best.slots[l] };
                    best.bound[l] = if take { tb } else { best.bound[l] };
                }
            }
        }
        if sp == 0 {
            break;
        }
        sp -= 1;
        (at, mask) = stack[sp];
    }
}

/// `closest_hit_top` for the rays `rays` (in `r`, world shears `sh`) whose bit is set in
/// `active`, `out` holding t_max and no hit in every lane: each lane's hit as the mirror's
/// two-level search gives it.
#[allow(clippy::too_many_arguments)]
#[inline(always)]
pub(super) fn closest_hit_top_lanes<B: Build, O: Origins>(
    b: B,
    g: &Globals<f32>,
    rays: &[Ray<f32>; LANES],
    r: &Lanes<O>,
    sh: &ShearLanes,
    active: Mask,
    t_min: f32,
    mut out: PacketHits<B::Inst>,
) -> PacketHits<B::Inst> {
    let nodes = &g.buf.nodes;
    if g.buf.params.n_nodes == 0 {
        return out;
    }
    let t_max = out.t[0];
    let mut best = Best {
        t: [t_max; LANES],
        prim: [PRIM_NONE; LANES],
        u: [0.0; LANES],
        v: [0.0; LANES],
        inst: [0; LANES],
        slots: out.slots,
        bound: [t_max; LANES],
    };
    let mut near = [0.0f32; LANES];
    let mut mask = box_lanes::<B, _>(b, &nodes[0], r, t_min, &best.bound, &mut near) & active;
    if mask == 0 {
        return out;
    }
    let mut stack = [(0u32, 0 as Mask); BVH_STACK];
    let mut sp = 0usize;
    let mut at = 0u32;
    for _step in 0..g.buf.params.n_nodes {
        let node = &nodes[at as usize];
        if node.count_axis >> 2 == 0 {
            let next = descend::<B, _>(
                b,
                g,
                at,
                node,
                r,
                t_min,
                &best.bound,
                mask,
                &mut stack,
                &mut sp,
            );
            if let Some(next) = next {
                (at, mask) = next;
                continue;
            }
        } else {
            // A top-level leaf holds one instance.
            let inst = node.first;
            let x = instance_at(g, inst);
            let root = x.root & !INSTANCE_IDENTITY;
            match object_lanes(g, &x, rays, r) {
                None => closest_in_instance::<B, O>(
                    b, g, root, inst, rays, r, sh, mask, t_min, &mut best,
                ),
                Some((obj, lanes, osh)) => closest_in_instance::<B, O>(
                    b, g, root, inst, &obj, &lanes, &osh, mask, t_min, &mut best,
                ),
            }
        }
        if sp == 0 {
            break;
        }
        sp -= 1;
        (at, mask) = stack[sp];
    }
    (out.t, out.prim, out.u, out.v, out.slots) = (best.t, best.prim, best.u, best.v, best.slots);
    for l in 0..LANES {
        out.inst.set(l, best.inst[l]);
    }
    out
}

/// The bottom-level step of `occluded_top` for the lanes in `lanes`: instance `inst`'s
/// tree from `root`, the rays in its object space; the lanes it blocks. `skip` is each
/// lane's primitive to pass over in this instance (`PRIM_NONE`: none).
#[allow(clippy::too_many_arguments)]
#[inline(always)]
fn occluded_in_instance<B: Build>(
    b: B,
    g: &Globals<f32>,
    root: u32,
    r: &Lanes<PerLane>,
    sh: &ShearLanes,
    skip: &[u32; LANES],
    lanes: Mask,
    t_min: f32,
    bound: &[f32; LANES],
) -> Mask {
    let nodes = &g.buf.nodes;
    let mut blocked: Mask = 0;
    let mut stack = [(0u32, 0 as Mask); BVH_STACK];
    let mut sp = 0usize;
    let (mut at, mut live) = (root, lanes);
    for _step in 0..g.buf.params.n_nodes {
        live &= !blocked;
        if live != 0 {
            let node = &nodes[at as usize];
            let count = node.count_axis >> 2;
            if count == 0 {
                let next =
                    descend::<B, _>(b, g, at, node, r, t_min, bound, live, &mut stack, &mut sp);
                if let Some(next) = next {
                    (at, live) = next;
                    continue;
                }
            } else {
                for k in node.first..node.first + count {
                    let id = g.buf.prim_ids[k as usize];
                    let tri = leaf_triangle(g, id, k);
                    let m = live & !blocked;
                    blocked |= blocking_lanes(g, r, sh, skip, id, tri, m, t_min, bound);
                    if live & !blocked == 0 {
                        break;
                    }
                }
            }
        }
        if sp == 0 || lanes & !blocked == 0 {
            break;
        }
        sp -= 1;
        (at, live) = stack[sp];
    }
    blocked
}

/// `occluded_top(ray, 0, 1, skip, skip_inst)` for each lane in `mask`, the rays given by
/// their origins `o` and directions `d`: the lanes whose ray is blocked.
#[inline(always)]
pub(super) fn occluded_top_lanes<B: Build>(
    b: B,
    g: &Globals<f32>,
    o: [[f32; LANES]; 3],
    d: &[[f32; LANES]; 3],
    skip: &[u32; LANES],
    skip_inst: &[u32; LANES],
    mask: Mask,
) -> Mask {
    let (t_min, t_max) = (0.0f32, crate::cpu::trace::finite_bound(1.0f32));
    let nodes = &g.buf.nodes;
    if g.buf.params.n_nodes == 0 {
        return 0;
    }
    let sh = shear_lanes(d, g.spec.triangle_algo == TRIANGLE_WATERTIGHT);
    let r = Lanes::new(PerLane(o), d);
    let mut rays = [Ray {
        origin: crate::shared::real::V3::splat(0.0f32),
        dir: crate::shared::real::V3::splat(0.0f32),
    }; LANES];
    for l in 0..LANES {
        rays[l].origin = r.origin.at(l).into();
        rays[l].dir = [d[0][l], d[1][l], d[2][l]].into();
    }
    let bound = [t_max; LANES];
    let mut near = [0.0f32; LANES];
    let mut lanes = box_lanes::<B, _>(b, &nodes[0], &r, t_min, &bound, &mut near) & mask;
    let mut blocked: Mask = 0;
    let mut stack = [(0u32, 0 as Mask); BVH_STACK];
    let mut sp = 0usize;
    let mut at = 0u32;
    for _step in 0..g.buf.params.n_nodes {
        lanes &= !blocked;
        if lanes != 0 {
            let node = &nodes[at as usize];
            if node.count_axis >> 2 == 0 {
                let next = descend::<B, _>(
                    b, g, at, node, &r, t_min, &bound, lanes, &mut stack, &mut sp,
                );
                if let Some(next) = next {
                    (at, lanes) = next;
                    continue;
                }
            } else {
                let inst = node.first;
                let x = instance_at(g, inst);
                let root = x.root & !INSTANCE_IDENTITY;
                // The hit primitive is passed over only in its own instance.
                let mut own = [PRIM_NONE; LANES];
                for l in 0..LANES {
                    own[l] = if skip_inst[l] == inst {
                        skip[l]
                    } else {
                        PRIM_NONE
                    };
                }
                blocked |= match object_lanes(g, &x, &rays, &r) {
                    None => {
                        occluded_in_instance::<B>(b, g, root, &r, &sh, &own, lanes, t_min, &bound)
                    }
                    Some((_, lanes_o, osh)) => occluded_in_instance::<B>(
                        b, g, root, &lanes_o, &osh, &own, lanes, t_min, &bound,
                    ),
                };
            }
        }
        if sp == 0 || mask & !blocked == 0 {
            break;
        }
        sp -= 1;
        (at, lanes) = stack[sp];
    }
    blocked
}
