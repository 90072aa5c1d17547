//! The CPU's fast path for camera rays: eight rays (a 4×2 block of pixels) are traced
//! together. Through the BVH each node is fetched once for the eight and its two child
//! boxes are tested against all eight at once; without it (small scenes) each primitive
//! is tested against the eight at once. The lane loops below are written for LLVM to
//! vectorise, and `trace_packet` is compiled a second time for AVX2.
//!
//! This is not a mirror of a WGSL function: it is the mirror's faster twin, and it gives
//! the same image bit for bit. Lane by lane it does the mirror's operations in the
//! mirror's order: `camera_ray`, `make_shear`, `box_interval`, the watertight test and
//! `shade` are written again as lane loops, op for op; everything else (the other
//! triangle tests, spheres, `pow`) calls the mirror's own functions one lane at a time.
//! Shadow rays go eight at a time as well, each lane from its own origin. Only the order
//! in which BVH leaves are reached differs, and `closest_hit_bvh`'s result does not
//! depend on that order: it is the hit with the smallest t and, of equal t, the lowest
//! primitive id (what `closest_hit_all` keeps), because every box test is conservative
//! for any bound past the nearest hit. `occluded_bvh`'s answer does not depend on it
//! either: each lane reaches exactly the leaves its own traversal would.
//! `tests/packets.rs` checks the two images against each other, bit for bit.

// Lane loops index several arrays in step, `for l in 0..LANES`, the form LLVM vectorises.
#![allow(clippy::needless_range_loop)]

use super::common::{BVH_STACK, Globals, Hit, Ray, clamp01, in_interval, max0};
use super::prims::{Shear, edge_function, hit_prim, hit_sphere, hit_triangle, shading_at};
use super::real::V3;
use super::trace::{finite_bound, nearer, phong_power, sample_offset, shadow_origin, tie_bound};
use crate::buffers::{
    BOX_SLACK, BvhNode, INFINITY, Light, MODEL_AMBIENT, MODEL_PHONG, Material, PRIM_NONE,
    TRIANGLE_BIT, TRIANGLE_WATERTIGHT, Triangle,
};

/// Rays per packet.
pub const LANES: usize = 8;
const _: () = assert!(LANES == 8, "mask_of gathers exactly eight flags");
/// Packet width in pixels (the packet is `PACKET_W` × `PACKET_H`).
pub const PACKET_W: u32 = 4;
/// Packet height in pixels.
pub const PACKET_H: u32 = 2;

/// A bit per lane.
pub type Mask = u8;

/// Where the lanes' rays start: `rel(p, l)` is `p - origin` of lane l, per component.
trait Origins {
    fn rel(&self, p: &[f32; 3], l: usize) -> [f32; 3];
}

/// One origin for every lane (camera rays): LLVM hoists `rel` out of the lane loops.
struct Shared(V3<f32>);

impl Origins for Shared {
    #[inline(always)]
    fn rel(&self, p: &[f32; 3], _l: usize) -> [f32; 3] {
        [p[0] - self.0.x, p[1] - self.0.y, p[2] - self.0.z]
    }
}

/// An origin per lane (shadow rays), as structure of arrays.
struct PerLane([[f32; LANES]; 3]);

impl Origins for PerLane {
    #[inline(always)]
    fn rel(&self, p: &[f32; 3], l: usize) -> [f32; 3] {
        [
            p[0] - self.0[0][l],
            p[1] - self.0[1][l],
            p[2] - self.0[2][l],
        ]
    }
}

/// Rays with their reciprocal directions as structure of arrays.
struct Lanes<O> {
    origin: O,
    ix: [f32; LANES],
    iy: [f32; LANES],
    iz: [f32; LANES],
}

impl<O> Lanes<O> {
    /// The rays from `origin` with directions `dir` (structure of arrays).
    #[inline(always)]
    fn new(origin: O, dir: &[[f32; LANES]; 3]) -> Self {
        let mut r = Lanes {
            origin,
            ix: [0.0; LANES],
            iy: [0.0; LANES],
            iz: [0.0; LANES],
        };
        for l in 0..LANES {
            r.ix[l] = 1.0 / dir[0][l];
            r.iy[l] = 1.0 / dir[1][l];
            r.iz[l] = 1.0 / dir[2][l];
        }
        r
    }
}

