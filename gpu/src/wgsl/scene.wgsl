// furnace-gpu: scene module — WGSL twin of what furnace-scene and furnace-cpu's integrator do
// at a hit (Rust side of the buffers: gpu/src/scene.rs; parity: furnace-tests' scene_parity.rs).
//
// What is twinned:
//
// * `scene_oct_decode`: `furnace_scene::oct_decode` (snorm16 octahedral normal, folded, then
//   normalised), `scene_decode_tangent`: `decode_tangent`.
// * `scene_position`, `scene_shading_normal`, `scene_uv`, `scene_tangent`: the barycentric
//   interpolations of `Geometry::{triangle, shading_normal, uv, tangent}`
//   (`(1 − b1 − b2)·a + b1·b + b2·c`, the same operations in the same order, glam's
//   `normalize_or_zero` as `v · (1 / sqrt(dot))` with its finiteness test).
// * `scene_image_sample`: `Image::sample_bilinear` — texel centres at (i + ½)/n, wrap modes
//   REPEAT / CLAMP_TO_EDGE / MIRRORED_REPEAT, decode to linear *before* filtering, glam's
//   `lerp` (`a·(1 − s) + b·s`), non-finite UV → (0, 0). Decoding reads the CPU's own tables
//   (`srgb_to_linear(i/255)`, `i/255`, at the head of `scene_texels`): bit-identical. The
//   texel coordinate is where the two sides differ: the CPU forms `u·n − ½` in f64; here the
//   UV is first moved by whole wrap periods into [0, 1) (REPEAT), [0, 2) (MIRRORED) or clamped
//   to [−1, 2] (CLAMP, beyond which both texels are the edge texel) — exact in f32 — and
//   `u·n − ½` is formed in f32, so the bilinear weights differ by about one ULP of the texel
//   coordinate (≈ n·2⁻²⁴), the texel chosen may differ only where its weight is ≈ 0.
// * `scene_texture_transform`: `TextureTransform::apply` with the CPU's matrix (no sin/cos
//   here), glam's `Mat3 · Vec3` order.
// * `scene_texture_sample`: `TextureRef::sample_bilinear` (transform, wrap, colour space; a
//   missing texture is opaque white).
// * `scene_material_evaluate` → `MaterialSample`: `Material::evaluate`.
// * `scene_surface_point`: furnace-cpu's `Renderer::surface_point`: position, geometric normal
//   `normalize_or_zero(cross(v1 − v0, v2 − v0))` (furnace-cpu's `geometric_normal`: the cross
//   product divided by its largest component first where |cross|² over- or underflows f32),
//   interpolated shading normal (geometric when
//   zero), the glTF normal map in the frame (T ⟂ N, B = w·N×T, N), and the orientation: on the
//   back (dot(geometric, direction) > 0) a double-sided material flips both normals, a
//   single-sided one gives no surface (`valid == 0`).
// * `scene_blend_coverage`: `Scene::coverage` of a BLEND material (stochastic transparency;
//   the integrator's shadow.wgsl draws the decisions).
// * `scene_alpha_passes`: furnace-cpu's `Renderer::alpha_passes` (the traversal's `hit_filter`):
//   MASK materials keep a hit where `baseColorFactor.a × texture alpha ≥ alphaCutoff`.
// * `scene_srgb_to_linear`: `furnace_scene::srgb_to_linear` for continuous values (texels use
//   the exact table instead); pow differs from the CPU's powf by float rounding.
//
// A driver may fuse multiply-adds and WGSL division / sqrt are not correctly rounded, so
// floating-point results agree with the CPU to float rounding, not bit for bit.
//
// What the composing shader must declare before this module (Rust:
// `furnace_gpu::scene::bindings(group, first)`, generated): the `SCENE_*` constants of
// gpu/src/scene.rs, the structs `SceneTriangle`, `SceneVertex`, `SceneTextureRef`,
// `SceneMaterial` (furnace_gpu::scene::Gpu*), and the six buffers
//
//   var<storage, read> scene_triangles: array<SceneTriangle>;
//   var<storage, read> scene_vertices: array<SceneVertex>;
//   var<storage, read> scene_attributes: array<vec2<u32>>;
//   var<storage, read> scene_tangents: array<vec2<u32>>;
//   var<storage, read> scene_materials: array<SceneMaterial>;
//   var<storage, read> scene_texels: array<u32>;
//
// The module is composed through `furnace_gpu::wgsl::select` with two features: `UV_SETS`
// (some texture samples a UV set other than UV0) and `VERTEX_COLORS` (the scene has COLOR_0);
// without them, those reads are not composed (`|_| true` composes everything).

