// glint's kernel, part 7 of 8: arbitrary output variables (AOVs), what the primary ray
// through each pixel's centre hit (after `whitted.wgsl`; see `common.wgsl`'s header for how
// the parts are joined and mirrored). Its own entry point, which a colour render's
// pipeline never compiles. Mirror: `src/cpu/aov.rs`.

/// One pixel's AOVs (Rust: buffers::AovOut). On a miss t and depth are −1, prim and
/// material PRIM_NONE, the vectors 0.
struct AovOut {
    position: vec3<f32>,
    t: f32,
    geo_normal: vec3<f32>,
    depth: f32,
    normal: vec3<f32>,
    prim: u32,
    albedo: vec3<f32>,
    material: u32,
}

@group(0) @binding(16) var<storage, read_write> aov_out: array<AovOut>;

/// The AOVs of a hit `hit` of `ray`, as `shade` sees it: the point, the geometric normal
/// turned to face the ray, the shading normal, kd after textures, and the depth
/// t·(dir·forward) along the camera's axis. `hit` must be a hit, not a miss.
fn aov_of(ray: Ray, hit: Hit) -> AovOut {
    let mat = prim_material(hit);
    let a = albedo(hit, materials[mat]);
    let p = ray.origin + ray.dir * hit.t;
    var n = prim_normal(hit, p);
    if dot(n, ray.dir) > 0.0 {
        n = -n;
    }
    let sh = shading_at(hit, p, n);
    let depth = hit.t * dot(ray.dir, params.forward);
    return AovOut(p, hit.t, n, depth, sh.n, hit.prim, a.kd, mat);
}

/// The AOVs of pixel (i, j): the hit of the ray through its centre, whatever the
/// antialiasing (so ids and normals are never blends).
fn aov_pixel(i: u32, j: u32) -> AovOut {
    let ray = camera_ray(i, j, 0.5, 0.5);
    let hit = closest_hit(ray, 0.0, INFINITY);
    if hit.prim == PRIM_NONE {
        let zero = vec3<f32>(0.0, 0.0, 0.0);
        return AovOut(zero, -1.0, zero, -1.0, zero, PRIM_NONE, zero, PRIM_NONE);
    }
    return aov_of(ray, hit);
}

/// One invocation per pixel of the current tile, laid out as `render`'s.
@compute @workgroup_size(64, 1, 1)
fn render_aov(@builtin(workgroup_id) group: vec3<u32>, @builtin(local_invocation_index) local: u32) {
    let gid = pixel_of(group, local);
    if gid.x >= params.tile_width || gid.y >= params.tile_height {
        return;
    }
    aov_out[gid.y * params.tile_width + gid.x] = aov_pixel(params.tile_x + gid.x, params.tile_y + gid.y);
}
