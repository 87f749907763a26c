// Material parameters at a surface point: the material's factors, scaled by its textures
// (glTF metallic-roughness: base colour and alpha, roughness in G and metalness in B,
// emission). Textures are packed into one texel buffer (`texels`, RGBA8) described by the
// table `textures` (lavapipe has no binding arrays) and filtered bilinearly (or nearest, with
// TEXTURE_NEAREST), sRGB-encoded colour decoded before filtering. Needs the resources
// `materials`, `textures` and `texels`.

#if TEXTURES
// sRGB-encoded colour to linear.
fn texture_srgb_decode(c: vec3<f32>) -> vec3<f32> {
    return select(pow((c + 0.055) / 1.055, vec3<f32>(2.4)), c / 12.92, c <= vec3<f32>(0.04045));
}

// Texel (x, y) of `t` as linear RGBA.
fn texture_texel(t: TextureInfo, x: u32, y: u32) -> vec4<f32> {
    if ((t.flags & TEXTURE_CHECKER) != 0u) {
        let i = t.offset + 4u * ((x + y) & 1u);
        return bitcast<vec4<f32>>(vec4<u32>(texels[i], texels[i + 1u], texels[i + 2u], texels[i + 3u]));
    }
    let c = unpack4x8unorm(texels[t.offset + y * t.width + x]);
    if ((t.flags & TEXTURE_SRGB) != 0u) {
        return vec4<f32>(texture_srgb_decode(c.rgb), c.a);
    }
    return c;
}

// Texel index `i` wrapped into 0 .. n by the wrap mode `mode`.
fn texture_wrap(i: i32, n: i32, mode: u32) -> u32 {
    if (mode == TEXTURE_WRAP_CLAMP) {
        return u32(clamp(i, 0, n - 1));
    }
    if (mode == TEXTURE_WRAP_MIRROR) {
        let period = 2 * n;
        let m = ((i % period) + period) % period;
        return u32(select(m, period - 1 - m, m >= n));
    }
    return u32(((i % n) + n) % n);
}

// Texture `index` at texture coordinates `uv` (before the texture's transform), (0, 0) at the
// top left of the image: bilinear between the four nearest texel centres, or the texel under
// the point with TEXTURE_NEAREST.
fn texture_sample(index: u32, uv: vec2<f32>) -> vec4<f32> {
    let t = textures[index];
    let st = vec2<f32>(dot(t.row0, vec3<f32>(uv, 1.0)), dot(t.row1, vec3<f32>(uv, 1.0)));
    let size = vec2<i32>(i32(t.width), i32(t.height));
    let mode_s = (t.flags >> TEXTURE_WRAP_S_SHIFT) & 3u;
    let mode_t = (t.flags >> TEXTURE_WRAP_T_SHIFT) & 3u;
    // Coordinates far out stay within the range of i32 (any integer wraps to a texel).
    if ((t.flags & TEXTURE_NEAREST) != 0u) {
        let n = vec2<i32>(clamp(floor(st * vec2<f32>(size)), vec2<f32>(-1e9), vec2<f32>(1e9)));
        return texture_texel(t, texture_wrap(n.x, size.x, mode_s), texture_wrap(n.y, size.y, mode_t));
    }
    let p = st * vec2<f32>(size) - 0.5;
    let base = floor(p);
    let f = p - base;
    let b = vec2<i32>(clamp(base, vec2<f32>(-1e9), vec2<f32>(1e9)));
    let x0 = texture_wrap(b.x, size.x, mode_s);
    let x1 = texture_wrap(b.x + 1, size.x, mode_s);
    let y0 = texture_wrap(b.y, size.y, mode_t);
    let y1 = texture_wrap(b.y + 1, size.y, mode_t);
    let top = mix(texture_texel(t, x0, y0), texture_texel(t, x1, y0), f.x);
    let bottom = mix(texture_texel(t, x0, y1), texture_texel(t, x1, y1), f.x);
    return mix(top, bottom, f.y);
}
#endif

// Material `index` resolved at texture coordinates `tex`.
fn material_at(index: u32, tex: vec2<f32>) -> Material {
    var m = materials[index];
// Only scenes with textures (the host sets the TEXTURES flag) sample them.
#if TEXTURES
    if (m.base_color_texture >= 0) {
        let c = texture_sample(u32(m.base_color_texture), tex);
        m.diffuse *= c.rgb;
        m.alpha *= c.a;
    }
    if (m.metallic_roughness_texture >= 0) {
        let c = texture_sample(u32(m.metallic_roughness_texture), tex);
        m.roughness *= c.g;
        m.metallic *= c.b;
    }
    if (m.emissive_texture >= 0) {
        m.emission *= texture_sample(u32(m.emissive_texture), tex).rgb;
    }
#endif
    return m;
}

// The alpha of material `m` at texture coordinates `tex` (its factor times the base colour
// texture's alpha).
fn material_alpha(m: Material, tex: vec2<f32>) -> f32 {
#if TEXTURES
    if (m.base_color_texture >= 0) {
        return m.alpha * texture_sample(u32(m.base_color_texture), tex).a;
    }
#endif
    return m.alpha;
}