// furnace_scene::MaterialSample.
struct MaterialSample {
    base_color: vec3<f32>,
    alpha: f32,
    metallic: f32,
    roughness: f32,
    emission: vec3<f32>,
    specular_factor: f32,
    specular_color: vec3<f32>,
}

// furnace-cpu's SurfacePoint; `valid` is 0 on the back of a single-sided material (the Rust
// `None`), 1 otherwise.
struct SceneSurfacePoint {
    position: vec3<f32>,
    valid: u32,
    geometric: vec3<f32>,
    // 1 on the back of a double-sided surface (normals flipped): emission is one-sided.
    back_face: u32,
    shading: vec3<f32>,
}

// ---------------------------------------------------------------------------------------------
// Float helpers with glam's operation order.

// f32::is_finite, on the bits (a compiler may assume no NaN in float comparisons).
fn scene_is_finite(x: f32) -> bool {
    return (bitcast<u32>(x) & 0x7f800000u) != 0x7f800000u;
}

// Vec3::dot: (x·x' + y·y') + z·z'.
fn scene_dot(a: vec3<f32>, b: vec3<f32>) -> f32 {
    return a.x * b.x + a.y * b.y + a.z * b.z;
}

// Vec3::cross.
fn scene_cross(a: vec3<f32>, b: vec3<f32>) -> vec3<f32> {
    return vec3<f32>(a.y * b.z - b.y * a.z, a.z * b.x - b.z * a.x, a.x * b.y - b.x * a.y);
}

// Vec3::normalize_or: v · (1/|v|) when that reciprocal is finite and positive, else fallback.
fn scene_normalize_or(v: vec3<f32>, fallback: vec3<f32>) -> vec3<f32> {
    let rcp = 1.0 / sqrt(scene_dot(v, v));
    if scene_is_finite(rcp) && rcp > 0.0 {
        return v * rcp;
    }
    return fallback;
}

fn scene_normalize_or_zero(v: vec3<f32>) -> vec3<f32> {
    return scene_normalize_or(v, vec3<f32>(0.0));
}

// furnace-cpu's `geometric_normal`: `normalize_or_zero(cross(v1 − v0, v2 − v0))`, except where
// that is zero for a finite, non-zero cross product (|cross|² overflows f32 for edges beyond
// ~4e9, underflows below ~1e-10): then the cross product is divided by its largest component
// first. Bit-identical to the plain form wherever that is not zero.
fn scene_geometric_normal(v0: vec3<f32>, v1: vec3<f32>, v2: vec3<f32>) -> vec3<f32> {
    let c = scene_cross(v1 - v0, v2 - v0);
    let n = scene_normalize_or_zero(c);
    let exponent = bitcast<vec3<u32>>(c) & vec3<u32>(0x7f800000u);
    if any(n != vec3<f32>(0.0)) || any(exponent == vec3<u32>(0x7f800000u)) {
        return n;
    }
    let m = max(max(abs(c.x), abs(c.y)), abs(c.z));
    if m > 0.0 {
        return scene_normalize_or_zero(c / m);
    }
    return vec3<f32>(0.0);
}

// (1 − b1 − b2)·a + b1·b + b2·c, glam's order.
fn scene_interpolate3(a: vec3<f32>, b: vec3<f32>, c: vec3<f32>, b1: f32, b2: f32) -> vec3<f32> {
    return (1.0 - b1 - b2) * a + b1 * b + b2 * c;
}

// i16 in bits 16k..16k+15 of `w`, as f32 / 32767.
fn scene_snorm16(w: u32, k: u32) -> f32 {
    let shift = 16u - 16u * k;
    return f32(bitcast<i32>(w << shift) >> 16u) / 32767.0;
}

// ---------------------------------------------------------------------------------------------
// Geometry.