/// `box_interval` for every lane at once: the lanes whose ray meets `node`'s box in
/// (t_min, bound), and each lane's entry distance. The same operations as
/// `box_interval`, lane by lane.
#[inline(always)]
fn box_lanes<O: Origins>(
    node: &BvhNode,
    r: &Lanes<O>,
    t_min: f32,
    bound: &[f32; LANES],
    near_out: &mut [f32; LANES],
) -> Mask {
    let mut hit = [false; LANES];
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
        let mut fx = if sx { lx } else { hx };
        let mut fy = if sy { ly } else { hy };
        let mut fz = if sz { lz } else { hz };
        fx = fx + fx.abs() * BOX_SLACK;
        fy = fy + fy.abs() * BOX_SLACK;
        fz = fz + fz.abs() * BOX_SLACK;
        let mut t0 = t_min;
        let mut t1 = bound[l];
        t0 = if nx > t0 { nx } else { t0 };
        t0 = if ny > t0 { ny } else { t0 };
        t0 = if nz > t0 { nz } else { t0 };
        t1 = if fx < t1 { fx } else { t1 };
        t1 = if fy < t1 { fy } else { t1 };
        t1 = if fz < t1 { fz } else { t1 };
        near_out[l] = t0;
        hit[l] = t0 <= t1;
    }
    mask_of(&hit)
}

/// The bits of eight flags, lane l in bit l. Branch-free: the flags as bytes (0 or 1)
/// times 0x0102040810204080 puts byte l's bit in bit 56 + l, and no two partial products
/// share a bit, so nothing carries.
#[inline(always)]
fn mask_of(flags: &[bool; LANES]) -> Mask {
    let bytes: [u8; LANES] = flags.map(|f| f as u8);
    (u64::from_le_bytes(bytes).wrapping_mul(0x0102_0408_1020_4080) >> 56) as Mask
}

/// The lanes' `Shear`s as structure of arrays.
struct ShearLanes {
    kx: [u32; LANES],
    ky: [u32; LANES],
    kz: [u32; LANES],
    sx: [f32; LANES],
    sy: [f32; LANES],
    sz: [f32; LANES],
}

/// `ray_shear` of every lane: `make_shear` lane by lane when `watertight` (the same
/// comparisons, the same one division), else the identity `ray_shear` gives.
#[inline(always)]
fn shear_lanes(dir: &[[f32; LANES]; 3], watertight: bool) -> ShearLanes {
    let mut sh = ShearLanes {
        kx: [0; LANES],
        ky: [1; LANES],
        kz: [2; LANES],
        sx: [0.0; LANES],
        sy: [0.0; LANES],
        sz: [1.0; LANES],
    };
    if !watertight {
        return sh;
    }
    for l in 0..LANES {
        let d = [dir[0][l], dir[1][l], dir[2][l]];
        let ad = [d[0].abs(), d[1].abs(), d[2].abs()];
        let mut kz = if ad[1] > ad[0] { 1 } else { 0 };
        if ad[2] > pick(&ad, kz) {
            kz = 2;
        }
        let mut kx = (kz + 1) % 3;
        let mut ky = (kx + 1) % 3;
        if pick(&d, kz) < 0.0 {
            std::mem::swap(&mut kx, &mut ky);
        }
        let sz = 1.0 / pick(&d, kz);
        sh.kx[l] = kx;
        sh.ky[l] = ky;
        sh.kz[l] = kz;
        sh.sx[l] = pick(&d, kx) * sz;
        sh.sy[l] = pick(&d, ky) * sz;
        sh.sz[l] = sz;
    }
    sh
}

impl ShearLanes {
    /// Lane l's `Shear`.
    #[inline(always)]
    fn lane(&self, l: usize) -> Shear<f32> {
        Shear {
            kx: self.kx[l],
            ky: self.ky[l],
            kz: self.kz[l],
            sx: self.sx[l],
            sy: self.sy[l],
            sz: self.sz[l],
        }
    }
}

/// Each lane's (t, u, v), t = INFINITY on a miss.
struct TriLanes {
    t: [f32; LANES],
    u: [f32; LANES],
    v: [f32; LANES],
}

/// `V3::get`: component k of (x, y, z), as selects so that a lane loop vectorises.
#[inline(always)]
fn pick(v: &[f32; 3], k: u32) -> f32 {
    if k == 0 {
        v[0]
    } else if k == 1 {
        v[1]
    } else {
        v[2]
    }
}

