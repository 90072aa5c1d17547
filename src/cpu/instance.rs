//! The CPU mirror of `shaders/instance.wgsl`: instances, the two-level search and the
//! hit's triangle carried back to world space (see [`super::common`] for the mirror's
//! rules, and the WGSL header for the layout). The maps are f32 scene values, widened
//! exactly to `R` where read, as a triangle's corners are.

// `!(x > 0)` is not `x <= 0` for NaN; the shader writes it so, on purpose, and so does its mirror.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

use super::common::{Globals, Hit, Ray};
use super::count::Count;
use super::prims::{hit_prim, ray_shear};
use super::trace::{box_interval, tie_bound};
use crate::buffers::{INSTANCE_IDENTITY, NO_INSTANCE, NO_MATERIAL, PRIM_NONE, Triangle};
use crate::shared::real::{Real, V3};

/// WGSL `TOP_STACK`: a top-level path, then a mesh's.
pub const TOP_STACK: usize = 2 * super::common::BVH_STACK;

/// WGSL `InstanceX`: an instance's maps (rows `[m0, m1, m2, t]`) in the tracer's
/// precision, its mesh's root and its material.
#[derive(Clone, Copy, Debug)]
pub struct InstanceX<R> {
    /// World to object.
    pub o: [[R; 4]; 3],
    /// Object to world.
    pub w: [[R; 4]; 3],
    /// Root node, with `INSTANCE_IDENTITY` for the identity.
    pub root: u32,
    /// Replacing material, or `NO_MATERIAL`.
    pub material: u32,
}

/// WGSL `instance_at`: instance `k`, widened.
pub fn instance_at<R: Real, C: Count>(g: &Globals<R, C>, k: u32) -> InstanceX<R> {
    let x = &g.buf.instances[k as usize];
    let widen = |m: &[[f32; 4]; 3]| m.map(|r| r.map(R::from_f32));
    InstanceX {
        o: widen(&x.to_object),
        w: widen(&x.to_world),
        root: x.root,
        material: x.material,
    }
}

/// WGSL `map_point`: ((m0·x + m1·y) + m2·z) + t per row.
#[inline]
pub fn map_point<R: Real>(m: &[[R; 4]; 3], p: V3<R>) -> V3<R> {
    let row = |r: &[R; 4]| r[0] * p.x + r[1] * p.y + r[2] * p.z + r[3];
    V3::new(row(&m[0]), row(&m[1]), row(&m[2]))
}

/// WGSL `map_vector`: the linear part only.
#[inline]
pub fn map_vector<R: Real>(m: &[[R; 4]; 3], v: V3<R>) -> V3<R> {
    let row = |r: &[R; 4]| r[0] * v.x + r[1] * v.y + r[2] * v.z;
    V3::new(row(&m[0]), row(&m[1]), row(&m[2]))
}

/// WGSL `map_normal`: by the transpose of the linear part.
#[inline]
pub fn map_normal<R: Real>(m: &[[R; 4]; 3], n: V3<R>) -> V3<R> {
    V3::new(
        m[0][0] * n.x + m[1][0] * n.y + m[2][0] * n.z,
        m[0][1] * n.x + m[1][1] * n.y + m[2][1] * n.z,
        m[0][2] * n.x + m[1][2] * n.y + m[2][2] * n.z,
    )
}

/// WGSL `ray_into`: the world ray in the instance's object space.
#[inline]
pub fn ray_into<R: Real>(x: &InstanceX<R>, ray: Ray<R>) -> Ray<R> {
    if (x.root & INSTANCE_IDENTITY) != 0 {
        return ray;
    }
    Ray {
        origin: map_point(&x.o, ray.origin),
        dir: map_vector(&x.o, ray.dir),
    }
}

/// WGSL `triangle_of`'s result: a triangle's corners in the tracer's precision, its
/// material and its vertex normals' index.
#[derive(Clone, Copy, Debug)]
pub struct TriangleX<R> {
    /// Corner a.
    pub a: V3<R>,
    /// Corner b.
    pub b: V3<R>,
    /// Corner c.
    pub c: V3<R>,
    /// Material index.
    pub material: u32,
    /// Index into `normals`, or `FLAT`.
    pub normals: u32,
}