// furnace_scene::oct_decode.
fn scene_oct_decode(e: u32) -> vec3<f32> {
    let x0 = scene_snorm16(e, 0u);
    let y0 = scene_snorm16(e, 1u);
    let z = 1.0 - abs(x0) - abs(y0);
    let t = max(-z, 0.0);
    let x = x0 + select(t, -t, x0 >= 0.0);
    let y = y0 + select(t, -t, y0 >= 0.0);
    let v = vec3<f32>(x, y, z);
    return v * (1.0 / sqrt(scene_dot(v, v)));
}

// furnace_scene::decode_tangent of a vertex's two words.
fn scene_decode_tangent(w: vec2<u32>) -> vec4<f32> {
    return vec4<f32>(scene_snorm16(w.x, 0u), scene_snorm16(w.x, 1u), scene_snorm16(w.y, 0u), scene_snorm16(w.y, 1u));
}

// The material index of a triangle (clamped into the materials at upload).
fn scene_triangle_material(triangle: u32) -> u32 {
    return scene_triangles[triangle].material;
}

// #if INSTANCES
// furnace_scene::Instance: a shared mesh's point, normal and tangent carried to world space by
// the instance of the hit being shaded (`trv_instance`, set by the traversal; the world
// triangles are an instance of their own, placed by the identity, which changes no bit).
fn scene_place_point(p: vec3<f32>) -> vec3<f32> {
    let i = instances[trv_instance];
    let p1 = vec4<f32>(p, 1.0);
    return vec3<f32>(dot(i.world_x, p1), dot(i.world_y, p1), dot(i.world_z, p1));
}

fn scene_place_normal(n: vec3<f32>) -> vec3<f32> {
    let i = instances[trv_instance];
    return scene_normalize_or_zero(vec3<f32>(dot(i.normal_x.xyz, n), dot(i.normal_y.xyz, n), dot(i.normal_z.xyz, n)));
}

fn scene_place_tangent(t: vec4<f32>) -> vec4<f32> {
    let i = instances[trv_instance];
    let d = vec4<f32>(t.xyz, 0.0);
    let xyz = scene_normalize_or_zero(vec3<f32>(dot(i.world_x, d), dot(i.world_y, d), dot(i.world_z, d)));
    return vec4<f32>(xyz, select(t.w, -t.w, i.mirrors != 0u));
}
// #endif

// The point at barycentrics (b1, b2) of a triangle.
fn scene_position(triangle: u32, b1: f32, b2: f32) -> vec3<f32> {
    let t = scene_triangles[triangle];
    // #if INSTANCES
    return scene_interpolate3(scene_place_point(scene_vertices[t.i0].position),
        scene_place_point(scene_vertices[t.i1].position), scene_place_point(scene_vertices[t.i2].position), b1, b2);
    // #else
    return scene_interpolate3(scene_vertices[t.i0].position, scene_vertices[t.i1].position,
        scene_vertices[t.i2].position, b1, b2);
    // #endif
}

// Geometry::shading_normal: interpolated vertex normals, normalised (zero if they cancel).
fn scene_shading_normal(triangle: u32, b1: f32, b2: f32) -> vec3<f32> {
    let t = scene_triangles[triangle];
    let n = scene_interpolate3(scene_oct_decode(scene_vertices[t.i0].normal),
        scene_oct_decode(scene_vertices[t.i1].normal), scene_oct_decode(scene_vertices[t.i2].normal), b1, b2);
    // #if INSTANCES
    return scene_place_normal(scene_normalize_or_zero(n));
    // #else
    return scene_normalize_or_zero(n);
    // #endif
}

// VertexAttributes: the UV sets (those a material does not sample: (0, 0)) and COLOR_0
// (opaque white without it) at a shading point.
struct SceneAttributes {
    uv0: vec2<f32>,
    uv1: vec2<f32>,
    uv2: vec2<f32>,
    uv3: vec2<f32>,
    color: vec4<f32>,
}

// VertexAttributes::from_uv: UV0 alone.
fn scene_attributes_of_uv(uv: vec2<f32>) -> SceneAttributes {
    return SceneAttributes(uv, vec2<f32>(0.0), vec2<f32>(0.0), vec2<f32>(0.0), vec4<f32>(1.0));
}

