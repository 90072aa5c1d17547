//! The packet twins of `trace.rs`: camera rays, the box test, the nearest-hit and shadow
//! searches over every primitive or through the BVH, as lane loops (their shading is
//! `shade.rs`).

// Lane loops index several arrays in step, `for l in 0..LANES`, the form LLVM vectorises.
#![allow(clippy::needless_range_loop)]

use super::common::{
    Build, InstLanes, LANES, Lanes, Mask, Origins, PACKET_W, PerLane, Shared, choose, choose_bits,
    flush_nonneg, mask_of,
};
use super::instance::closest_hit_top_lanes;
use super::prims::{
    ShearLanes, hit_prim_lane, leaf_triangle, prim_lanes, shear_lanes, sphere_lanes, triangle_lanes,
};
use super::shade::{Facts, shade_lanes};
use crate::buffers::{
    BOX_SLACK, BvhNode, INFINITY, PRIM_NONE, TRIANGLE_BIT, TRIANGLE_WATERTIGHT, Triangle,
};
use crate::cpu::common::{BVH_STACK, Globals, Hit, Ray};
use crate::cpu::trace::{finite_bound, nearer, sample_offset, tie_bound};
use crate::shared::real::V3;

/// `box_interval` for every lane at once: the lanes whose ray meets `node`'s box in
/// (t_min, bound), and each lane's entry distance. The same operations as
/// `box_interval`, lane by lane.
///
/// Where every lane's direction runs the same way on each axis with finite, non-zero
/// reciprocals (`Lanes::neg`), the near and far planes are picked once for the packet
/// instead of by a compare and two selects a lane and axis. Same values: with such a
/// reciprocal, the product with the far plane is never below the product with the near
/// one, and where the two are equal they are the same bits (`box_picks_like_the_compare`).
/// `node`'s box must have lo <= hi on every axis, as every box the builder makes has.
#[inline(always)]
pub(super) fn box_lanes<B: Build, O: Origins>(
    b: B,
    node: &BvhNode,
    r: &Lanes<O>,
    t_min: f32,
    bound: &[f32; LANES],
    near_out: &mut [f32; LANES],
) -> Mask {
    let mut far_out = [0.0f32; LANES];
    if let Some(neg) = r.neg {
        // Written out, not `[0, 1, 2].map(..)`: LLVM kept that map's bookkeeping, a
        // seventh of the instructions of a frame.
        let pick = |a: &[f32; 3], b: &[f32; 3]| {
            [
                if neg[0] { b[0] } else { a[0] },
                if neg[1] { b[1] } else { a[1] },
                if neg[2] { b[2] } else { a[2] },
            ]
        };
        let (near_p, far_p) = (pick(&node.lo, &node.hi), pick(&node.hi, &node.lo));
        for l in 0..LANES {
            let n = r.origin.rel(&near_p, l);
            let f = r.origin.rel(&far_p, l);
            let near = [n[0] * r.ix[l], n[1] * r.iy[l], n[2] * r.iz[l]];
            let far = [f[0] * r.ix[l], f[1] * r.iy[l], f[2] * r.iz[l]];
            (near_out[l], far_out[l]) = clip_interval(near, far, t_min, bound[l]);
        }
        return b.le_mask(near_out, &far_out);
    }
    for l in 0..LANES {
        let lo = r.origin.rel(&node.lo, l);
        let hi = r.origin.rel(&node.hi, l);
        let lx = lo[0] * r.ix[l];
        let ly = lo[1] * r.iy[l];
        let lz = lo[2] * r.iz[l];
        let hx = hi[0] * r.ix[l];
        let hy = hi[1] * r.iy[l];
        let hz = hi[2] * r.iz[l];
        let (sx, sy, sz) = (hx < lx, hy < ly, hz < lz);
        let nx = if sx { hx } else { lx };
        let ny = if sy { hy } else { ly };
        let nz = if sz { hz } else { lz };
        let fx = if sx { lx } else { hx };
        let fy = if sy { ly } else { hy };
        let fz = if sz { lz } else { hz };
        (near_out[l], far_out[l]) = clip_interval([nx, ny, nz], [fx, fy, fz], t_min, bound[l]);
    }
    b.le_mask(near_out, &far_out)
}