/// WGSL `triangle_of`: the hit's triangle in world space, of the material it is shaded
/// with.
#[inline]
pub fn triangle_of<R: Real, C: Count>(g: &Globals<R, C>, hit: &Hit<R>) -> TriangleX<R> {
    let t: &Triangle = &g.buf.triangles[(hit.prim & !crate::buffers::TRIANGLE_BIT) as usize];
    let mut tri = TriangleX {
        a: V3::from_f32(t.a),
        b: V3::from_f32(t.b),
        c: V3::from_f32(t.c),
        material: t.material,
        normals: t.normals,
    };
    if g.spec.instances {
        let x = instance_at(g, hit.inst);
        if (x.root & INSTANCE_IDENTITY) == 0 {
            tri.a = map_point(&x.w, tri.a);
            tri.b = map_point(&x.w, tri.b);
            tri.c = map_point(&x.w, tri.c);
        }
        if x.material != NO_MATERIAL {
            tri.material = x.material;
        }
    }
    tri
}

/// WGSL `normals_of`: the hit triangle's vertex normals in world space.
#[inline]
pub fn normals_of<R: Real, C: Count>(
    g: &Globals<R, C>,
    hit: &Hit<R>,
    tri: &TriangleX<R>,
) -> [V3<R>; 3] {
    let vn = &g.buf.normals[tri.normals as usize];
    let mut n = [vn.na, vn.nb, vn.nc].map(V3::from_f32);
    if g.spec.instances {
        let x = instance_at(g, hit.inst);
        if (x.root & INSTANCE_IDENTITY) == 0 {
            n = n.map(|v| map_normal(&x.o, v).normalize());
        }
    }
    n
}

/// WGSL `nearer_in`: nearer, or as near with a lower (instance, primitive) pair.
#[inline]
pub fn nearer_in<R: Real>(t: R, inst: u32, id: u32, best: &Hit<R>) -> bool {
    if t < best.t {
        return true;
    }
    if !(t == best.t) || best.prim == PRIM_NONE {
        return false;
    }
    inst < best.inst || (inst == best.inst && id < best.prim)
}

/// WGSL `closest_hit_top`: the two-level search, depth first; one stack for both levels.
pub fn closest_hit_top<R: Real, C: Count>(
    g: &Globals<R, C>,
    ray: Ray<R>,
    t_min: R,
    t_max: R,
) -> Hit<R> {
    let mut best = Hit {
        t: t_max,
        prim: PRIM_NONE,
        u: R::ZERO,
        v: R::ZERO,
        inst: 0,
    };
    if g.buf.params.n_nodes == 0 {
        return best;
    }
    let nodes = &g.buf.nodes;
    let world_inv = V3::splat(R::ONE) / ray.dir;
    let world_sh = ray_shear(g, ray.dir);
    let root = box_interval(&nodes[0], ray.origin, world_inv, t_min, t_max);
    g.count.nodes_read(1);
    if !(root.0 <= root.1) {
        return best;
    }
    let mut r = ray;
    let mut inv_dir = world_inv;
    let mut sh = world_sh;
    let mut inst = NO_INSTANCE;
    let mut inst_sp = 0usize;
    let mut stack = [0u32; TOP_STACK];
    let mut sp = 0usize;
    let mut at = 0u32;
    loop {
        let node = &nodes[at as usize];
        g.count.nodes_read(1);
        let count = node.count_axis >> 2;
        if count == 0 {
            g.count.interior();
            g.count.nodes_read(2);
            let bound = tie_bound(&best);
            let left = box_interval(&nodes[at as usize + 1], r.origin, inv_dir, t_min, bound);
            let right = box_interval(&nodes[node.first as usize], r.origin, inv_dir, t_min, bound);
            let hit_left = left.0 <= left.1;
            let hit_right = right.0 <= right.1;
            if hit_left && hit_right {
                if right.0 < left.0 {
                    stack[sp] = at + 1;
                    at = node.first;
                } else {
                    stack[sp] = node.first;
                    at += 1;
                }
                sp += 1;
                g.count.stack(sp);
                continue;
            }
            if hit_left {
                at += 1;
                continue;
            }
            if hit_right {
                at = node.first;
                continue;
            }
        } else if inst == NO_INSTANCE {
            inst = node.first;
            inst_sp = sp;
            let x = instance_at(g, inst);
            r = ray_into(&x, ray);
            inv_dir = V3::splat(R::ONE) / r.dir;
            sh = ray_shear(g, r.dir);
            at = x.root & !INSTANCE_IDENTITY;
            continue;
        } else {
            g.count.leaf();
            for k in node.first..node.first + count {
                let id = g.buf.prim_ids[k as usize];
                g.count.prim(id);
                let h = hit_prim(g, r, sh, id, t_min, tie_bound(&best));
                if nearer_in(h.0, inst, id, &best) {
                    best = Hit {
                        t: h.0,
                        prim: id,
                        u: h.1,
                        v: h.2,
                        inst,
                    };
                }
            }
        }
        if inst != NO_INSTANCE && sp == inst_sp {
            inst = NO_INSTANCE;
            r = ray;
            inv_dir = world_inv;
            sh = world_sh;
        }
        if sp == 0 {
            break;
        }
        sp -= 1;
        at = stack[sp];
    }
    best
}