/// The sheared vertices (ax, ay, bx, by, cx, cy) of `hit_triangle_watertight` for lane l,
/// from the vertices relative to the origin.
#[inline(always)]
fn sheared(a: &[f32; 3], b: &[f32; 3], c: &[f32; 3], sh: &ShearLanes, l: usize) -> [f32; 6] {
    let (kx, ky, kz) = (sh.kx[l], sh.ky[l], sh.kz[l]);
    [
        pick(a, kx) - sh.sx[l] * pick(a, kz),
        pick(a, ky) - sh.sy[l] * pick(a, kz),
        pick(b, kx) - sh.sx[l] * pick(b, kz),
        pick(b, ky) - sh.sy[l] * pick(b, kz),
        pick(c, kx) - sh.sx[l] * pick(c, kz),
        pick(c, ky) - sh.sy[l] * pick(c, kz),
    ]
}

/// `hit_triangle_watertight` of one triangle for every lane, with lane l's `t_max` =
/// `t_max[l]`: the same operations in the same order, lane by lane. An edge function
/// that comes out exactly 0 is recomputed by `edge_function` itself (its exact
/// fallback), so that every lane's (t, u, v) is the scalar test's, bit for bit.
#[inline(always)]
fn watertight_lanes<O: Origins>(
    tri: &Triangle,
    r: &Lanes<O>,
    sh: &ShearLanes,
    mask: Mask,
    t_min: f32,
    t_max: &[f32; LANES],
) -> TriLanes {
    let rel = |l: usize| {
        (
            r.origin.rel(&tri.a, l),
            r.origin.rel(&tri.b, l),
            r.origin.rel(&tri.c, l),
        )
    };
    let mut e = [[0.0f32; LANES]; 3];
    let mut zero_flags = [false; LANES];
    for l in 0..LANES {
        let (a, b, c) = rel(l);
        let [ax, ay, bx, by, cx, cy] = sheared(&a, &b, &c, sh, l);
        e[0][l] = cx * by - cy * bx;
        e[1][l] = ax * cy - ay * cx;
        e[2][l] = bx * ay - by * ax;
        zero_flags[l] = (e[0][l] == 0.0) | (e[1][l] == 0.0) | (e[2][l] == 0.0);
    }
    let zero = mask_of(&zero_flags);
    let mut fix = zero & mask;
    while fix != 0 {
        let l = fix.trailing_zeros() as usize;
        fix &= fix - 1;
        let (a, b, c) = rel(l);
        let [ax, ay, bx, by, cx, cy] = sheared(&a, &b, &c, sh, l);
        e[0][l] = edge_function(cx, by, cy, bx);
        e[1][l] = edge_function(ax, cy, ay, cx);
        e[2][l] = edge_function(bx, ay, by, ax);
    }
    let mut out = TriLanes {
        t: [INFINITY; LANES],
        u: [0.0; LANES],
        v: [0.0; LANES],
    };
    for l in 0..LANES {
        let (u, v, w) = (e[0][l], e[1][l], e[2][l]);
        let outside = (u < 0.0 || v < 0.0 || w < 0.0) && (u > 0.0 || v > 0.0 || w > 0.0);
        let det = u + v + w;
        #[allow(clippy::eq_op)]
        let degenerate = det == 0.0 || det != det;
        let kz = sh.kz[l];
        let (a, b, c) = rel(l);
        let az = sh.sz[l] * pick(&a, kz);
        let bz = sh.sz[l] * pick(&b, kz);
        let cz = sh.sz[l] * pick(&c, kz);
        let t_scaled = u * az + v * bz + w * cz;
        let inv_det = 1.0 / det;
        let t = t_scaled * inv_det;
        let hit = !outside && !degenerate && in_interval(t, t_min, t_max[l]);
        out.t[l] = if hit { t } else { INFINITY };
        out.u[l] = if hit { v * inv_det } else { 0.0 };
        out.v[l] = if hit { w * inv_det } else { 0.0 };
    }
    out
}

/// Asks the cache for what a step at `node` will read next: its far child's box (the
/// near one sits right after it), or its first primitive's triangle. Only a hint: no
/// value depends on it.
#[inline(always)]
fn prefetch_children(g: &Globals<f32>, node: &BvhNode) {
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
            .leaf_triangles
            .as_ptr()
            .wrapping_add(node.first as usize) as *const i8;
        for line in 0..(count as usize * size_of::<Triangle>()).div_ceil(64) {
            // SAFETY: as above.
            unsafe { _mm_prefetch::<_MM_HINT_T0>(first.wrapping_add(64 * line)) };
        }
    }
}