/// The end of `box_interval` for one lane, from its slabs' near and far distances: (t_min,
/// bound) clipped to the slabs, the far end at the nearest far distance (NaNs passed
/// over) widened by `BOX_SLACK` of itself. Returns the interval (t0, t1); the box is hit
/// where t0 <= t1 (the caller's compare, all lanes at once). One widening, of the nearest
/// exit (`docs/bench/cpu-packets.md`).
#[inline(always)]
fn clip_interval(near: [f32; 3], far: [f32; 3], t_min: f32, bound: f32) -> (f32, f32) {
    let mut t0 = t_min;
    t0 = if near[0] > t0 { near[0] } else { t0 };
    t0 = if near[1] > t0 { near[1] } else { t0 };
    t0 = if near[2] > t0 { near[2] } else { t0 };
    let mut f = INFINITY;
    f = if far[0] < f { far[0] } else { f };
    f = if far[1] < f { far[1] } else { f };
    f = if far[2] < f { far[2] } else { f };
    // An exit at -∞ is raised to -INFINITY, a miss (see `box_interval`).
    let f = if -INFINITY > f { -INFINITY } else { f };
    let f = f + f.abs() * BOX_SLACK;
    let t1 = if f < bound { f } else { bound };
    (t0, t1)
}

/// Asks the cache for what a step at `node` will read next: its far child's box (the
/// near one sits right after it), or its first primitive's triangle. Only a hint: no
/// value depends on it.
#[inline(always)]
pub(super) fn prefetch_children(g: &Globals<f32>, node: &BvhNode) {
    #[cfg(not(target_arch = "x86_64"))]
    let _ = (g, node);
    #[cfg(target_arch = "x86_64")]
    {
        use std::arch::x86_64::{_MM_HINT_T0, _mm_prefetch};
        let count = node.count_axis >> 2;
        if count == 0 {
            let p = g.buf.nodes.as_ptr().wrapping_add(node.first as usize) as *const i8;
            // SAFETY: a prefetch reads nothing and cannot fault, whatever the address.
            unsafe { _mm_prefetch::<_MM_HINT_T0>(p) };
            return;
        }
        // A leaf's triangles are consecutive in `leaf_triangles`.
        let first = g
            .buf
            .leaf_triangles()
            .as_ptr()
            .wrapping_add(node.first as usize) as *const i8;
        for line in 0..(count as usize * size_of::<Triangle>()).div_ceil(64) {
            // SAFETY: as above.
            unsafe { _mm_prefetch::<_MM_HINT_T0>(first.wrapping_add(64 * line)) };
        }
    }
}

/// `closest_hit_all` for every lane in `mask`, into `best` (misses at t_max): spheres
/// then triangles in index order, each lane's t_max its own nearest t so far. `best`'s
/// lanes outside `mask` are left as they are.
#[inline(always)]
pub(super) fn closest_hit_all_lanes<O: Origins>(
    g: &Globals<f32>,
    rays: &[Ray<f32>; LANES],
    r: &Lanes<O>,
    sh: &ShearLanes,
    mask: Mask,
    t_min: f32,
    best: &mut PacketHits<impl InstLanes>,
) {
    if g.spec.has_spheres {
        // Each lane's nearest t and sphere so far (misses keep t_max).
        let mut bt = best.t;
        let mut bp = [PRIM_NONE; LANES];
        for k in 0..g.buf.params.n_spheres {
            // Culled: a sphere that every lane passes well clear of is not tested.
            let t = sphere_lanes(&g.buf.spheres[k as usize], r, mask, true, t_min, &bt);
            for l in 0..LANES {
                let nearer = t[l] < bt[l];
                bt[l] = if nearer { t[l] } else { bt[l] };
                bp[l] = if nearer { k } else { bp[l] };
            }
        }
        // Merged with `choose` (a plain select here was a branch and four scalar stores a
        // lane).
        let mut found = [false; LANES];
        for l in 0..LANES {
            found[l] = bp[l] != PRIM_NONE;
        }
        let take = mask_of(&found) & mask;
        for l in 0..LANES {
            best.t[l] = choose(take, l, bt[l], best.t[l]);
            best.prim[l] = choose_bits(take, l, bp[l], best.prim[l]);
            best.u[l] = choose(take, l, 0.0, best.u[l]);
            best.v[l] = choose(take, l, 0.0, best.v[l]);
        }
    }
    if g.spec.has_triangles {
        // As for spheres: each lane's nearest (t, prim, u, v) so far.
        let (mut bt, mut bp, mut bu, mut bv) = (best.t, best.prim, best.u, best.v);
        for k in 0..g.buf.params.n_triangles {
            let tri = &g.buf.triangles[k as usize];
            let id = k | TRIANGLE_BIT;
            let h = prim_lanes(g, |l| rays[l], r, sh, id, Some(tri), mask, t_min, &bt);
            for l in 0..LANES {
                let nearer = h.t[l] < bt[l];
                bt[l] = if nearer { h.t[l] } else { bt[l] };
                bp[l] = if nearer { id } else { bp[l] };
                bu[l] = if nearer { h.u[l] } else { bu[l] };
                bv[l] = if nearer { h.v[l] } else { bv[l] };
            }
        }
        for l in 0..LANES {
            best.t[l] = choose(mask, l, bt[l], best.t[l]);
            best.prim[l] = choose_bits(mask, l, bp[l], best.prim[l]);
            best.u[l] = choose(mask, l, bu[l], best.u[l]);
            best.v[l] = choose(mask, l, bv[l], best.v[l]);
        }
    }
}