/// WGSL `occluded_top`: whether anything but primitive `skip` of instance `skip_inst`
/// lies on the ray, through the two levels; stops at the first hit.
pub fn occluded_top<R: Real, C: Count>(
    g: &Globals<R, C>,
    ray: Ray<R>,
    t_min: R,
    t_max: R,
    skip: u32,
    skip_inst: u32,
) -> bool {
    if g.buf.params.n_nodes == 0 {
        return false;
    }
    let nodes = &g.buf.nodes;
    let world_inv = V3::splat(R::ONE) / ray.dir;
    let world_sh = ray_shear(g, ray.dir);
    let root = box_interval(&nodes[0], ray.origin, world_inv, t_min, t_max);
    g.count.nodes_read(1);
    if !(root.0 <= root.1) {
        return false;
    }
    let mut r = ray;
    let mut inv_dir = world_inv;
    let mut sh = world_sh;
    let mut inst = NO_INSTANCE;
    let mut inst_sp = 0usize;
    let mut stack = [0u32; TOP_STACK];
    let mut sp = 0usize;
    let mut at = 0u32;
    loop {
        let node = &nodes[at as usize];
        g.count.nodes_read(1);
        let count = node.count_axis >> 2;
        if count == 0 {
            g.count.interior();
            g.count.nodes_read(2);
            let left = box_interval(&nodes[at as usize + 1], r.origin, inv_dir, t_min, t_max);
            let right = box_interval(&nodes[node.first as usize], r.origin, inv_dir, t_min, t_max);
            let hit_left = left.0 <= left.1;
            let hit_right = right.0 <= right.1;
            if hit_left && hit_right {
                if right.0 < left.0 {
                    stack[sp] = at + 1;
                    at = node.first;
                } else {
                    stack[sp] = node.first;
                    at += 1;
                }
                sp += 1;
                g.count.stack(sp);
                continue;
            }
            if hit_left {
                at += 1;
                continue;
            }
            if hit_right {
                at = node.first;
                continue;
            }
        } else if inst == NO_INSTANCE {
            inst = node.first;
            inst_sp = sp;
            let x = instance_at(g, inst);
            r = ray_into(&x, ray);
            inv_dir = V3::splat(R::ONE) / r.dir;
            sh = ray_shear(g, r.dir);
            at = x.root & !INSTANCE_IDENTITY;
            continue;
        } else {
            g.count.leaf();
            for k in node.first..node.first + count {
                let id = g.buf.prim_ids[k as usize];
                g.count.prim(id);
                if !(id == skip && inst == skip_inst)
                    && hit_prim(g, r, sh, id, t_min, t_max).0 < t_max
                {
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
        if sp == 0 {
            break;
        }
        sp -= 1;
        at = stack[sp];
    }
    false
}
