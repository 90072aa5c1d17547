// glint's ray-query tracer: `shaders/trace.wgsl` with its `closest_hit` and `occluded`
// replaced by the two below, which hand the triangles to the driver's acceleration
// structure (VK_KHR_ray_query) and keep glint's own exact test for the spheres.
//
// `src/gpu/rq.rs::shader_source` assembles the module: `enable wgpu_ray_query;`, then
// trace.wgsl with `fn closest_hit(` and `fn occluded(` renamed `..._compute(`, then this
// file. Everything else (the camera, `shade`, smooth normals, antialiasing, the entry points
// `render` and `query`) is trace.wgsl's own, so an image differs from the compute tracer's
// only where the driver's triangle hits differ. There is no CPU mirror: the driver's
// triangle test is not glint's, so this tracer is measured against f64, not asserted equal.

/// The scene's triangles as one bottom-level acceleration structure with one instance
/// (identity transform, triangle k is primitive k).
@group(0) @binding(11) var accel: acceleration_structure;

/// Whether the driver may be asked about this ray: VK_KHR_ray_query leaves NaN or infinite
/// origins and directions, a negative t_min and t_max < t_min undefined; glint's tracers
/// hit nothing there, and so does this one.
fn ray_query_valid(ray: Ray, t_min: f32, t_max: f32) -> bool {
    let o = ray.origin;
    let d = ray.dir;
    let finite = abs(o.x) <= INFINITY && abs(o.y) <= INFINITY && abs(o.z) <= INFINITY
        && abs(d.x) <= INFINITY && abs(d.y) <= INFINITY && abs(d.z) <= INFINITY;
    return finite && dot(d, d) > 0.0 && t_min >= 0.0 && t_max >= t_min;
}

/// The nearest hit in (t_min, t_max): every sphere by glint's own test, then the triangles
/// by a ray query whose t_max is the nearest sphere's t, so that a triangle wins only when
/// strictly nearer (at equal t the sphere, whose id is lower, wins as in `closest_hit`).
/// The driver's interval is closed, glint's open: a triangle hit at exactly t_min is dropped.
fn closest_hit(ray: Ray, t_min: f32, t_max: f32) -> Hit {
    let t_hi = finite_bound(t_max);
    var best = Hit(t_hi, PRIM_NONE, 0.0, 0.0, 0u);
    if HAS_SPHERES {
        best = closest_sphere(ray, t_min, best);
    }
    if HAS_TRIANGLES && ray_query_valid(ray, t_min, best.t) {
        var rq: ray_query;
        rayQueryInitialize(&rq, accel, RayDesc(RAY_FLAG_FORCE_OPAQUE, 0xFFu, t_min, best.t, ray.origin, ray.dir));
        rayQueryProceed(&rq);
        let x = rayQueryGetCommittedIntersection(&rq);
        if x.kind == RAY_QUERY_INTERSECTION_TRIANGLE && x.t > t_min && x.t < best.t {
            best = Hit(x.t, x.primitive_index | TRIANGLE_BIT, x.barycentrics.x, x.barycentrics.y, 0u);
        }
    }
    return best;
}

/// Whether anything but primitive `skip` lies on the ray in (t_min, t_max): the spheres by
/// glint's test, the triangles by a terminate-on-first-hit query in which every candidate
/// but `skip` (and any outside the open interval) is accepted. `skip_inst` is always 0: the
/// ray-query tracer takes no scene with instances (`src/gpu/rq.rs`).
fn occluded(ray: Ray, t_min: f32, t_max: f32, skip: u32, skip_inst: u32) -> bool {
    let t_hi = finite_bound(t_max);
    if HAS_SPHERES && sphere_blocks(ray, t_min, t_hi, skip) {
        return true;
    }
    if HAS_TRIANGLES && ray_query_valid(ray, t_min, t_hi) {
        var rq: ray_query;
        let flags = RAY_FLAG_FORCE_NO_OPAQUE | RAY_FLAG_TERMINATE_ON_FIRST_HIT;
        rayQueryInitialize(&rq, accel, RayDesc(flags, 0xFFu, t_min, t_hi, ray.origin, ray.dir));
        while rayQueryProceed(&rq) {
            let c = rayQueryGetCandidateIntersection(&rq);
            if (c.primitive_index | TRIANGLE_BIT) != skip && c.t > t_min && c.t < t_hi {
                rayQueryConfirmIntersection(&rq);
            }
        }
        let x = rayQueryGetCommittedIntersection(&rq);
        return x.kind == RAY_QUERY_INTERSECTION_TRIANGLE;
    }
    return false;
}
