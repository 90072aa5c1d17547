// glint view: the copy from the viewer's texture to the surface, one triangle over the
// screen, each fragment the texel under it. Not part of the tracing kernel.

@group(0) @binding(0) var picture: texture_2d<f32>;

@vertex
fn vs(@builtin(vertex_index) k: u32) -> @builtin(position) vec4<f32> {
    let x = f32((k << 1u) & 2u) * 2.0 - 1.0;
    let y = f32(k & 2u) * 2.0 - 1.0;
    return vec4<f32>(x, y, 0.0, 1.0);
}

@fragment
fn fs(@builtin(position) p: vec4<f32>) -> @location(0) vec4<f32> {
    let size = vec2<i32>(textureDimensions(picture));
    let at = min(vec2<i32>(p.xy), size - vec2<i32>(1, 1));
    return textureLoad(picture, at, 0);
}
