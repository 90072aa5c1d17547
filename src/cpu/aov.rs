//! The CPU mirror of `shaders/aov.wgsl`: the arbitrary output variables (AOVs) of a pixel,
//! what the primary ray through its centre hit (see [`super::common`] for the mirror's
//! rules).

use super::common::{Globals, Hit, Ray};
use super::count::{Count, RayKind};
use super::prims::{prim_material, prim_normal, shading_at};
use super::texture::albedo;
use super::trace::{camera_ray, closest_hit};
use crate::buffers::{AovOut, PRIM_NONE};
use crate::shared::real::Real;

/// WGSL `aov_of`: the AOVs of a hit `hit` of `ray`, as `shade` sees it: the point, the
/// geometric normal turned to face the ray, the shading normal, kd after textures, and the
/// depth t·(dir·forward). `hit` must be a hit, not a miss.
pub fn aov_of<R: Real, C: Count>(g: &Globals<R, C>, ray: Ray<R>, hit: &Hit<R>) -> AovOut {
    let mat = prim_material(g, hit);
    let a = albedo(g, hit, &g.buf.materials[mat as usize]);
    let p = ray.origin + ray.dir * hit.t;
    let mut n = prim_normal(g, hit, p);
    if n.dot(ray.dir) > R::ZERO {
        n = -n;
    }
    let sh = shading_at(g, hit, p, n);
    let depth = hit.t * ray.dir.dot(g.cam.forward);
    AovOut {
        position: p.to_f32(),
        t: hit.t.to_f32(),
        geo_normal: n.to_f32(),
        depth: depth.to_f32(),
        normal: sh.n.to_f32(),
        prim: hit.prim,
        albedo: a.kd.to_f32(),
        material: mat,
    }
}

/// The record of a pixel whose ray hits nothing.
pub const MISS: AovOut = AovOut {
    position: [0.0; 3],
    t: -1.0,
    geo_normal: [0.0; 3],
    depth: -1.0,
    normal: [0.0; 3],
    prim: PRIM_NONE,
    albedo: [0.0; 3],
    material: PRIM_NONE,
};

/// WGSL `aov_pixel`: the AOVs of pixel (i, j), from the ray through its centre whatever
/// the antialiasing.
pub fn aov_pixel<R: Real, C: Count>(g: &Globals<R, C>, i: u32, j: u32) -> AovOut {
    let half = R::ONE / (R::ONE + R::ONE);
    let ray: Ray<R> = camera_ray(g, i, j, half, half);
    g.count.next_kind(RayKind::Camera);
    let hit: Hit<R> = closest_hit(g, ray, R::ZERO, R::INFINITY);
    if hit.prim == PRIM_NONE {
        return MISS;
    }
    aov_of(g, ray, &hit)
}