/// Where a lane's hit triangle is when it was found in a BVH leaf: its index in
/// `leaf_triangles`, else this.
pub const NO_SLOT: u32 = u32::MAX;

/// What `closest_hit_packet` finds: each lane's hit, as `closest_hit` gives it, as
/// structure of arrays (the shading's lane loops read them in step; as an array of
/// `Hit`s they were written and read back a lane at a time).
pub(super) struct PacketHits<I> {
    /// Each lane's `Hit::t`.
    pub t: [f32; LANES],
    /// Each lane's `Hit::prim`.
    pub prim: [u32; LANES],
    /// Each lane's `Hit::u`.
    pub u: [f32; LANES],
    /// Each lane's `Hit::v`.
    pub v: [f32; LANES],
    /// Each lane's `Hit::inst`: `()` where the scene has no instances (instance 0).
    pub inst: I,
    /// Each lane's hit triangle's index in `leaf_triangles` (the same triangle as
    /// `triangles[hit.prim]`, in memory the traversal has just read), or `NO_SLOT`.
    pub slots: [u32; LANES],
}

impl<I: InstLanes> PacketHits<I> {
    /// Lane l's hit.
    #[inline(always)]
    pub fn hit(&self, l: usize) -> Hit<f32> {
        Hit {
            t: self.t[l],
            prim: self.prim[l],
            u: self.u[l],
            v: self.v[l],
            inst: self.inst.lane(l),
        }
    }
}

/// A packet's step at interior node `node` (index `at`) for the lanes in `lanes`: both
/// children's boxes tested per lane against `bound`; where some lanes enter both, the
/// nearer along the split axis comes next and the other is pushed with its lanes.
/// Returns the child to visit next with its lanes, or `None` when no lane enters either.
#[allow(clippy::too_many_arguments)]
#[inline(always)]
pub(super) fn descend<B: Build, O: Origins>(
    b: B,
    g: &Globals<f32>,
    at: u32,
    node: &BvhNode,
    r: &Lanes<O>,
    t_min: f32,
    bound: &[f32; LANES],
    lanes: Mask,
    stack: &mut [(u32, Mask); BVH_STACK],
    sp: &mut usize,
) -> Option<(u32, Mask)> {
    let nodes = &g.buf.nodes;
    let (left, right) = (&nodes[at as usize + 1], &nodes[node.first as usize]);
    // The entry distances are not needed here (the order comes from the split axis).
    let mut near = [0.0f32; LANES];
    let ml = box_lanes::<B, O>(b, left, r, t_min, bound, &mut near) & lanes;
    let mr = box_lanes::<B, O>(b, right, r, t_min, bound, &mut near) & lanes;
    if ml != 0 && mr != 0 {
        // The nearer child by the split axis and the direction of the first lane that
        // enters either: the left child holds the lower centres on that axis, so a ray
        // running down it meets the right child first (not a vote of the lanes by their
        // entry distances: docs/bench/cpu-packets.md). The order changes no lane's answer
        // wherever every primitive's computed hit lies in its box's computed interval;
        // where one does not (the naive test far from the origin), the order decides
        // which hit the bound culls. The shader's query rays met that (4 of 100000, with
        // lane 0's order; its nearest-hit packet votes again); camera packets here have
        // not (`far_vertex_grids_equal_the_mirror`, eyes up to 1e6 away): evidence, not
        // proof.
        let axis = ((node.count_axis & 3) as usize).min(2);
        let lead = (ml | mr).trailing_zeros() as usize;
        let (near, far) = if r.dir[axis][lead] < 0.0 {
            ((node.first, mr), (at + 1, ml))
        } else {
            ((at + 1, ml), (node.first, mr))
        };
        prefetch_children(g, left);
        prefetch_children(g, right);
        stack[*sp] = far;
        *sp += 1;
        return Some(near);
    }
    if ml != 0 {
        prefetch_children(g, left);
        return Some((at + 1, ml));
    }
    if mr != 0 {
        prefetch_children(g, right);
        return Some((node.first, mr));
    }
    None
}

