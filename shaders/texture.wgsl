// glint's kernel, part 3 of 8: image textures (after `common.wgsl` and `prims.wgsl`; see
// the first's header for how the parts are joined and mirrored). Mirror: `src/cpu/texture.rs`.
//
// A texture is linear RGB f32 texels in a storage buffer (`texels`), filtered by the
// bilinear lookup written out below (pbrt-v4's `Image::Bilerp`, its weights in its order),
// not by the GPU's sampler: a sampler interpolates with 8 fractional bits
// (`subTexelPrecisionBits`), so no sampler agrees with the CPU bit for bit. Only
// triangles are textured: a sphere's (u, v) needs `atan2` and `acos`, whose results differ
// between drivers.

/// The reflectances a hit is shaded with: the material's ka and kd, each times its
/// texture's colour where it has one.
struct Albedo {
    ka: vec3<f32>,
    kd: vec3<f32>,
}

/// `u` wrapped into [0, 1] (repeat): u − floor(u), which rounds up to 1 for a tiny
/// negative u; 0 for NaN and ±inf.
fn wrap01(u: f32) -> f32 {
    let f = u - floor(u);
    return select(0.0, f, f >= 0.0 && f <= 1.0);
}

/// Texel (x, y) of `tex` (row y counted from the bottom), for x in [−1, width] and y in
/// [−1, height], wrapped into the image (repeat).
fn texel(tex: Texture, x: i32, y: i32) -> vec3<f32> {
    let w = i32(tex.width);
    let h = i32(tex.height);
    let xw = select(select(x, x - w, x >= w), x + w, x < 0);
    let yw = select(select(y, y - h, y >= h), y + h, y < 0);
    let k = tex.offset + 3u * (u32(yw) * tex.width + u32(xw));
    return vec3<f32>(bitcast<f32>(texels[k]), bitcast<f32>(texels[k + 1u]), bitcast<f32>(texels[k + 2u]));
}

/// Texture `id`'s place: the four words at 4 × `id` in `texels`.
fn texture_place(id: u32) -> Texture {
    let k = 4u * id;
    return Texture(texels[k], texels[k + 1u], texels[k + 2u], 0u);
}

/// The colour of texture `id` at `uv`, v up: bilinear between the four texel centres
/// around it (texel (x, y) is centred at ((x + 0.5) / width, (y + 0.5) / height)), wrapping
/// around the edges. At a texel centre it is that texel's colour exactly.
fn texture_colour(id: u32, uv: vec2<f32>) -> vec3<f32> {
    let tex = texture_place(id);
    let x = wrap01(uv.x) * f32(tex.width) - 0.5;
    let y = wrap01(uv.y) * f32(tex.height) - 0.5;
    let xf = floor(x);
    let yf = floor(y);
    let dx = x - xf;
    let dy = y - yf;
    let xi = i32(xf);
    let yi = i32(yf);
    let c00 = texel(tex, xi, yi) * ((1.0 - dx) * (1.0 - dy));
    let c10 = texel(tex, xi + 1, yi) * (dx * (1.0 - dy));
    let c01 = texel(tex, xi, yi + 1) * ((1.0 - dx) * dy);
    let c11 = texel(tex, xi + 1, yi + 1) * (dx * dy);
    return c00 + c10 + c01 + c11;
}

/// The reflectances at a hit on material `m`: kd times the colour of its `map_kd` at the
/// hit's (u, v), ka times its `map_ka`'s (each product below the smallest normal f32 made
/// 0, as `shade`'s terms are). Spheres and untextured triangles take `m`'s as they are.
fn albedo(hit: Hit, m: Material) -> Albedo {
    var out = Albedo(m.ka, m.kd);
    if !TEXTURES || !is_triangle(hit.prim) {
        return out;
    }
    let tri = triangles[hit.prim & ~TRIANGLE_BIT];
    if tri.uvs == NO_UVS {
        return out;
    }
    let r = uvs[tri.uvs];
    let w = 1.0 - hit.u - hit.v;
    let uv = r.uv_a * w + r.uv_b * hit.u + r.uv_c * hit.v;
    var kd_colour = vec3<f32>(1.0, 1.0, 1.0);
    if r.map_kd != NO_TEXTURE {
        kd_colour = texture_colour(r.map_kd, uv);
        out.kd = flush3(m.kd * kd_colour);
    }
    if r.map_ka != NO_TEXTURE {
        if r.map_ka == r.map_kd {
            out.ka = flush3(m.ka * kd_colour);
        } else {
            out.ka = flush3(m.ka * texture_colour(r.map_ka, uv));
        }
    }
    return out;
}