/// `hit_prim` of primitive `id` for the lanes in `mask`, lane l against `t_max[l]`; `tri`
/// is its triangle when it is one (`triangles[id]` or its copy in `leaf_triangles`). A
/// triangle goes through `watertight_lanes` under the watertight algorithm, else through
/// the mirror's `hit_triangle` lane by lane; a sphere through the mirror's `hit_prim`.
/// Only the lanes in `mask` are meaningful.
#[allow(clippy::too_many_arguments)]
#[inline(always)]
fn prim_lanes<O: Origins>(
    g: &Globals<f32>,
    ray: impl Fn(usize) -> Ray<f32>,
    r: &Lanes<O>,
    sh: &ShearLanes,
    id: u32,
    tri: Option<&Triangle>,
    mask: Mask,
    t_min: f32,
    t_max: &[f32; LANES],
) -> TriLanes {
    let tri = tri.filter(|_| g.spec.has_triangles);
    if let Some(tri) = tri
        && g.spec.triangle_algo == TRIANGLE_WATERTIGHT
    {
        return watertight_lanes(tri, r, sh, mask, t_min, t_max);
    }
    let mut h = TriLanes {
        t: [INFINITY; LANES],
        u: [0.0; LANES],
        v: [0.0; LANES],
    };
    let mut m = mask;
    while m != 0 {
        let l = m.trailing_zeros() as usize;
        m &= m - 1;
        (h.t[l], h.u[l], h.v[l]) = match tri {
            // `hit_prim` of a triangle, with the triangle already in hand.
            Some(tri) => hit_triangle(g, ray(l), sh.lane(l), tri, t_min, t_max[l]),
            None => hit_prim(g, ray(l), sh.lane(l), id, t_min, t_max[l]),
        };
    }
    h
}

/// `closest_hit_all` for every lane in `mask`, into `best` (misses at t_max): spheres
/// then triangles in index order, each lane's t_max its own nearest t so far.
#[inline(always)]
fn closest_hit_all_lanes(
    g: &Globals<f32>,
    rays: &[Ray<f32>; LANES],
    r: &Lanes<Shared>,
    sh: &ShearLanes,
    mask: Mask,
    t_min: f32,
    best: &mut [Hit<f32>; LANES],
) {
    if g.spec.has_spheres {
        for k in 0..g.buf.params.n_spheres {
            let s = &g.buf.spheres[k as usize];
            let mut m = mask;
            while m != 0 {
                let l = m.trailing_zeros() as usize;
                m &= m - 1;
                let t = hit_sphere(rays[l], s, t_min, best[l].t);
                if t < best[l].t {
                    best[l] = Hit {
                        t,
                        prim: k,
                        u: 0.0,
                        v: 0.0,
                    };
                }
            }
        }
    }
    if g.spec.has_triangles {
        for k in 0..g.buf.params.n_triangles {
            let tri = &g.buf.triangles[k as usize];
            let t_max: [f32; LANES] = std::array::from_fn(|l| best[l].t);
            let id = k | TRIANGLE_BIT;
            let h = prim_lanes(g, |l| rays[l], r, sh, id, Some(tri), mask, t_min, &t_max);
            let mut m = mask;
            while m != 0 {
                let l = m.trailing_zeros() as usize;
                m &= m - 1;
                if h.t[l] < best[l].t {
                    best[l] = Hit {
                        t: h.t[l],
                        prim: id,
                        u: h.u[l],
                        v: h.v[l],
                    };
                }
            }
        }
    }
}

/// Where a lane's hit triangle is when it was found in a BVH leaf: its index in
/// `leaf_triangles`, else this.
pub const NO_SLOT: u32 = u32::MAX;

/// What `closest_hit_packet` finds.
pub struct PacketHits {
    /// Each lane's hit, as `closest_hit` gives it.
    pub hits: [Hit<f32>; LANES],
    /// Each lane's hit triangle's index in `leaf_triangles` (the same triangle as
    /// `triangles[hit.prim]`, in memory the traversal has just read), or `NO_SLOT`.
    pub slots: [u32; LANES],
}