/// The lanes of `m` whose shadow ray (in `r`, shears `sh`) primitive `id` blocks: a hit in
/// (t_min, `bound`) when `id` is not the lane's `skip`; `tri` is its triangle when it is
/// one. Written out rather than through `prim_lanes` (that shared helper, inlined here,
/// made shadow rays 1.8–2.2× slower on the peers 2-triangle scene), and a function
/// forced inline rather than a closure: the closure it was had one body, compiled for the
/// baseline instruction set (SSE2) and called from every build, 15 % of a shadowed
/// 1M-triangle frame.
#[allow(clippy::too_many_arguments)]
#[inline(always)]
pub(super) fn blocking_lanes(
    g: &Globals<f32>,
    r: &Lanes<PerLane>,
    sh: &ShearLanes,
    skip: &[u32; LANES],
    id: u32,
    tri: Option<&Triangle>,
    m: Mask,
    t_min: f32,
    bound: &[f32; LANES],
) -> Mask {
    let t_max = bound[0];
    let mut out: Mask = 0;
    if let Some(tri) = tri
        && g.spec.has_triangles
    {
        let h = triangle_lanes(g, tri, r, sh, m, t_min, bound);
        for l in 0..LANES {
            out |= (((m >> l) & 1 != 0 && id != skip[l] && h.t[l] < t_max) as Mask) << l;
        }
        return out;
    }
    if (id & TRIANGLE_BIT) == 0 {
        if g.spec.has_spheres {
            let t = sphere_lanes(&g.buf.spheres[id as usize], r, m, true, t_min, bound);
            for l in 0..LANES {
                out |= (((m >> l) & 1 != 0 && id != skip[l] && t[l] < t_max) as Mask) << l;
            }
        }
        return out;
    }
    let mut left = m;
    while left != 0 {
        let l = left.trailing_zeros() as usize;
        left &= left - 1;
        let ray = Ray {
            origin: V3::new(r.origin.0[0][l], r.origin.0[1][l], r.origin.0[2][l]),
            dir: V3::new(r.dir[0][l], r.dir[1][l], r.dir[2][l]),
        };
        if id != skip[l] && hit_prim_lane(g, ray, sh.lane(l), id, t_min, t_max).0 < t_max {
            out |= 1 << l;
        }
    }
    out
}