// Word k of the triangle's vertices' attributes (`stride` words per vertex), interpolated as
// a UV.
fn scene_interpolate_uv(t: SceneTriangle, stride: u32, k: u32, b1: f32, b2: f32) -> vec2<f32> {
    let a = bitcast<vec2<f32>>(scene_attributes[t.i0 * stride + k]);
    let b = bitcast<vec2<f32>>(scene_attributes[t.i1 * stride + k]);
    let c = bitcast<vec2<f32>>(scene_attributes[t.i2 * stride + k]);
    return (1.0 - b1 - b2) * a + b1 * b + b2 * c;
}

// decode_color: RGBA unorm16 in two words.
fn scene_decode_color(w: vec2<u32>) -> vec4<f32> {
    return vec4<f32>(f32(w.x & 0xffffu), f32(w.x >> 16u), f32(w.y & 0xffffu), f32(w.y >> 16u)) / 65535.0;
}

// Geometry::attributes at barycentrics (b1, b2) of `triangle`, whose material is `material`:
// the UV sets its textures sample and the vertex colour where the scene has them.
fn scene_hit_attributes(material: u32, triangle: u32, b1: f32, b2: f32) -> SceneAttributes {
    var a = scene_attributes_of_uv(vec2<f32>(0.0));
    let flags = scene_materials[material].flags;
    let stride = (flags >> SCENE_MATERIAL_STRIDE_SHIFT) & 7u;
    if stride == 0u {
        return a;
    }
    let t = scene_triangles[triangle];
    let sets = (flags >> SCENE_MATERIAL_UV_SETS_SHIFT) & 7u;
    if sets > 0u {
        a.uv0 = scene_interpolate_uv(t, stride, 0u, b1, b2);
    }
    // #if UV_SETS
    if sets > 1u {
        a.uv1 = scene_interpolate_uv(t, stride, 1u, b1, b2);
    }
    if sets > 2u {
        a.uv2 = scene_interpolate_uv(t, stride, 2u, b1, b2);
    }
    if sets > 3u {
        a.uv3 = scene_interpolate_uv(t, stride, 3u, b1, b2);
    }
    // #endif
    // #if VERTEX_COLORS
    if (flags & SCENE_MATERIAL_VERTEX_COLOR) != 0u {
        let k = stride - 1u;
        a.color = (1.0 - b1 - b2) * scene_decode_color(scene_attributes[t.i0 * stride + k])
            + b1 * scene_decode_color(scene_attributes[t.i1 * stride + k])
            + b2 * scene_decode_color(scene_attributes[t.i2 * stride + k]);
    }
    // #endif
    return a;
}

// Geometry::uv: interpolated UV0 ((0, 0) in a scene without UVs).
fn scene_uv(triangle: u32, b1: f32, b2: f32) -> vec2<f32> {
    return scene_hit_attributes(scene_triangles[triangle].material, triangle, b1, b2).uv0;
}

// Geometry::tangent: interpolated xyz re-normalised, handedness of the first vertex. Only
// meaningful in a scene with tangents (some material normal-mapped).
fn scene_tangent(triangle: u32, b1: f32, b2: f32) -> vec4<f32> {
    let t = scene_triangles[triangle];
    let ta = scene_decode_tangent(scene_tangents[t.i0]);
    let tb = scene_decode_tangent(scene_tangents[t.i1]);
    let tc = scene_decode_tangent(scene_tangents[t.i2]);
    let xyz = scene_normalize_or_zero(scene_interpolate3(ta.xyz, tb.xyz, tc.xyz, b1, b2));
    // #if INSTANCES
    return scene_place_tangent(vec4<f32>(xyz, select(1.0, -1.0, ta.w < 0.0)));
    // #else
    return vec4<f32>(xyz, select(1.0, -1.0, ta.w < 0.0));
    // #endif
}

// ---------------------------------------------------------------------------------------------
// Textures.

// furnace_scene::srgb_to_linear (IEC 61966-2-1) for a continuous value.
fn scene_srgb_to_linear(c: f32) -> f32 {
    if c <= 0.04045 {
        return c / 12.92;
    }
    return pow((c + 0.055) / 1.055, 2.4);
}