/// A packet's step at interior node `node` (index `at`) for the lanes in `lanes`: both
/// children's boxes tested per lane against `bound`; where some lanes enter both, the
/// nearer by the vote of those lanes comes next and the other is pushed with its lanes.
/// Returns the child to visit next with its lanes, or `None` when no lane enters either.
#[allow(clippy::too_many_arguments)]
#[inline(always)]
fn descend<O: Origins>(
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
    let mut near_l = [0.0f32; LANES];
    let mut near_r = [0.0f32; LANES];
    let ml = box_lanes(left, r, t_min, bound, &mut near_l) & lanes;
    let mr = box_lanes(right, r, t_min, bound, &mut near_r) & lanes;
    if ml != 0 && mr != 0 {
        let both = ml & mr;
        let mut vote = 0i32;
        for l in 0..LANES {
            let w = ((both >> l) & 1) as i32;
            vote += w * if near_r[l] < near_l[l] { 1 } else { -1 };
        }
        let (near, far) = if vote > 0 {
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

/// `occluded(ray, 0, 1, skip)` for each lane in `mask`, the rays given by their origins
/// `o` and directions `d` (structure of arrays): the lanes whose ray is blocked. Through
/// the BVH each lane reaches exactly the leaves its own `occluded_bvh` would (its box
/// tests are `box_interval`'s operations, against a t_max that never shrinks), so the
/// answer is the same, whatever order the packet takes.
#[inline(always)]
fn occluded_lanes(
    g: &Globals<f32>,
    o: [[f32; LANES]; 3],
    d: &[[f32; LANES]; 3],
    skip: &[u32; LANES],
    mask: Mask,
) -> Mask {
    let (t_min, t_max) = (0.0f32, finite_bound(1.0f32));
    let sh = shear_lanes(d, g.spec.triangle_algo == TRIANGLE_WATERTIGHT);
    let ray = |l: usize| Ray {
        origin: V3::new(o[0][l], o[1][l], o[2][l]),
        dir: V3::new(d[0][l], d[1][l], d[2][l]),
    };
    let r = Lanes::new(PerLane(o), d);
    let bound = [t_max; LANES];
    let mut blocked: Mask = 0;
    // Tests primitive `id` (triangle `tri` when it is one) for the lanes in `m`; returns
    // the lanes it blocks.
    //
    // Written out rather than through `prim_lanes`: that shared helper, inlined here three
    // times, made shadow rays 1.8–2.2× slower on the peers 2-triangle scene (benches/ab.sh,
    // ecddaff against 5c405e2), with the same image.
    let watertight = g.spec.has_triangles && g.spec.triangle_algo == TRIANGLE_WATERTIGHT;
    let test = |id: u32, tri: Option<&Triangle>, m: Mask| -> Mask {
        let mut out: Mask = 0;
        if let (Some(tri), true) = (tri, watertight) {
            let h = watertight_lanes(tri, &r, &sh, m, t_min, &bound);
            for l in 0..LANES {
                out |= (((m >> l) & 1 != 0 && id != skip[l] && h.t[l] < t_max) as Mask) << l;
            }
            return out;
        }
        let mut left = m;
        while left != 0 {
            let l = left.trailing_zeros() as usize;
            left &= left - 1;
            if id != skip[l] && hit_prim(g, ray(l), sh.lane(l), id, t_min, t_max).0 < t_max {
                out |= 1 << l;
            }
        }
        out
    };
    if !g.spec.use_bvh {
        // `occluded_all`: spheres, then triangles, each lane until it is blocked.
        let mut open = mask;
        if g.spec.has_spheres {
            for k in 0..g.buf.params.n_spheres {
                if open == 0 {
                    break;
                }
                open &= !test(k, None, open);
            }
        }
        if g.spec.has_triangles {
            for k in 0..g.buf.params.n_triangles {
                if open == 0 {
                    break;
                }
                open &= !test(k | TRIANGLE_BIT, Some(&g.buf.triangles[k as usize]), open);
            }
        }
        return mask & !open;
    }
    let nodes = &g.buf.nodes;
    if g.buf.params.n_nodes == 0 {
        return 0;
    }
    let mut near = [0.0f32; LANES];
    let mut lanes = box_lanes(&nodes[0], &r, t_min, &bound, &mut near) & mask;
    let mut stack = [(0u32, 0 as Mask); BVH_STACK];
    let mut sp = 0usize;
    let mut at = 0u32;
    for _step in 0..g.buf.params.n_nodes {
        lanes &= !blocked;
        if lanes != 0 {
            let node = &nodes[at as usize];
            let count = node.count_axis >> 2;
            if count == 0 {
                let next = descend(g, at, node, &r, t_min, &bound, lanes, &mut stack, &mut sp);
                if let Some(next) = next {
                    (at, lanes) = next;
                    continue;
                }
            } else {
                for k in node.first..node.first + count {
                    let id = g.buf.prim_ids[k as usize];
                    let tri = ((id & TRIANGLE_BIT) != 0).then(|| &g.buf.leaf_triangles[k as usize]);
                    blocked |= test(id, tri, lanes & !blocked);
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
pub fn closest_hit_packet(
    g: &Globals<f32>,
    rays: &[Ray<f32>; LANES],
    active: Mask,
    t_min: f32,
    t_max: f32,
) -> PacketHits {
    let miss = Hit {
        t: t_max,
        prim: PRIM_NONE,
        u: 0.0,
        v: 0.0,
    };
    let mut out = PacketHits {
        hits: [miss; LANES],
        slots: [NO_SLOT; LANES],
    };
    if active == 0 {
        return out;
    }
    let best = &mut out.hits;
    let slots = &mut out.slots;
    let mut dir = [[0.0f32; LANES]; 3];
    for l in 0..LANES {
        dir[0][l] = rays[l].dir.x;
        dir[1][l] = rays[l].dir.y;
        dir[2][l] = rays[l].dir.z;
    }
    let r = Lanes::new(Shared(rays[0].origin), &dir);
    let sh = shear_lanes(&dir, g.spec.triangle_algo == TRIANGLE_WATERTIGHT);
    if !g.spec.use_bvh {
        closest_hit_all_lanes(g, rays, &r, &sh, active, t_min, best);
        return out;
    }
    let nodes = &g.buf.nodes;
    if g.buf.params.n_nodes == 0 {
        return out;
    }
    let mut near = [0.0f32; LANES];
    let mut bound = [t_max; LANES];
    let mut mask = box_lanes(&nodes[0], &r, t_min, &bound, &mut near) & active;
    if mask == 0 {
        return out;
    }
    let mut stack = [(0u32, 0 as Mask); BVH_STACK];
    let mut sp = 0usize;
    let mut at = 0u32;
    for _step in 0..g.buf.params.n_nodes {
        let node = &nodes[at as usize];
        let count = node.count_axis >> 2;
        if count == 0 {
            let next = descend(g, at, node, &r, t_min, &bound, mask, &mut stack, &mut sp);
            if let Some(next) = next {
                (at, mask) = next;
                continue;
            }
        } else {
            for k in node.first..node.first + count {
                let id = g.buf.prim_ids[k as usize];
                let tri = ((id & TRIANGLE_BIT) != 0).then(|| &g.buf.leaf_triangles[k as usize]);
                let h = prim_lanes(g, |l| rays[l], &r, &sh, id, tri, mask, t_min, &bound);
                let mut m = mask;
                while m != 0 {
                    let l = m.trailing_zeros() as usize;
                    m &= m - 1;
                    if nearer(h.t[l], id, &best[l]) {
                        best[l] = Hit {
                            t: h.t[l],
                            prim: id,
                            u: h.u[l],
                            v: h.v[l],
                        };
                        bound[l] = tie_bound(&best[l]);
                        slots[l] = k;
                    }
                }
            }
        }
        if sp == 0 {
            break;
        }
        sp -= 1;
        (at, mask) = stack[sp];
    }
    out
}

/// Which build of the packet tracer runs.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Simd {
    /// The widest the CPU has (AVX2 on x86-64 when present).
    Best,
    /// The build for the target's baseline instruction set (SSE2 on x86-64), which a CPU
    /// without AVX2 runs: tests check it too.
    Baseline,
}

/// `trace_pixel` for the `PACKET_W` × `PACKET_H` block whose top-left pixel is (i, j),
/// lane `dy * PACKET_W + dx` for pixel (i + dx, j + dy); pixels outside the image are
/// left out.
/// `simd` picks the build: [`Simd::Best`] is AVX2 where the CPU has it.
pub fn trace_packet(g: &Globals<f32>, i: u32, j: u32, simd: Simd) -> [[f32; 4]; LANES] {
    #[cfg(not(target_arch = "x86_64"))]
    let _ = simd;
    #[cfg(target_arch = "x86_64")]
    if simd == Simd::Best && std::arch::is_x86_feature_detected!("avx2") {
        // SAFETY: the CPU has AVX2, checked just above.
        return unsafe { trace_packet_avx2(g, i, j) };
    }
    trace_packet_body(g, i, j)
}

/// `trace_packet` compiled for AVX2: the lane loops become eight-wide. Floating-point
/// results do not change with the instruction set (Rust never contracts `a * b + c`).
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
unsafe fn trace_packet_avx2(g: &Globals<f32>, i: u32, j: u32) -> [[f32; 4]; LANES] {
    trace_packet_body(g, i, j)
}

/// `camera_ray` through the point (dx, dy) of each pixel of the block at (i, j), lane by
/// lane with the same operations in the same order, written as lane loops so that they
/// vectorise; and the lanes whose pixel lies inside the image.
#[inline(always)]
pub fn camera_rays(
    g: &Globals<f32>,
    i: u32,
    j: u32,
    dx: f32,
    dy: f32,
) -> ([Ray<f32>; LANES], Mask) {
    let c = &g.cam;
    let two = 1.0f32 + 1.0;
    let mut active: Mask = 0;
    for l in 0..LANES {
        let (px, py) = (i + l as u32 % PACKET_W, j + l as u32 / PACKET_W);
        active |= ((px < c.width && py < c.height) as Mask) << l;
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
    let rays = std::array::from_fn(|l| Ray {
        origin: c.eye,
        dir: V3::new(n[0][l], n[1][l], n[2][l]),
    });
    (rays, active)
}

/// `trace_pixel` for the block: one packet per sample position, each packet the block's
/// pixels at the same point of their pixel (as coherent as the block itself), the lanes
/// summing their samples in `trace_pixel`'s order.
#[inline(always)]
fn trace_packet_body(g: &Globals<f32>, i: u32, j: u32) -> [[f32; 4]; LANES] {
    let half = 1.0f32 / (1.0 + 1.0);
    if !g.spec.antialias {
        return sample_packet(g, i, j, half, half);
    }
    let n = g.cam.samples;
    let mut sum = [[0.0f32; 3]; LANES];
    let mut t_near = [-1.0f32; LANES];
    for sy in 0..n {
        let dy = sample_offset::<f32>(sy, n);
        for sx in 0..n {
            let dx = sample_offset::<f32>(sx, n);
            let s = sample_packet(g, i, j, dx, dy);
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
    std::array::from_fn(|l| [sum[l][0] / nn, sum[l][1] / nn, sum[l][2] / nn, t_near[l]])
}

/// `trace_sample` at the point (dx, dy) of each pixel of the block.
#[inline(always)]
fn sample_packet(g: &Globals<f32>, i: u32, j: u32, dx: f32, dy: f32) -> [[f32; 4]; LANES] {
    let (rays, active) = camera_rays(g, i, j, dx, dy);
    let found = closest_hit_packet(g, &rays, active, 0.0, f32::MAX);
    let hits = &found.hits;
    let mut lit: Mask = 0;
    for l in 0..LANES {
        lit |= ((hits[l].prim != PRIM_NONE) as Mask) << l;
    }
    let colors = shade_lanes(g, &rays, &found, lit & active);
    std::array::from_fn(|l| {
        let hit = &hits[l];
        if hit.prim == PRIM_NONE {
            let bg = g.buf.params.background;
            return [bg[0], bg[1], bg[2], -1.0];
        }
        [colors[0][l], colors[1][l], colors[2][l], hit.t]
    })
}

/// `a · b` of lane l, left to right as `V3::dot`.
#[inline(always)]
fn dot_lane(a: &[[f32; LANES]; 3], b: &[[f32; LANES]; 3], l: usize) -> f32 {
    a[0][l] * b[0][l] + a[1][l] * b[1][l] + a[2][l] * b[2][l]
}

/// `V3::normalize` of every lane.
#[inline(always)]
fn normalize_lanes(v: &[[f32; LANES]; 3]) -> [[f32; LANES]; 3] {
    let mut out = [[0.0f32; LANES]; 3];
    for l in 0..LANES {
        let len = dot_lane(v, v, l).sqrt();
        out[0][l] = v[0][l] / len;
        out[1][l] = v[1][l] / len;
        out[2][l] = v[2][l] / len;
    }
    out
}

/// `shade` for the lanes in `mask`, which must all hit something: the same operations in
/// the same order, lane by lane, with the square roots, divisions and the exponent's
/// squarings as lane loops. Shadow rays and non-integer exponents go lane by lane
/// through the mirror's own `occluded` and `phong_power`. Lanes outside `mask` compute
/// lane `mask`'s first lane's values, which are not used.
#[inline(always)]
fn shade_lanes(
    g: &Globals<f32>,
    rays: &[Ray<f32>; LANES],
    found: &PacketHits,
    mask: Mask,
) -> [[f32; LANES]; 3] {
    let hits = &found.hits;
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
            return &g.buf.leaf_triangles[slot as usize];
        }
        &g.buf.triangles[(hits[l].prim & !TRIANGLE_BIT) as usize]
    };
    let mats: [&Material; LANES] = std::array::from_fn(|l| {
        let hit = &hits[src(l)];
        // `prim_material`.
        let material = if (hit.prim & TRIANGLE_BIT) != 0 {
            tri_of(src(l)).material
        } else {
            g.buf.spheres[hit.prim as usize].material
        };
        &g.buf.materials[material as usize]
    });
    let o = g.cam.eye;
    let mut p = [[0.0f32; LANES]; 3];
    let mut nv = [[0.0f32; LANES]; 3];
    let mut dir = [[0.0f32; LANES]; 3];
    for l in 0..LANES {
        let (ray, hit) = (&rays[src(l)], &hits[src(l)]);
        dir[0][l] = ray.dir.x;
        dir[1][l] = ray.dir.y;
        dir[2][l] = ray.dir.z;
        p[0][l] = o.x + ray.dir.x * hit.t;
        p[1][l] = o.y + ray.dir.y * hit.t;
        p[2][l] = o.z + ray.dir.z * hit.t;
        // `prim_normal` before its normalize.
        if (hit.prim & TRIANGLE_BIT) != 0 {
            let tri = tri_of(src(l));
            let e1 = [0, 1, 2].map(|k| tri.b[k] - tri.a[k]);
            let e2 = [0, 1, 2].map(|k| tri.c[k] - tri.a[k]);
            nv[0][l] = e1[1] * e2[2] - e1[2] * e2[1];
            nv[1][l] = e1[2] * e2[0] - e1[0] * e2[2];
            nv[2][l] = e1[0] * e2[1] - e1[1] * e2[0];
        } else {
            let c = g.buf.spheres[hit.prim as usize].center;
            nv[0][l] = p[0][l] - c[0];
            nv[1][l] = p[1][l] - c[1];
            nv[2][l] = p[2][l] - c[2];
        }
    }
    let mut n = normalize_lanes(&nv);
    let ambient = g.buf.params.ambient;
    let mut diffuse: Mask = 0;
    for l in 0..LANES {
        if dot_lane(&n, &dir, l) > 0.0 {
            n[0][l] = -n[0][l];
            n[1][l] = -n[1][l];
            n[2][l] = -n[2][l];
        }
        for k in 0..3 {
            color[k][l] = ambient[k] * mats[l].ka[k];
        }
        diffuse |= ((mats[l].model != MODEL_AMBIENT) as Mask) << l;
    }
    diffuse &= mask;
    // `shading_at`, lane by lane through the mirror's own function: the shading normal
    // `ns` and the shadow rays' start `ps` (`n` and `p` themselves for a flat hit).
    let mut ns = n;
    let mut ps = p;
    if g.spec.smooth {
        for l in 0..LANES {
            let pl = V3::new(p[0][l], p[1][l], p[2][l]);
            let nl = V3::new(n[0][l], n[1][l], n[2][l]);
            let sh = shading_at(g, &hits[src(l)], pl, nl);
            [ns[0][l], ns[1][l], ns[2][l]] = [sh.n.x, sh.n.y, sh.n.z];
            [ps[0][l], ps[1][l], ps[2][l]] = [sh.p.x, sh.p.y, sh.p.z];
        }
    }
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
                    skip[l] = hits[l].prim;
                }
                on &= !occluded_lanes(g, so, &sd, &skip, on);
            }
            for l in 0..LANES {
                if (on >> l) & 1 != 0 {
                    for c in 0..3 {
                        color[c][l] += light_color[c] * mats[l].kd[c] * ndl[l];
                    }
                }
            }
            let mut phong: Mask = 0;
            for l in 0..LANES {
                phong |= ((mats[l].model == MODEL_PHONG) as Mask) << l;
            }
            phong &= on;
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
                for l in 0..LANES {
                    if (phong >> l) & 1 != 0 {
                        for c in 0..3 {
                            color[c][l] += light_color[c] * mats[l].ks[c] * pw[l];
                        }
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
/// lane whose exponent is spent multiplies no further, as the scalar loop stops), other
/// exponents through `phong_power` itself.
#[inline(always)]
fn phong_power_lanes(base: &[f32; LANES], mats: &[&Material; LANES], mask: Mask) -> [f32; LANES] {
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