/// `occluded(ray, 0, 1, skip)` for each lane in `mask`, the rays given by their origins
/// `o` and directions `d` (structure of arrays): the lanes whose ray is blocked. Through
/// the BVH each lane reaches exactly the leaves its own `occluded_bvh` would (its box
/// tests are `box_interval`'s operations, against a t_max that never shrinks), so the
/// answer is the same, whatever order the packet takes.
#[inline(always)]
pub(super) fn occluded_lanes<B: Build>(
    b: B,
    g: &Globals<f32>,
    o: [[f32; LANES]; 3],
    d: &[[f32; LANES]; 3],
    skip: &[u32; LANES],
    mask: Mask,
) -> Mask {
    let (t_min, t_max) = (0.0f32, finite_bound(1.0f32));
    let sh = shear_lanes(d, g.spec.triangle_algo == TRIANGLE_WATERTIGHT);
    let r = Lanes::new(PerLane(o), d);
    let bound = [t_max; LANES];
    let mut blocked: Mask = 0;
    if !g.spec.use_bvh {
        // `occluded_all`: spheres, then triangles, each lane until it is blocked.
        let mut open = mask;
        if g.spec.has_spheres {
            // Spheres written out (not through `blocking_lanes`), with their own early
            // exit: this loop is most of a scene of spheres' shadow rays.
            for k in 0..g.buf.params.n_spheres {
                if open == 0 {
                    break;
                }
                let t = sphere_lanes(&g.buf.spheres[k as usize], &r, open, true, t_min, &bound);
                let mut hit = [false; LANES];
                for l in 0..LANES {
                    hit[l] = k != skip[l] && t[l] < t_max;
                }
                open &= !mask_of(&hit);
            }
        }
        if g.spec.has_triangles {
            for k in 0..g.buf.params.n_triangles {
                if open == 0 {
                    break;
                }
                let tri = Some(&g.buf.triangles[k as usize]);
                open &=
                    !blocking_lanes(g, &r, &sh, skip, k | TRIANGLE_BIT, tri, open, t_min, &bound);
            }
        }
        return mask & !open;
    }
    let nodes = &g.buf.nodes;
    if g.buf.params.n_nodes == 0 {
        return 0;
    }
    let mut near = [0.0f32; LANES];
    let mut lanes = box_lanes::<B, _>(b, &nodes[0], &r, t_min, &bound, &mut near) & mask;
    let mut stack = [(0u32, 0 as Mask); BVH_STACK];
    let mut sp = 0usize;
    let mut at = 0u32;
    for _step in 0..g.buf.params.n_nodes {
        lanes &= !blocked;
        if lanes != 0 {
            let node = &nodes[at as usize];
            let count = node.count_axis >> 2;
            if count == 0 {
                let next = descend::<B, _>(
                    b, g, at, node, &r, t_min, &bound, lanes, &mut stack, &mut sp,
                );
                if let Some(next) = next {
                    (at, lanes) = next;
                    continue;
                }
            } else {
                for k in node.first..node.first + count {
                    let id = g.buf.prim_ids[k as usize];
                    let tri = leaf_triangle(g, id, k);
                    let m = lanes & !blocked;
                    blocked |= blocking_lanes(g, &r, &sh, skip, id, tri, m, t_min, &bound);
                    if lanes & !blocked == 0 {
                        break;
                    }
                }
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

/// `closest_hit` for the rays of `rays` whose bit is set in `active` (the others are
/// returned as misses): the same hit for each ray as `closest_hit` gives it, through the
/// BVH (`closest_hit_bvh`) or testing every primitive (`closest_hit_all`) as the
/// specialisation says.
/// Every ray must have `rays[0].origin` as its origin (camera rays do), and `t_max` must
/// be finite (`finite_bound`), as `closest_hit` passes it.
#[inline(always)]
pub(super) fn closest_hit_packet<B: Build>(
    b: B,
    g: &Globals<f32>,
    rays: &[Ray<f32>; LANES],
    dir: &[[f32; LANES]; 3],
    active: Mask,
    t_min: f32,
    t_max: f32,
) -> PacketHits<B::Inst> {
    let out = PacketHits {
        t: [t_max; LANES],
        prim: [PRIM_NONE; LANES],
        u: [0.0; LANES],
        v: [0.0; LANES],
        inst: B::Inst::default(),
        slots: [NO_SLOT; LANES],
    };
    if active == 0 {
        return out;
    }
    let r = Lanes::new(Shared(rays[0].origin), dir);
    let sh = shear_lanes(dir, g.spec.triangle_algo == TRIANGLE_WATERTIGHT);
    closest_hit_lanes::<B, _>(b, g, rays, &r, &sh, active, t_min, out)
}

/// [`closest_hit_packet`] for rays `r` from any origins (`rays` the same rays lane by
/// lane), `out` holding t_max and no hit in every lane.
#[allow(clippy::too_many_arguments)]
#[inline(always)]
pub(super) fn closest_hit_lanes<B: Build, O: Origins>(
    b: B,
    g: &Globals<f32>,
    rays: &[Ray<f32>; LANES],
    r: &Lanes<O>,
    sh: &ShearLanes,
    active: Mask,
    t_min: f32,
    mut out: PacketHits<B::Inst>,
) -> PacketHits<B::Inst> {
    if B::INSTANCES {
        return closest_hit_top_lanes::<B, O>(b, g, rays, r, sh, active, t_min, out);
    }
    let t_max = out.t[0];
    if !g.spec.use_bvh {
        closest_hit_all_lanes(g, rays, r, sh, active, t_min, &mut out);
        return out;
    }
    let slots = &mut out.slots;
    let nodes = &g.buf.nodes;
    if g.buf.params.n_nodes == 0 {
        return out;
    }
    let mut near = [0.0f32; LANES];
    let mut bound = [t_max; LANES];
    let mut mask = box_lanes::<B, _>(b, &nodes[0], r, t_min, &bound, &mut near) & active;
    if mask == 0 {
        return out;
    }
    // Each lane's nearest hit so far, as lane arrays (written to `best` at the end).
    let mut bt = [t_max; LANES];
    let mut bp = [PRIM_NONE; LANES];
    let mut bu = [0.0f32; LANES];
    let mut bv = [0.0f32; LANES];
    let mut stack = [(0u32, 0 as Mask); BVH_STACK];
    let mut sp = 0usize;
    let mut at = 0u32;
    for _step in 0..g.buf.params.n_nodes {
        let node = &nodes[at as usize];
        let count = node.count_axis >> 2;
        if count == 0 {
            let next = descend::<B, _>(b, g, at, node, r, t_min, &bound, mask, &mut stack, &mut sp);
            if let Some(next) = next {
                (at, mask) = next;
                continue;
            }
        } else {
            for k in node.first..node.first + count {
                let id = g.buf.prim_ids[k as usize];
                let tri = leaf_triangle(g, id, k);
                let h = prim_lanes(g, |l| rays[l], r, sh, id, tri, mask, t_min, &bound);
                // The merge as selects over lane arrays, every lane at once (a loop over
                // the live lanes, through `best[l]`, was scalar code at every leaf).
                for l in 0..LANES {
                    let cur = Hit {
                        t: bt[l],
                        prim: bp[l],
                        u: 0.0,
                        v: 0.0,
                        inst: 0,
                    };
                    let take = (mask >> l) & 1 != 0 && nearer(h.t[l], id, &cur);
                    let new = Hit {
                        t: h.t[l],
                        prim: id,
                        u: 0.0,
                        v: 0.0,
                        inst: 0,
                    };
                    let b = tie_bound(&new);
                    bt[l] = if take { h.t[l] } else { bt[l] };
                    bp[l] = if take { id } else { bp[l] };
                    bu[l] = if take { h.u[l] } else { bu[l] };
                    bv[l] = if take { h.v[l] } else { bv[l] };
                    bound[l] = if take { b } else { bound[l] };
                    slots[l] = if take { k } else { slots[l] };
                }
            }
        }
        if sp == 0 {
            break;
        }
        sp -= 1;
        (at, mask) = stack[sp];
    }
    (out.t, out.prim, out.u, out.v) = (bt, bp, bu, bv);
    out
}

/// `camera_ray` through the point (dx, dy) of each pixel of the block at (i, j), lane by
/// lane with the same operations in the same order, written as lane loops so that they
/// vectorise; the same directions as lane arrays; and the lanes whose pixel lies inside
/// the image.
#[inline(always)]
pub fn camera_rays(
    g: &Globals<f32>,
    i: u32,
    j: u32,
    dx: f32,
    dy: f32,
) -> ([Ray<f32>; LANES], [[f32; LANES]; 3], Mask) {
    let c = &g.cam;
    let two = 1.0f32 + 1.0;
    // The block's columns and rows inside the image, as a mask (lane dy * PACKET_W + dx).
    let cols = c.width.saturating_sub(i).min(PACKET_W);
    let rows = c.height.saturating_sub(j).min(LANES as u32 / PACKET_W);
    let row: Mask = ((1u32 << cols) - 1) as Mask;
    let mut active: Mask = 0;
    for y in 0..rows {
        active |= row << (y * PACKET_W);
    }
    let mut d = [[0.0f32; LANES]; 3];
    for l in 0..LANES {
        let fi = (i + l as u32 % PACKET_W) as f32;
        let fj = (j + l as u32 / PACKET_W) as f32;
        let x = ((fi + dx) / c.width as f32 * two - 1.0) * c.tan_half * c.aspect;
        let y = (1.0 - (fj + dy) / c.height as f32 * two) * c.tan_half;
        d[0][l] = c.forward.x + c.right.x * x + c.up.x * y;
        d[1][l] = c.forward.y + c.right.y * x + c.up.y * y;
        d[2][l] = c.forward.z + c.right.z * x + c.up.z * y;
    }
    let mut n = [[0.0f32; LANES]; 3];
    for l in 0..LANES {
        let len = (d[0][l] * d[0][l] + d[1][l] * d[1][l] + d[2][l] * d[2][l]).sqrt();
        n[0][l] = d[0][l] / len;
        n[1][l] = d[1][l] / len;
        n[2][l] = d[2][l] / len;
    }
    let mut rays = [Ray {
        origin: c.eye,
        dir: V3::new(0.0, 0.0, 0.0),
    }; LANES];
    for l in 0..LANES {
        rays[l].dir = V3::new(n[0][l], n[1][l], n[2][l]);
    }
    (rays, n, active)
}

/// `trace_pixel` for the block: one packet per sample position, each packet the block's
/// pixels at the same point of their pixel (as coherent as the block itself), the lanes
/// summing their samples in `trace_pixel`'s order.
#[inline(always)]
pub(super) fn trace_packet_body<B: Build>(
    b: B,
    g: &Globals<f32>,
    i: u32,
    j: u32,
) -> [[f32; 4]; LANES] {
    let half = 1.0f32 / (1.0 + 1.0);
    if !g.spec.antialias {
        return sample_packet::<B>(b, g, i, j, half, half);
    }
    let n = g.cam.samples;
    let mut sum = [[0.0f32; 3]; LANES];
    let mut t_near = [-1.0f32; LANES];
    for sy in 0..n {
        let dy = sample_offset::<f32>(sy, n);
        for sx in 0..n {
            let dx = sample_offset::<f32>(sx, n);
            let s = sample_packet::<B>(b, g, i, j, dx, dy);
            for l in 0..LANES {
                for c in 0..3 {
                    sum[l][c] += s[l][c];
                }
                if s[l][3] >= 0.0 && (t_near[l] < 0.0 || s[l][3] < t_near[l]) {
                    t_near[l] = s[l][3];
                }
            }
        }
    }
    let nn = (n * n) as f32;
    let mut out = [[0.0f32; 4]; LANES];
    for l in 0..LANES {
        out[l] = [
            flush_nonneg(sum[l][0] / nn),
            flush_nonneg(sum[l][1] / nn),
            flush_nonneg(sum[l][2] / nn),
            t_near[l],
        ];
    }
    out
}

/// `trace_sample` at the point (dx, dy) of each pixel of the block.
#[inline(always)]
pub(super) fn sample_packet<B: Build>(
    b: B,
    g: &Globals<f32>,
    i: u32,
    j: u32,
    dx: f32,
    dy: f32,
) -> [[f32; 4]; LANES] {
    sample_packet_hits::<B, _>(b, g, i, j, dx, dy, &mut ()).0
}

/// [`sample_packet`], with the camera rays, their hits and the lanes inside the image, for
/// a caller that describes the hits further (the AOVs of the same rays), with what the
/// shading found of the hits in `facts` (`shade_lanes`).
#[allow(clippy::type_complexity)]
#[inline(always)]
pub(super) fn sample_packet_hits<B: Build, F: Facts>(
    b: B,
    g: &Globals<f32>,
    i: u32,
    j: u32,
    dx: f32,
    dy: f32,
    facts: &mut F,
) -> (
    [[f32; 4]; LANES],
    [Ray<f32>; LANES],
    PacketHits<B::Inst>,
    Mask,
) {
    let (rays, dir, active) = camera_rays(g, i, j, dx, dy);
    let found = closest_hit_packet::<B>(b, g, &rays, &dir, active, 0.0, f32::MAX);
    let mut hit = [false; LANES];
    for l in 0..LANES {
        hit[l] = found.prim[l] != PRIM_NONE;
    }
    let lit = mask_of(&hit);
    let colors =
        shade_lanes::<B, _, _>(b, g, &Shared(g.cam.eye), &dir, &found, lit & active, facts);
    // Loops, not `array::from_fn`: that is a generic function of its own, compiled once
    // for the baseline instruction set and called from every build.
    let bg = g.buf.params.background;
    let mut out = [[bg[0], bg[1], bg[2], -1.0]; LANES];
    for l in 0..LANES {
        if found.prim[l] != PRIM_NONE {
            out[l] = [colors[0][l], colors[1][l], colors[2][l], found.t[l]];
        }
    }
    if g.spec.whitted {
        super::whitted::secondary_lanes::<B>(b, g, &rays, &found, lit & active, &mut out);
    }
    (out, rays, found, active)
}

#[cfg(test)]
mod tests {
    use super::super::common::Portable;
    use super::super::prims::tests::Rng;
    use super::*;

    /// `box_lanes` on a uniform-sign packet, then on the same packet sent down the compare.
    fn check<O: Origins>(
        case: usize,
        node: &BvhNode,
        t_min: f32,
        bound: &[f32; LANES],
        mut r: Lanes<O>,
    ) {
        assert!(r.neg.is_some(), "case {case}: a uniform-sign packet");
        let (mut a, mut b) = ([0.0f32; LANES], [0.0f32; LANES]);
        let ma = box_lanes::<Portable, O>(Portable, node, &r, t_min, bound, &mut a);
        r.neg = None;
        let mb = box_lanes::<Portable, O>(Portable, node, &r, t_min, bound, &mut b);
        assert_eq!(ma, mb, "case {case}: mask");
        assert_eq!(
            a.map(f32::to_bits),
            b.map(f32::to_bits),
            "case {case}: entry"
        );
    }

    /// The packet-wide plane pick gives the per-lane compare's mask and entry distances in
    /// every bit: uniform-sign packets against random boxes, flat boxes, boxes with a face
    /// through the origin and boxes around it, shared and per-lane origins.
    #[test]
    fn box_picks_like_the_compare() {
        let mut rng = Rng(0x0b0c_5eed);
        for case in 0..20_000 {
            let sign = [0, 1, 2].map(|k| if (case >> k) & 1 == 1 { -1.0f32 } else { 1.0 });
            let scale = [1e-3f32, 1.0, 1e3][case % 3];
            let mut dir = [[0.0f32; LANES]; 3];
            let mut org = [[0.0f32; LANES]; 3];
            for l in 0..LANES {
                for k in 0..3 {
                    dir[k][l] = sign[k] * rng.range(1e-3, 1.0);
                    org[k][l] = rng.range(-1.0, 1.0) * scale;
                }
            }
            let o0 = [org[0][0], org[1][0], org[2][0]];
            let mut lo = [0, 1, 2].map(|_| rng.range(-2.0, 2.0) * scale);
            let mut hi = [0, 1, 2].map(|k| lo[k] + rng.range(0.0, 2.0) * scale);
            match case % 5 {
                0 => hi[case % 3] = lo[case % 3], // flat
                1 => lo[case % 3] = o0[case % 3], // a face through lane 0's origin
                2 => hi[case % 3] = o0[case % 3],
                3 => (lo, hi) = (o0.map(|v| v - scale), o0.map(|v| v + scale)), // around it
                _ => {}
            }
            for k in 0..3 {
                // A node's box has lo <= hi on every axis (the builder's do).
                (lo[k], hi[k]) = (lo[k].min(hi[k]), lo[k].max(hi[k]));
            }
            let node = BvhNode {
                lo,
                first: 0,
                hi,
                count_axis: 0,
            };
            let bound = [0; LANES].map(|_| rng.range(0.0, 4.0) * scale);
            let t_min = if case % 2 == 0 { 0.0 } else { 1e-4 * scale };
            let shared = Lanes::new(Shared(V3::new(o0[0], o0[1], o0[2])), &dir);
            check(case, &node, t_min, &bound, shared);
            check(case, &node, t_min, &bound, Lanes::new(PerLane(org), &dir));
        }
        // A zero or mixed-sign component leaves the packet on the compare.
        let mut dir = [[0.5f32; LANES]; 3];
        dir[1][3] = 0.0;
        assert!(
            Lanes::new(Shared(V3::new(0.0, 0.0, 0.0)), &dir)
                .neg
                .is_none()
        );
        dir[1][3] = -0.5;
        assert!(
            Lanes::new(Shared(V3::new(0.0, 0.0, 0.0)), &dir)
                .neg
                .is_none()
        );
        dir[1][3] = f32::NAN;
        assert!(
            Lanes::new(Shared(V3::new(0.0, 0.0, 0.0)), &dir)
                .neg
                .is_none()
        );
    }
}