// Moves u by whole periods of the wrap mode (exact in f32: u − floor(u) is representable), so
// that u·n stays small: [0, 1] for REPEAT, [0, 2] for MIRRORED; CLAMP clamps to [−1, 2], past
// which both texels of the bilinear footprint are the edge texel.
fn scene_wrap_reduce(u: f32, mode: u32) -> f32 {
    if mode == SCENE_WRAP_REPEAT {
        return u - floor(u);
    }
    if mode == SCENE_WRAP_MIRRORED {
        return u - 2.0 * floor(0.5 * u);
    }
    return clamp(u, -1.0, 2.0);
}

// WrapMode::apply: texel index i (any integer) into 0..n.
fn scene_wrap(i: i32, n: u32, mode: u32) -> u32 {
    let m = i32(max(n, 1u));
    if mode == SCENE_WRAP_REPEAT {
        return u32(((i % m) + m) % m);
    }
    if mode == SCENE_WRAP_MIRRORED {
        let r = ((i % (2 * m)) + 2 * m) % (2 * m);
        return u32(select(2 * m - 1 - r, r, r < m));
    }
    return u32(clamp(i, 0, m - 1));
}

// Image::texel: texel (x, y) decoded to linear RGBA through the CPU's tables.
fn scene_texel(t: SceneTextureRef, x: u32, y: u32) -> vec4<f32> {
    let w = scene_texels[t.texel_offset + y * t.width + x];
    let rgb = select(SCENE_LINEAR_TABLE, SCENE_SRGB_TABLE, (t.flags & SCENE_TEXTURE_SRGB) != 0u);
    return vec4<f32>(
        bitcast<f32>(scene_texels[rgb + (w & 0xffu)]),
        bitcast<f32>(scene_texels[rgb + ((w >> 8u) & 0xffu)]),
        bitcast<f32>(scene_texels[rgb + ((w >> 16u) & 0xffu)]),
        bitcast<f32>(scene_texels[SCENE_LINEAR_TABLE + (w >> 24u)]),
    );
}

// Vec4::lerp.
fn scene_lerp4(a: vec4<f32>, b: vec4<f32>, s: f32) -> vec4<f32> {
    return a * (1.0 - s) + b * s;
}

// Image::sample_bilinear with the reference's wrap modes and colour space.
fn scene_image_sample(t: SceneTextureRef, uv_in: vec2<f32>) -> vec4<f32> {
    var uv = uv_in;
    if !(scene_is_finite(uv.x) && scene_is_finite(uv.y)) {
        uv = vec2<f32>(0.0);
    }
    let ws = (t.flags >> SCENE_WRAP_S_SHIFT) & 3u;
    let wt = (t.flags >> SCENE_WRAP_T_SHIFT) & 3u;
    let x = scene_wrap_reduce(uv.x, ws) * f32(t.width) - 0.5;
    let y = scene_wrap_reduce(uv.y, wt) * f32(t.height) - 0.5;
    let x0 = floor(x);
    let y0 = floor(y);
    let fx = x - x0;
    let fy = y - y0;
    let xa = scene_wrap(i32(x0), t.width, ws);
    let xb = scene_wrap(i32(x0) + 1, t.width, ws);
    let ya = scene_wrap(i32(y0), t.height, wt);
    let yb = scene_wrap(i32(y0) + 1, t.height, wt);
    let top = scene_lerp4(scene_texel(t, xa, ya), scene_texel(t, xb, ya), fx);
    let bottom = scene_lerp4(scene_texel(t, xa, yb), scene_texel(t, xb, yb), fx);
    return scene_lerp4(top, bottom, fy);
}

// TextureTransform::apply (matrix from the CPU); identity without the extension.
fn scene_texture_transform(t: SceneTextureRef, uv: vec2<f32>) -> vec2<f32> {
    if (t.flags & SCENE_TEXTURE_TRANSFORM) == 0u {
        return uv;
    }
    let m = t.transform;
    return vec2<f32>(m[0] * uv.x + m[2] * uv.y + m[4], m[1] * uv.x + m[3] * uv.y + m[5]);
}

// TextureRef::sample: at the slot's UV set of `at` (UV0 in a scene whose textures sample no
// other).
fn scene_texture_sample_at(t: SceneTextureRef, at: SceneAttributes) -> vec4<f32> {
    var uv = at.uv0;
    // #if UV_SETS
    let uv_set = (t.flags >> SCENE_TEXTURE_UV_SET_SHIFT) & 3u;
    if uv_set == 1u {
        uv = at.uv1;
    } else if uv_set == 2u {
        uv = at.uv2;
    } else if uv_set == 3u {
        uv = at.uv3;
    }
    // #endif
    return scene_texture_sample(t, uv);
}

// TextureRef::sample_bilinear: linear RGBA at `uv`; opaque white without a texture.
fn scene_texture_sample(t: SceneTextureRef, uv: vec2<f32>) -> vec4<f32> {
    if (t.flags & SCENE_TEXTURE_PRESENT) == 0u {
        return vec4<f32>(1.0);
    }
    return scene_image_sample(t, scene_texture_transform(t, uv));
}

// ---------------------------------------------------------------------------------------------
// Materials.

// Material::uses_textures: whether evaluating needs the hit's UV.
fn scene_material_is_textured(material: u32) -> bool {
    return (scene_materials[material].flags & SCENE_MATERIAL_TEXTURED) != 0u;
}

// Material::evaluate: factors × textures at `at`, the base colour and alpha times the vertex
// colour.
fn scene_material_evaluate(material: u32, at: SceneAttributes) -> MaterialSample {
    let m = scene_materials[material];
    var base = m.base_color_factor * scene_texture_sample_at(m.base_color_texture, at);
    // #if VERTEX_COLORS
    base *= at.color;
    // #endif
    let mr = scene_texture_sample_at(m.metallic_roughness_texture, at);
    let emission = m.emissive * scene_texture_sample_at(m.emissive_texture, at).xyz;
    return MaterialSample(base.xyz, base.w, m.metallic_factor * mr.z, m.roughness_factor * mr.y, emission,
        m.specular_factor, m.specular_color_factor);
}

// Material::evaluate of a material without textures or vertex colours: its factors.
fn scene_material_factors(material: u32) -> MaterialSample {
    let m = scene_materials[material];
    return MaterialSample(m.base_color_factor.xyz, m.base_color_factor.w, m.metallic_factor, m.roughness_factor,
        m.emissive, m.specular_factor, m.specular_color_factor);
}

// Renderer::alpha_passes (the traversal's hit_filter): false only where a MASK material's
// alpha is below its cutoff.
fn scene_alpha_passes(triangle_id: u32, b1: f32, b2: f32) -> bool {
    let mi = scene_triangles[triangle_id].material;
    let flags = scene_materials[mi].flags;
    if (flags & SCENE_ALPHA_MODE_BITS) != SCENE_ALPHA_MASK {
        return true;
    }
    return scene_alpha_at(mi, triangle_id, b1, b2) >= scene_materials[mi].alpha_cutoff;
}

// Scene::alpha_at: baseColorFactor.a × base colour texture alpha × vertex alpha at a hit.
fn scene_alpha_at(mi: u32, triangle_id: u32, b1: f32, b2: f32) -> f32 {
    let at = scene_hit_attributes(mi, triangle_id, b1, b2);
    return scene_materials[mi].base_color_factor.w
        * scene_texture_sample_at(scene_materials[mi].base_color_texture, at).w * at.color.w;
}

// Scene::coverage of a BLEND material `mi`'s hit: its alpha clamped to [0, 1], 0 for NaN.
fn scene_blend_coverage(mi: u32, triangle_id: u32, b1: f32, b2: f32) -> f32 {
    let a = scene_alpha_at(mi, triangle_id, b1, b2);
    return select(0.0, min(a, 1.0), a > 0.0);
}


// Scene::normal_mapped: `normal` with a glTF normal map applied at `at` through the vertex
// tangents: the tangent-space normal (2·rgb − 1)·(scale, scale, 1) in the frame
// (T, B = w·N×T, N), with T made orthogonal to N; `normal` itself without a map.
fn scene_normal_mapped(triangle: u32, b1: f32, b2: f32, normal: vec3<f32>, map: SceneTextureRef, scale: f32,
                       at: SceneAttributes) -> vec3<f32> {
    if (map.flags & SCENE_TEXTURE_PRESENT) == 0u {
        return normal;
    }
    let tangent = scene_tangent(triangle, b1, b2);
    let m = (2.0 * scene_texture_sample_at(map, at).xyz - vec3<f32>(1.0)) * vec3<f32>(scale, scale, 1.0);
    let tn = scene_normalize_or_zero(tangent.xyz - normal * scene_dot(normal, tangent.xyz));
    if all(tn == vec3<f32>(0.0)) {
        return normal;
    }
    let bn = tangent.w * scene_cross(normal, tn);
    return scene_normalize_or(m.x * tn + m.y * bn + m.z * normal, normal);
}

// valid_reflection_normal: `n` bent towards `ng` just enough that the mirror reflection of
// `wo` leaves the surface at least min(0.9·(wo·ng), 0.01) above it (the normal-mapped normal
// of a hit; see the Rust for the quadratic).
fn scene_valid_reflection_normal(ng: vec3<f32>, wo: vec3<f32>, n: vec3<f32>) -> vec3<f32> {
    let iz = scene_dot(wo, ng);
    let t = min(0.9 * iz, 0.01);
    let r = 2.0 * scene_dot(n, wo) * n - wo;
    if !(iz > 0.0) || scene_dot(r, ng) >= t {
        return n;
    }
    let x = scene_normalize_or_zero(n - ng * scene_dot(n, ng));
    if all(x == vec3<f32>(0.0)) {
        return ng;
    }
    let ix = scene_dot(wo, x);
    let a = ix * ix + iz * iz;
    let b = 2.0 * (a + iz * t);
    let c = (t + iz) * (t + iz);
    let root = sqrt(max(b * b - 4.0 * a * c, 0.0));
    var z2 = c / (b + root);
    var x2 = 0.25 * (2.0 * (a - iz * t) + root) / a;
    if ix < 0.0 {
        z2 = 0.25 * (b + root) / a;
        x2 = (iz - t) * (iz - t) / (2.0 * (a - iz * t) + root);
    }
    return scene_normalize_or(x * sqrt(clamp(x2, 0.0, 1.0)) + ng * sqrt(clamp(z2, 0.0, 1.0)), ng);
}

// Renderer::surface_point for a ray travelling along `direction` that hit `triangle` at
// barycentrics (b1, b2); `at` is the hit's attributes (used by a normal map only).
fn scene_surface_point(triangle: u32, b1: f32, b2: f32, at: SceneAttributes, direction: vec3<f32>) -> SceneSurfacePoint {
    let t = scene_triangles[triangle];
    // #if INSTANCES
    let v0 = scene_place_point(scene_vertices[t.i0].position);
    let v1 = scene_place_point(scene_vertices[t.i1].position);
    let v2 = scene_place_point(scene_vertices[t.i2].position);
    // #else
    let v0 = scene_vertices[t.i0].position;
    let v1 = scene_vertices[t.i1].position;
    let v2 = scene_vertices[t.i2].position;
    // #endif
    let position = scene_interpolate3(v0, v1, v2, b1, b2);
    var geometric = scene_geometric_normal(v0, v1, v2);
    // #if INSTANCES
    // A mirroring instance turns the winding: its front stays the mesh's front.
    if instances[trv_instance].mirrors != 0u {
        geometric = -geometric;
    }
    // #endif
    var shading = scene_shading_normal(triangle, b1, b2);
    if all(shading == vec3<f32>(0.0)) {
        shading = geometric;
    }
    let base = shading;
    shading = scene_normal_mapped(triangle, b1, b2, shading, scene_materials[t.material].normal_texture,
                                  scene_materials[t.material].normal_scale, at);
    let mapped = any(shading != base);
    var valid = 1u;
    var back_face = 0u;
    if scene_dot(geometric, direction) > 0.0 {
        if (scene_materials[t.material].flags & SCENE_MATERIAL_DOUBLE_SIDED) == 0u {
            valid = 0u;
        }
        back_face = 1u;
        geometric = -geometric;
        shading = -shading;
    }
    if mapped {
        shading = scene_valid_reflection_normal(geometric, -direction, shading);
    }
    return SceneSurfacePoint(position, valid, geometric, back_face, shading);
}
