//! The scene on the GPU against furnace-scene and furnace-cpu's per-hit code: `scene.wgsl` runs
//! on the buffers of `furnace_gpu::scene::SceneBuffers`, the Rust on the `Scene`, on the same
//! random inputs.
//!
//! Scenes: an in-memory glTF written here (always run) whose four materials exercise every
//! path — sRGB and linear textures of odd sizes with random texels, all three wrap modes,
//! KHR_texture_transform, UVs far outside [0, 1], normal maps with generated and with file
//! tangents (handedness −1), emissive strength, KHR_materials_specular, MASK by texture and by
//! factor, BLEND, single- and double-sided; the built-in Cornell box (untextured); Khronos'
//! BoxTextured and DamagedHelmet (2048² textures) from `tests/data/scenes/`.
//!
//! Inputs: random (triangle, barycentrics, ray direction) — 10⁵ on the in-memory scene and on
//! DamagedHelmet — and random (material, UV) — 10⁵, UVs up to ±10⁴ plus non-finite ones.
//! Compared: `MaterialSample` fields, raw texture lookups of each slot, UV, position, geometric
//! and shading normals (interpolated and normal-mapped), tangents, the double-sided
//! orientation and the alpha test. Tolerances are derived per input (see [`texture_tolerance`]
//! and the comments at each comparison); the worst error against its tolerance is printed.
//!
//! The tolerances leave room for a driver that fuses multiply-adds: a software rasteriser without
//! FMA contraction gives values bit-identical to the CPU's except the texel coordinate of
//! transformed or far-out UVs (worst ratio to tolerance 0.29); a GPU driver that fuses them
//! reached a worst ratio of 0.48 (interpolated positions and UVs, 2 ULP against a 4 ULP bound).

use furnace_tests::Rng;
use furnace_tests::gltf::{base64, png};

use furnace_gpu::scene::{
    self, GpuMaterial, GpuScene, GpuSceneTriangle, GpuTextureRef, GpuVertex, SceneBuffers,
};
use furnace_gpu::{GpuContext, GpuError, wgsl};
use furnace_scene::{AlphaMode, Material, Scene, TextureRef, VertexAttributes, builtin, srgb_to_linear};
use furnace_tests::gpu::{self as kernel, test_context};
use glam::{Vec2, Vec3, Vec4};
use std::fmt::Write as _;

// ---------------------------------------------------------------------------------------------
// The in-memory glTF.

/// A random-texel image (fixed seed).
fn noise_png(width: u32, height: u32, seed: u64) -> Vec<u8> {
    png(width, height, |x, y| {
        let mut r = Rng(seed ^ ((u64::from(y) << 32) | u64::from(x)).wrapping_mul(0x2545_F491_4F6C_DD1D));
        let v = r.next_u64().to_le_bytes();
        [v[0], v[1], v[2], v[3]]
    })
}

/// One primitive: an `n × n` grid of quads on a wavy surface around `origin`, normals tilted
/// away from the true ones (so interpolation matters), UVs spanning `uv_lo..uv_hi`, and
/// optionally a TANGENT attribute with handedness `w`.
struct Sheet {
    origin: Vec3,
    uv_lo: Vec2,
    uv_hi: Vec2,
    tangent_w: Option<f32>,
    material: usize,
}

const GRID: usize = 12;

fn sheet_vertices(s: &Sheet, seed: u64) -> (Vec<f32>, Vec<f32>, Vec<f32>, Vec<f32>, Vec3, Vec3) {
    let mut rng = Rng(seed);
    let (mut p, mut n, mut uv, mut t) = (Vec::new(), Vec::new(), Vec::new(), Vec::new());
    let (mut lo, mut hi) = (Vec3::INFINITY, Vec3::NEG_INFINITY);
    for j in 0..=GRID {
        for i in 0..=GRID {
            let (a, b) = (i as f32 / GRID as f32, j as f32 / GRID as f32);
            let h = 0.3 * (3.0 * a).sin() * (2.0 * b).cos();
            let pos = s.origin + Vec3::new(2.0 * a, h, 2.0 * b);
            lo = lo.min(pos);
            hi = hi.max(pos);
            let dx = Vec3::new(2.0, 0.9 * (3.0 * a).cos() * (2.0 * b).cos() / 2.0, 0.0);
            let dz = Vec3::new(0.0, -0.6 * (3.0 * a).sin() * (2.0 * b).sin() / 2.0, 2.0);
            let normal = (dz.cross(dx).normalize() + 0.3 * rng.unit_vector()).normalize();
            p.extend(pos.to_array());
            n.extend(normal.to_array());
            uv.extend((s.uv_lo + (s.uv_hi - s.uv_lo) * Vec2::new(a, b)).to_array());
            let tan = (dx - normal * normal.dot(dx)).normalize();
            t.extend(tan.extend(s.tangent_w.unwrap_or(1.0)).to_array());
        }
    }
    (p, n, uv, t, lo, hi)
}

/// The binary buffer with its views and accessors, as JSON fragments.
#[derive(Default)]
struct Buf {
    bin: Vec<u8>,
    views: Vec<String>,
    accessors: Vec<String>,
}

impl Buf {
    /// Appends `bytes` as a view and an accessor of `count` `kind` elements; returns its index.
    fn accessor(&mut self, bytes: &[u8], component: u32, count: usize, kind: &str, extra: &str) -> usize {
        let offset = self.bin.len();
        self.bin.extend_from_slice(bytes);
        self.views.push(format!(r#"{{"buffer":0,"byteOffset":{offset},"byteLength":{}}}"#, bytes.len()));
        self.accessors.push(format!(
            r#"{{"bufferView":{},"componentType":{component},"count":{count},"type":"{kind}"{extra}}}"#,
            self.views.len() - 1
        ));
        self.accessors.len() - 1
    }
}

/// The in-memory scene's glTF JSON (one buffer and all images as data URIs).
fn procedural_gltf() -> String {
    let sheets = [
        Sheet {
            origin: Vec3::ZERO,
            uv_lo: Vec2::new(-1.7, -0.6),
            uv_hi: Vec2::new(2.6, 3.1),
            tangent_w: None,
            material: 0,
        },
        Sheet {
            origin: Vec3::new(3.0, 0.0, 0.0),
            uv_lo: Vec2::new(-0.4, 1.3),
            uv_hi: Vec2::new(1.4, -0.9),
            tangent_w: Some(-1.0),
            material: 1,
        },
        Sheet {
            origin: Vec3::new(0.0, 0.0, 3.0),
            uv_lo: Vec2::ZERO,
            uv_hi: Vec2::ONE,
            tangent_w: None,
            material: 2,
        },
        Sheet {
            origin: Vec3::new(3.0, 0.0, 3.0),
            uv_lo: Vec2::new(-5.0, -5.0),
            uv_hi: Vec2::new(5.0, 5.0),
            tangent_w: Some(1.0),
            material: 3,
        },
        Sheet {
            origin: Vec3::new(0.0, 1.0, 6.0),
            uv_lo: Vec2::new(0.0, 0.0),
            uv_hi: Vec2::new(1.0, 1.0),
            tangent_w: None,
            material: 4,
        },
    ];
    let mut buf = Buf::default();
    let mut meshes = Vec::new();
    let indices: Vec<u32> = (0..GRID)
        .flat_map(|j| {
            (0..GRID).flat_map(move |i| {
                let v = |a: usize, b: usize| ((GRID + 1) * b + a) as u32;
                [v(i, j), v(i, j + 1), v(i + 1, j + 1), v(i, j), v(i + 1, j + 1), v(i + 1, j)]
            })
        })
        .collect();
    let nv = (GRID + 1) * (GRID + 1);
    for (k, s) in sheets.iter().enumerate() {
        let (p, n, uv, t, lo, hi) = sheet_vertices(s, 77 + k as u64);
        let bytes = |v: &[f32]| v.iter().flat_map(|x| x.to_le_bytes()).collect::<Vec<u8>>();
        let mm = format!(r#","min":[{},{},{}],"max":[{},{},{}]"#, lo.x, lo.y, lo.z, hi.x, hi.y, hi.z);
        let pa = buf.accessor(&bytes(&p), 5126, nv, "VEC3", &mm);
        let na = buf.accessor(&bytes(&n), 5126, nv, "VEC3", "");
        let ua = buf.accessor(&bytes(&uv), 5126, nv, "VEC2", "");
        let mut attributes = format!(r#""POSITION":{pa},"NORMAL":{na},"TEXCOORD_0":{ua}"#);
        if s.tangent_w.is_some() {
            let ta = buf.accessor(&bytes(&t), 5126, nv, "VEC4", "");
            write!(attributes, r#","TANGENT":{ta}"#).unwrap();
        }
        let ib: Vec<u8> = indices.iter().flat_map(|i| i.to_le_bytes()).collect();
        let ia = buf.accessor(&ib, 5125, indices.len(), "SCALAR", "");
        meshes.push(format!(
            r#"{{"primitives":[{{"attributes":{{{attributes}}},"indices":{ia},"material":{}}}]}}"#,
            s.material
        ));
    }
    // Images: odd sizes, random texels (alpha too). Image 4 is a normal map (random, tilted).
    let images: Vec<String> = [(13, 7), (5, 9), (16, 16), (64, 32), (3, 1)]
        .iter()
        .enumerate()
        .map(|(k, &(w, h))| {
            format!(r#"{{"uri":"data:image/png;base64,{}"}}"#, base64(&noise_png(w, h, 1000 + k as u64)))
        })
        .collect();
    // Samplers: (REPEAT, MIRRORED), (CLAMP, REPEAT), (MIRRORED, CLAMP), (CLAMP, CLAMP).
    let samplers = r#"[{"wrapS":10497,"wrapT":33648},{"wrapS":33071,"wrapT":10497},{"wrapS":33648,"wrapT":33071},{"wrapS":33071,"wrapT":33071}]"#;
    // Textures: (image, sampler).
    let textures = [(0, 0), (1, 1), (2, 2), (3, 3), (0, 2), (4, 0), (2, 0)];
    let textures: Vec<String> =
        textures.iter().map(|(i, s)| format!(r#"{{"source":{i},"sampler":{s}}}"#)).collect();
    let transform = |off: [f32; 2], rot: f32, scale: [f32; 2]| {
        format!(
            r#","extensions":{{"KHR_texture_transform":{{"offset":[{},{}],"rotation":{rot},"scale":[{},{}]}}}}"#,
            off[0], off[1], scale[0], scale[1]
        )
    };
    let materials = [
        // 0: everything textured, transformed base colour, MASK by texture alpha, single-sided.
        format!(
            r#"{{"pbrMetallicRoughness":{{"baseColorFactor":[0.9,0.8,0.7,1.0],"baseColorTexture":{{"index":0{}}},"metallicFactor":0.6,"roughnessFactor":0.9,"metallicRoughnessTexture":{{"index":1}}}},"normalTexture":{{"index":2,"scale":0.6}},"emissiveTexture":{{"index":4{}}},"emissiveFactor":[1.0,0.5,0.25],"alphaMode":"MASK","alphaCutoff":0.45,"doubleSided":false,"extensions":{{"KHR_materials_emissive_strength":{{"emissiveStrength":4.0}},"KHR_materials_specular":{{"specularFactor":0.7,"specularColorFactor":[1.2,0.9,0.5]}}}}}}"#,
            transform([0.3, -0.2], 0.7, [1.5, 0.8]),
            transform([0.0, 0.5], -1.1, [2.0, 2.0])
        ),
        // 1: clamped base colour with a transform, file tangents (w = −1), strong normal map,
        //    BLEND (stochastic transparency by the texture's alpha), double-sided.
        format!(
            r#"{{"pbrMetallicRoughness":{{"baseColorTexture":{{"index":3{}}},"metallicFactor":0.1,"roughnessFactor":0.4}},"normalTexture":{{"index":5,"scale":1.3}},"alphaMode":"BLEND","doubleSided":true}}"#,
            transform([-0.25, 0.1], 2.0, [1.7, 0.6])
        ),
        // 2: untextured (the CPU's constant-material shortcut), emissive, single-sided.
        r#"{"pbrMetallicRoughness":{"baseColorFactor":[0.2,0.4,0.6,1.0],"metallicFactor":0.3,"roughnessFactor":0.6},"emissiveFactor":[0.1,0.2,0.3],"doubleSided":false}"#.to_string(),
        // 3: mirrored/clamped normal map only, file tangents (w = +1), MASK by factor alone
        //    (alpha 0.3 < 0.5: every hit rejected), double-sided.
        r#"{"pbrMetallicRoughness":{"baseColorFactor":[1.0,1.0,1.0,0.3],"metallicFactor":0.0,"roughnessFactor":0.5,"metallicRoughnessTexture":{"index":1}},"normalTexture":{"index":6},"alphaMode":"MASK","doubleSided":true}"#.to_string(),
        // 4: MASK with the default cutoff on a 3×1 base colour, emissive texture.
        r#"{"pbrMetallicRoughness":{"baseColorTexture":{"index":5},"metallicFactor":1.0,"roughnessFactor":0.2},"emissiveTexture":{"index":0},"emissiveFactor":[1.0,0.5,1.0],"alphaMode":"MASK","doubleSided":true,"extensions":{"KHR_materials_emissive_strength":{"emissiveStrength":2.5}}}"#.to_string(),
    ];
    let nodes: Vec<String> = (0..sheets.len()).map(|i| format!(r#"{{"mesh":{i}}}"#)).collect();
    let node_list: Vec<String> = (0..sheets.len()).map(|i| i.to_string()).collect();
    format!(
        r#"{{"asset":{{"version":"2.0"}},"extensionsUsed":["KHR_texture_transform","KHR_materials_specular","KHR_materials_emissive_strength"],"scene":0,"scenes":[{{"nodes":[{}]}}],"nodes":[{}],"meshes":[{}],"materials":[{}],"textures":[{}],"samplers":{samplers},"images":[{}],"accessors":[{}],"bufferViews":[{}],"buffers":[{{"byteLength":{},"uri":"data:application/octet-stream;base64,{}"}}]}}"#,
        node_list.join(","),
        nodes.join(","),
        meshes.join(","),
        materials.join(","),
        textures.join(","),
        images.join(","),
        buf.accessors.join(","),
        buf.views.join(","),
        buf.bin.len(),
        base64(&buf.bin)
    )
}

fn procedural_scene() -> Scene {
    let json = procedural_gltf();
    let scene =
        Scene::from_slice(json.as_bytes(), "scene_parity.gltf").unwrap_or_else(|e| panic!("{e}\n{json}"));
    assert!(scene.warnings.is_empty(), "{:?}", scene.warnings);
    assert!(!scene.geometry.tangents.is_empty() && !scene.geometry.uvs.is_empty());
    scene
}

/// A scene of `tests/data/scenes/`.
fn data_scene(p: &str) -> Scene {
    Scene::load(furnace_tests::data::scene(p)).unwrap_or_else(|e| panic!("{e}"))
}

// ---------------------------------------------------------------------------------------------
// The CPU side: furnace-scene's functions, composed as furnace-cpu's integrator composes them.

/// furnace-cpu's `Renderer::surface_point` (private there), from the same public functions:
/// `(position, geometric, shading)` or `None` on the back of a single-sided material; also the
/// length of the normal-mapped vector before normalisation and of the orthogonalised tangent
/// (the conditioning of the tolerance).
struct CpuSurface {
    point: Option<(Vec3, Vec3, Vec3)>,
    facing_dot: f32,
    perturbed_len: f32,
    tangent_perp_len: f32,
    cross_condition: f32,
    /// The shading normal before `valid_reflection_normal` bent it, where it did.
    unbent: Option<Vec3>,
}

fn cpu_surface_point(scene: &Scene, t: usize, b1: f32, b2: f32, uv: Vec2, direction: Vec3) -> CpuSurface {
    let g = &scene.geometry;
    let material = &scene.materials[g.triangle_materials[t].min(scene.materials.len() as u32 - 1) as usize];
    let [v0, v1, v2] = g.triangle(t).unwrap();
    let position = (1.0 - b1 - b2) * v0 + b1 * v1 + b2 * v2;
    let c = (v1 - v0).cross(v2 - v0);
    let cross_condition = (v1 - v0).length() * (v2 - v0).length() / c.length();
    // furnace-cpu's `geometric_normal` (private there).
    let mut geometric = match c.normalize_or_zero() {
        n if n != Vec3::ZERO || !c.is_finite() => n,
        _ => {
            let m = c.abs().max_element();
            if m > 0.0 { (c / m).normalize_or_zero() } else { Vec3::ZERO }
        }
    };
    let mut shading = g.shading_normal(t, b1, b2).filter(|n| *n != Vec3::ZERO).unwrap_or(geometric);
    let (mut perturbed_len, mut tangent_perp_len) = (1.0, 1.0);
    let base = shading;
    if let Some(normal_map) = &material.normal_texture
        && let Some(tangent) = g.tangent(t, b1, b2)
    {
        let m = normal_map.sample_bilinear(uv, &scene.textures, &scene.images).truncate();
        let m = (2.0 * m - Vec3::ONE) * Vec3::new(material.normal_scale, material.normal_scale, 1.0);
        let perp = tangent.truncate() - shading * shading.dot(tangent.truncate());
        tangent_perp_len = perp.length();
        let tn = perp.normalize_or_zero();
        if tn != Vec3::ZERO {
            let bn = tangent.w * shading.cross(tn);
            let v = m.x * tn + m.y * bn + m.z * shading;
            perturbed_len = v.length();
            shading = v.normalize_or(shading);
        }
    }
    let mapped = shading != base;
    let facing_dot = geometric.dot(direction);
    if facing_dot > 0.0 && material.double_sided {
        geometric = -geometric;
        shading = -shading;
    }
    let mut unbent = None;
    if mapped {
        let bent = furnace_scene::valid_reflection_normal(geometric, -direction, shading);
        if bent != shading {
            unbent = Some(shading);
        }
        shading = bent;
    }
    let point = (facing_dot <= 0.0 || material.double_sided).then_some((position, geometric, shading));
    CpuSurface { point, facing_dot, perturbed_len, tangent_perp_len, cross_condition, unbent }
}

/// furnace-cpu's `Renderer::alpha_passes`, and the alpha it tested.
fn cpu_alpha(scene: &Scene, material: &Material, uv: Vec2) -> (bool, f32) {
    let alpha = material.base_color_factor.w
        * material
            .base_color_texture
            .as_ref()
            .map_or(1.0, |t| t.sample_bilinear(uv, &scene.textures, &scene.images).w);
    (material.alpha_test(alpha), alpha)
}

/// Bound on |GPU − CPU| of one texture lookup (any channel) at the stored `uv`.
///
/// Decoding is exact (the GPU reads the CPU's tables) and texel selection agrees except where
/// a bilinear weight is ≈ 0 or 1, so the difference is the error of the weights times the
/// largest texel step (≤ 1), plus the lerps' rounding. The weights are the fraction of the texel
/// coordinate `u·n − ½`: the CPU forms it in f64 (exact), the GPU in f32 after an exact period
/// reduction, so it carries: the transform's rounding on the GPU (two products and two sums,
/// possibly fused: ≤ 2 ULP of the largest term, i.e. ≤ 2^-23·Σ|terms|), times `n`; the product
/// `u'·n` with u' ∈ [0, 2] and the subtraction of ½ (≤ 1 ULP of 2n, i.e. 2n·2^-24... taken
/// as n·2^-22 with margin). Three lerps of values ≤ 1 add ≤ 3·2^-23 (≈ 4e-7; 1e-6 stated).
fn texture_tolerance(scene: &Scene, r: &TextureRef, uv: Vec2) -> f32 {
    let tex = scene.textures[r.texture as usize];
    let img = &scene.images[tex.image as usize];
    let (sx, sy) = match &r.transform {
        Some(t) => {
            let m = t.matrix();
            (
                (m.x_axis.x * uv.x).abs() + (m.y_axis.x * uv.y).abs() + m.z_axis.x.abs(),
                (m.x_axis.y * uv.x).abs() + (m.y_axis.y * uv.y).abs() + m.z_axis.y.abs(),
            )
        }
        None => (0.0, 0.0),
    };
    let eps = 2f32.powi(-22);
    let ex = img.width as f32 * eps * (1.0 + sx);
    let ey = img.height as f32 * eps * (1.0 + sy);
    ex + ey + 1e-6
}

fn slot_tolerance(scene: &Scene, r: &Option<TextureRef>, uv: Vec2) -> f32 {
    r.as_ref().map_or(0.0, |r| texture_tolerance(scene, r, uv))
}

// ---------------------------------------------------------------------------------------------
// The GPU side: kernels over the scene buffers at bindings 3..8.

fn hit_kernel() -> String {
    wgsl::compose(&[
        kernel::PREAMBLE,
        &scene::bindings(0, 3),
        &all_of_scene_wgsl(),
        r#"
// Input per query: triangle, b1, b2, direction (6 words). Output: 36 words.
@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let i = invocation_index(gid, groups);
    if i >= params.x { return; }
    let tri = input[6u * i];
    let b1 = bitcast<f32>(input[6u * i + 1u]);
    let b2 = bitcast<f32>(input[6u * i + 2u]);
    let dir = vec3<f32>(bitcast<f32>(input[6u * i + 3u]), bitcast<f32>(input[6u * i + 4u]), bitcast<f32>(input[6u * i + 5u]));
    let mi = scene_triangle_material(tri);
    // As the integrator: the attributes the material reads.
    let at = scene_hit_attributes(mi, tri, b1, b2);
    let uv = at.uv0;
    let s = scene_surface_point(tri, b1, b2, at, dir);
    let m = scene_material_evaluate(mi, at);
    let n = scene_shading_normal(tri, b1, b2);
    let t = scene_tangent(tri, b1, b2);
    let o = 36u * i;
    let f = array<f32, 34>(
        uv.x, uv.y, s.position.x, s.position.y, s.position.z, bitcast<f32>(s.valid),
        s.geometric.x, s.geometric.y, s.geometric.z, s.shading.x, s.shading.y, s.shading.z,
        n.x, n.y, n.z, t.x, t.y, t.z, t.w,
        m.base_color.x, m.base_color.y, m.base_color.z, m.alpha, m.metallic, m.roughness,
        m.emission.x, m.emission.y, m.emission.z, m.specular_factor,
        m.specular_color.x, m.specular_color.y, m.specular_color.z,
        bitcast<f32>(u32(scene_alpha_passes(tri, b1, b2))), bitcast<f32>(mi));
    for (var k = 0u; k < 34u; k++) {
        output[o + k] = bitcast<u32>(f[k]);
    }
}
"#,
    ])
}

fn material_kernel() -> String {
    wgsl::compose(&[
        kernel::PREAMBLE,
        &scene::bindings(0, 3),
        &all_of_scene_wgsl(),
        r#"
// Input per query: material, u, v (3 words). Output: 32 words (MaterialSample, 4 raw slots).
@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let i = invocation_index(gid, groups);
    if i >= params.x { return; }
    let mi = input[3u * i];
    let uv = vec2<f32>(bitcast<f32>(input[3u * i + 1u]), bitcast<f32>(input[3u * i + 2u]));
    let m = scene_material_evaluate(mi, scene_attributes_of_uv(uv));
    let mat = scene_materials[mi];
    let a = scene_texture_sample(mat.base_color_texture, uv);
    let b = scene_texture_sample(mat.metallic_roughness_texture, uv);
    let c = scene_texture_sample(mat.normal_texture, uv);
    let d = scene_texture_sample(mat.emissive_texture, uv);
    let f = array<f32, 29>(
        m.base_color.x, m.base_color.y, m.base_color.z, m.alpha, m.metallic, m.roughness,
        m.emission.x, m.emission.y, m.emission.z, m.specular_factor,
        m.specular_color.x, m.specular_color.y, m.specular_color.z,
        a.x, a.y, a.z, a.w, b.x, b.y, b.z, b.w, c.x, c.y, c.z, c.w, d.x, d.y, d.z, d.w);
    for (var k = 0u; k < 29u; k++) {
        output[32u * i + k] = bitcast<u32>(f[k]);
    }
}
"#,
    ])
}

/// Worst error relative to its tolerance, and where.
#[derive(Default)]
struct Worst {
    compared: usize,
    identical: usize,
    ratio: f32,
    abs: f32,
    what: String,
    failures: Vec<String>,
}

impl Worst {
    fn check(&mut self, what: &str, query: usize, gpu: f32, cpu: f32, tol: f32) {
        self.compared += 1;
        if gpu.to_bits() == cpu.to_bits() {
            self.identical += 1;
        }
        let err = if gpu == cpu { 0.0 } else { (gpu - cpu).abs() };
        // NaN-safe: a NaN on either side fails.
        let ok = err <= tol;
        let ratio = if tol > 0.0 {
            err / tol
        } else if err == 0.0 {
            0.0
        } else {
            f32::INFINITY
        };
        self.abs = self.abs.max(err);
        if ratio > self.ratio || !ok {
            self.ratio = self.ratio.max(if ok { ratio } else { f32::INFINITY });
            self.what = format!("{what} (query {query}): GPU {gpu}, CPU {cpu}, tolerance {tol}");
        }
        if !ok && self.failures.len() < 20 {
            self.failures
                .push(format!("{what} (query {query}): GPU {gpu}, CPU {cpu}, |Δ| {err}, tolerance {tol}"));
        }
    }

    fn vec(&mut self, what: &str, query: usize, gpu: &[f32], cpu: &[f32], tol: f32) {
        for (k, (g, c)) in gpu.iter().zip(cpu).enumerate() {
            self.check(&format!("{what}[{k}]"), query, *g, *c, tol);
        }
    }

    fn finish(&self, label: &str) {
        println!(
            "{label}: {} values compared, {} bit-identical; worst |GPU − CPU| = {:.2e}, worst ratio to its \
             tolerance {:.3} ({})",
            self.compared, self.identical, self.abs, self.ratio, self.what
        );
        assert!(
            self.failures.is_empty(),
            "{label}: {} failures, first:\n{}",
            self.failures.len(),
            self.failures.join("\n")
        );
    }
}

fn f(words: &[u32], k: usize) -> f32 {
    f32::from_bits(words[k])
}

/// Ulp-scale tolerance of a barycentric interpolation (three products and two sums, possibly
/// fused): 4 ULP of the sum of the terms' magnitudes.
fn interp_tol(w: [f32; 3], a: [f32; 3]) -> f32 {
    4.0 * f32::EPSILON * (w[0].abs() * a[0].abs() + w[1].abs() * a[1].abs() + w[2].abs() * a[2].abs()) + 1e-30
}

/// Runs `n` random hits on `scene` and compares everything the integrator reads at a hit.
fn hit_parity(ctx: &GpuContext, scene: &Scene, label: &str, n: usize, seed: u64) {
    let buffers = SceneBuffers::new(scene, ctx.max_storage_binding()).unwrap();
    let g = &scene.geometry;
    let mut rng = Rng(seed);
    let mut input = Vec::with_capacity(6 * n);
    let mut queries = Vec::with_capacity(n);
    for q in 0..n {
        let t = rng.below(g.triangle_count() as u32);
        // Uniform in the triangle, with some vertices and edges exactly.
        let (mut b1, mut b2) = (rng.f32(), rng.f32());
        if b1 + b2 > 1.0 {
            (b1, b2) = (1.0 - b1, 1.0 - b2);
        }
        match q % 50 {
            0 => (b1, b2) = (0.0, 0.0),
            1 => (b1, b2) = (1.0, 0.0),
            2 => b2 = 1.0 - b1,
            _ => {}
        }
        let d = rng.unit_vector();
        input.extend([t, b1.to_bits(), b2.to_bits(), d.x.to_bits(), d.y.to_bits(), d.z.to_bits()]);
        queries.push((t as usize, b1, b2, d));
    }
    let out = kernel::run_with(ctx, &hit_kernel(), &input, &buffers.extra(), 36 * n, n as u32).unwrap();
    let mut worst = Worst::default();
    let (mut near_grazing, mut alpha_near_cutoff, mut alpha_rejected, mut bent) = (0, 0, 0, 0);
    let last = scene.materials.len() as u32 - 1;
    for (q, &(t, b1, b2, dir)) in queries.iter().enumerate() {
        let o = &out[36 * q..36 * q + 36];
        let mi = g.triangle_materials[t].min(last);
        assert_eq!(o[33], mi, "{label}: material of triangle {t}");
        let material = &scene.materials[mi as usize];
        let w = [1.0 - b1 - b2, b1, b2];
        let [i0, i1, i2] = g.triangles[t].map(|i| i as usize);
        // UV: as the integrator, only for textured materials.
        let uv = if material.uses_textures() { g.uv(t, b1, b2) } else { Vec2::ZERO };
        if material.uses_textures() {
            for k in 0..2 {
                let a = [g.uvs[i0][k], g.uvs[i1][k], g.uvs[i2][k]];
                worst.check("uv", q, f(o, k), uv[k], interp_tol(w, a));
            }
        }
        // The interpolated UV differs by `uv_err` (≤ interp_tol): texture lookups move by at
        // most uv_err·n on top of their own bound; bounded by doubling the transform term.
        let uv_slack = |r: &Option<TextureRef>| {
            r.as_ref().map_or(0.0, |r| {
                let img = &scene.images[scene.textures[r.texture as usize].image as usize];
                let s = r.transform.map_or(1.0, |t| t.scale.abs().max_element() + 1.0);
                8.0 * f32::EPSILON * (uv.abs().max_element() + 1.0) * s * img.width.max(img.height) as f32
            })
        };
        let tex_tol = |r: &Option<TextureRef>| slot_tolerance(scene, r, uv) + uv_slack(r);
        // MaterialSample: factor × texture, so the texture bound times the factor (plus 1 ULP of
        // the product).
        let ms = material.evaluate(&VertexAttributes::from_uv(uv), &scene.textures, &scene.images);
        let tb = tex_tol(&material.base_color_texture);
        let tmr = tex_tol(&material.metallic_roughness_texture);
        let te = tex_tol(&material.emissive_texture);
        let bf = material.base_color_factor;
        for k in 0..3 {
            worst.check("base_color", q, f(o, 19 + k), ms.base_color[k], bf[k].abs() * tb + 1e-7);
            worst.check("emission", q, f(o, 25 + k), ms.emission[k], material.emissive[k].abs() * te + 1e-7);
            worst.check("specular_color", q, f(o, 29 + k), ms.specular_color[k], 0.0);
        }
        worst.check("alpha", q, f(o, 22), ms.alpha, bf.w.abs() * tb + 1e-7);
        worst.check("metallic", q, f(o, 23), ms.metallic, material.metallic_factor.abs() * tmr + 1e-7);
        worst.check("roughness", q, f(o, 24), ms.roughness, material.roughness_factor.abs() * tmr + 1e-7);
        worst.check("specular_factor", q, f(o, 28), ms.specular_factor, 0.0);
        // Alpha test: the same decision unless the CPU's alpha is within the alpha tolerance of
        // the cutoff (then either is right to float rounding).
        let (pass, alpha) = cpu_alpha(scene, material, g.uv(t, b1, b2));
        let gpu_pass = o[32] != 0;
        if !pass {
            alpha_rejected += 1;
        }
        if let AlphaMode::Mask { cutoff } = material.alpha_mode
            && (alpha - cutoff).abs() <= bf.w.abs() * tb + 1e-7
        {
            alpha_near_cutoff += 1;
        } else {
            assert_eq!(gpu_pass, pass, "{label}: alpha test of query {q} (alpha {alpha})");
        }
        // Interpolated shading normal: oct decode (division, sqrt: a few ULP per component,
        // 16-bit inputs exact), interpolation and normalisation (a few ULP): 2e-6 per component
        // of a unit vector ≈ 16 ULP at 1.
        let n_cpu = g.shading_normal(t, b1, b2).unwrap();
        worst.vec("shading normal", q, &[f(o, 12), f(o, 13), f(o, 14)], &n_cpu.to_array(), 2e-6);
        if let Some(tan) = g.tangent(t, b1, b2) {
            // snorm16 decode and the same normalisation: as the normal.
            worst.vec("tangent", q, &[f(o, 15), f(o, 16), f(o, 17), f(o, 18)], &tan.to_array(), 2e-6);
        }
        let cpu = cpu_surface_point(scene, t, b1, b2, uv, dir);
        // Position: barycentric interpolation of the vertices.
        let p_cpu = (1.0 - b1 - b2) * g.positions[i0] + b1 * g.positions[i1] + b2 * g.positions[i2];
        for k in 0..3 {
            let a = [g.positions[i0][k], g.positions[i1][k], g.positions[i2][k]];
            worst.check("position", q, f(o, 2 + k), p_cpu[k], interp_tol(w, a));
        }
        // Orientation: the GPU may decide the other side only where dot(geometric, direction)
        // is within its rounding (the geometric normal's error, below, times |direction| = 1).
        let geo_tol = 4e-7 * cpu.cross_condition + 1e-6;
        if cpu.facing_dot.abs() <= geo_tol {
            near_grazing += 1;
            continue;
        }
        let valid = o[5] != 0;
        assert_eq!(valid, cpu.point.is_some(), "{label}: surface validity of query {q}");
        let Some((_, geometric, shading)) = cpu.point else { continue };
        // Geometric normal: the cross product of two edges cancels when they are nearly
        // parallel: its error is a few ULP of |e1|·|e2|, relative to |e1 × e2|.
        worst.vec("geometric", q, &[f(o, 6), f(o, 7), f(o, 8)], &geometric.to_array(), geo_tol);
        // Shading normal after the normal map: the texel error (tn) scaled by 2·scale, divided
        // by the perturbed vector's length; the tangent's orthogonalisation loses precision as
        // 1/|T − N(N·T)|.
        let mut sh_tol = 4e-6 + 2e-7 / cpu.tangent_perp_len;
        if material.normal_texture.is_some() && !g.tangents.is_empty() {
            let tn = tex_tol(&material.normal_texture);
            sh_tol += 4.0 * material.normal_scale.abs().max(1.0) * tn / cpu.perturbed_len;
        }
        // Where the normal was bent (the viewer below it), the bend's output moves with its
        // inputs by up to 1/√(discriminant): the tolerance adds the spread of the bent normal
        // over inputs moved by their own tolerances along each axis, doubled (second order).
        if let Some(n) = cpu.unbent {
            let spread = |ng: Vec3, n: Vec3| {
                (furnace_scene::valid_reflection_normal(ng.normalize(), -dir, n.normalize()) - shading)
                    .abs()
                    .max_element()
            };
            let mut worst_move = 0.0f32;
            for axis in [Vec3::X, Vec3::Y, Vec3::Z, -Vec3::X, -Vec3::Y, -Vec3::Z] {
                worst_move = worst_move.max(spread(geometric, n + sh_tol * axis));
                worst_move = worst_move.max(spread(geometric + geo_tol * axis, n));
            }
            sh_tol += 2.0 * worst_move;
            bent += 1;
        }
        worst.vec("shading", q, &[f(o, 9), f(o, 10), f(o, 11)], &shading.to_array(), sh_tol);
    }
    println!(
        "{label}: {n} hits, {near_grazing} within rounding of grazing (orientation not compared), \
         {alpha_near_cutoff} alphas within tolerance of the cutoff, {alpha_rejected} rejected by the alpha test, \
         {bent} normal-mapped normals bent for the viewer"
    );
    assert!(near_grazing * 1000 < n, "{label}: too many grazing queries: {near_grazing}");
    worst.finish(label);
}

/// Runs `n` random (material, UV) lookups, with UVs from texel centres to ±10⁴ and non-finite.
fn material_parity(ctx: &GpuContext, shader: &str, scene: &Scene, n: usize, seed: u64) -> Worst {
    let buffers = SceneBuffers::new(scene, ctx.max_storage_binding()).unwrap();
    let mut rng = Rng(seed);
    let mut input = Vec::with_capacity(3 * n);
    let mut queries = Vec::with_capacity(n);
    // Finite UVs stop at 10⁶: past |u·n| ≈ 2⁵² the CPU's f64 texel coordinate loses the half
    // texel, and past 10¹⁵ it clamps the texel index (`sample_bilinear`), while the GPU's period
    // reduction stays exact: the two differ there by design (and no mesh has such UVs).
    let special = [f32::NAN, f32::INFINITY, f32::NEG_INFINITY, 0.0, -0.0, 1.0, -1.0, 0.5, 2.0, 1e6, -1e6];
    for q in 0..n {
        let m = rng.below(scene.materials.len() as u32);
        let mut uv = match q % 10 {
            0..=5 => Vec2::new(rng.range(-3.0, 3.0), rng.range(-3.0, 3.0)),
            6 => Vec2::new(rng.range(-1e4, 1e4), rng.range(-1e4, 1e4)),
            7 => Vec2::new(rng.f32(), rng.f32()),
            // Texel centres and edges of a 2^k grid.
            8 => {
                let k = 1 << rng.below(7);
                Vec2::new(
                    rng.below(3 * k) as f32 / k as f32 - 1.0,
                    (rng.below(4 * k) as f32 + 0.5) / k as f32 - 2.0,
                )
            }
            _ => Vec2::new(rng.range(-2.0, 2.0), rng.range(-2.0, 2.0)),
        };
        if q % 97 == 0 {
            uv.x = special[rng.below(special.len() as u32) as usize];
        }
        if q % 89 == 0 {
            uv.y = special[rng.below(special.len() as u32) as usize];
        }
        input.extend([m, uv.x.to_bits(), uv.y.to_bits()]);
        queries.push((m as usize, uv));
    }
    let out = kernel::run_with(ctx, shader, &input, &buffers.extra(), 32 * n, n as u32).unwrap();
    let mut worst = Worst::default();
    for (q, &(mi, uv)) in queries.iter().enumerate() {
        let o = &out[32 * q..32 * q + 32];
        let material = &scene.materials[mi];
        let ms = material.evaluate(&VertexAttributes::from_uv(uv), &scene.textures, &scene.images);
        // Without a finite UV both sides sample at (0, 0): the bound at (0, 0).
        let tuv = if uv.is_finite() { uv } else { Vec2::ZERO };
        let slots = [
            &material.base_color_texture,
            &material.metallic_roughness_texture,
            &material.normal_texture,
            &material.emissive_texture,
        ];
        for (s, slot) in slots.iter().enumerate() {
            let has_slot = slot.is_some() && (s != 2 || !scene.geometry.tangents.is_empty());
            let cpu = if has_slot {
                slot.as_ref().unwrap().sample_bilinear(uv, &scene.textures, &scene.images)
            } else {
                Vec4::ONE
            };
            let tol = if has_slot {
                // The transformed UV of a huge input is large: its f32 rounding on the GPU is in
                // the bound's transform term.
                slot_tolerance(scene, slot, tuv)
            } else {
                0.0
            };
            let gpu = [f(o, 13 + 4 * s), f(o, 14 + 4 * s), f(o, 15 + 4 * s), f(o, 16 + 4 * s)];
            worst.vec(&format!("slot {s} of material {mi} at {uv}"), q, &gpu, &cpu.to_array(), tol);
        }
        let tb = slot_tolerance(scene, &material.base_color_texture, tuv);
        let tmr = slot_tolerance(scene, &material.metallic_roughness_texture, tuv);
        let te = slot_tolerance(scene, &material.emissive_texture, tuv);
        let bf = material.base_color_factor;
        for k in 0..3 {
            worst.check("base_color", q, f(o, k), ms.base_color[k], bf[k].abs() * tb + 1e-7);
            worst.check("emission", q, f(o, 6 + k), ms.emission[k], material.emissive[k].abs() * te + 1e-7);
            worst.check("specular_color", q, f(o, 10 + k), ms.specular_color[k], 0.0);
        }
        worst.check("alpha", q, f(o, 3), ms.alpha, bf.w.abs() * tb + 1e-7);
        worst.check("metallic", q, f(o, 4), ms.metallic, material.metallic_factor.abs() * tmr + 1e-7);
        worst.check("roughness", q, f(o, 5), ms.roughness, material.roughness_factor.abs() * tmr + 1e-7);
        worst.check("specular_factor", q, f(o, 9), ms.specular_factor, 0.0);
    }
    worst
}

// ---------------------------------------------------------------------------------------------
// Tests.

#[test]
fn procedural_scene_hits_and_materials_match_the_cpu() {
    let Some(ctx) = test_context() else { return };
    let scene = procedural_scene();
    let b = SceneBuffers::new(&scene, u64::MAX).unwrap();
    println!(
        "procedural: {} triangles, {} images stored, {:.1} bytes/triangle (geometry), {} bytes in all",
        b.triangles.len(),
        b.image_count,
        b.bytes_per_triangle(),
        b.bytes()
    );
    hit_parity(&ctx, &scene, "procedural hits", 100_000, 1);
    material_parity(&ctx, &material_kernel(), &scene, 100_000, 2).finish("procedural materials (10^5)");
}

#[test]
fn textured_sample_scenes_match_the_cpu() {
    let Some(ctx) = test_context() else { return };
    {
        let scene = data_scene("BoxTextured/glTF/BoxTextured.gltf");
        hit_parity(&ctx, &scene, "BoxTextured hits", 20_000, 3);
        material_parity(&ctx, &material_kernel(), &scene, 20_000, 4).finish("BoxTextured materials");
    }
    {
        let scene = data_scene("DamagedHelmet/glTF-Binary/DamagedHelmet.glb");
        let b = SceneBuffers::new(&scene, ctx.max_storage_binding()).unwrap();
        println!(
            "DamagedHelmet: {} triangles, {:.1} bytes/triangle (geometry), {} images, {:.1} MiB in all",
            b.triangles.len(),
            b.bytes_per_triangle(),
            b.image_count,
            b.bytes() as f64 / (1 << 20) as f64
        );
        hit_parity(&ctx, &scene, "DamagedHelmet hits", 100_000, 5);
    }
}

/// The comparison can fail: texel centres a quarter texel off, or the sRGB table swapped for
/// the linear one, are caught.
#[test]
fn mutated_lookups_are_caught() {
    let Some(ctx) = test_context() else { return };
    let scene = procedural_scene();
    let good = material_kernel();
    for (from, to) in [
        ("* f32(t.width) - 0.5;", "* f32(t.width) - 0.25;"),
        ("select(SCENE_LINEAR_TABLE, SCENE_SRGB_TABLE,", "select(SCENE_SRGB_TABLE, SCENE_LINEAR_TABLE,"),
        ("return u - 2.0 * floor(0.5 * u);", "return u - floor(u);"),
    ] {
        assert_eq!(good.matches(from).count(), 1, "{from}");
        let worst = material_parity(&ctx, &good.replace(from, to), &scene, 10_000, 7);
        println!("mutation `{to}`: {} failures", worst.failures.len());
        assert!(!worst.failures.is_empty(), "`{from}` → `{to}` was not detected");
    }
}

#[test]
fn cornell_box_uploads_untextured_and_matches() {
    let Some(ctx) = test_context() else { return };
    let scene = builtin::cornell_box().unwrap();
    let packed = SceneBuffers::new(&scene, ctx.max_storage_binding()).unwrap();
    // Untextured: no UVs, tangents or texels beyond the tables; 16 B per triangle + 16 B per
    // vertex.
    assert!(packed.attributes.is_empty() && packed.tangents.is_empty());
    assert_eq!(packed.texels.len(), scene::TABLE_WORDS as usize);
    let gpu = GpuScene::upload(&ctx, &scene).unwrap();
    println!(
        "cbox: {} triangles, {} vertices, {:.1} bytes/triangle (geometry), {} bytes in all",
        gpu.triangle_count,
        scene.geometry.positions.len(),
        gpu.bytes_per_triangle(),
        gpu.bytes
    );
    // The device holds exactly the packed words.
    for (k, words) in packed.extra().iter().enumerate() {
        let back = furnace_gpu::film::read_buffer(&ctx, &gpu.buffers[k]).unwrap();
        assert_eq!(back.as_slice(), *words, "buffer {k}");
    }
    assert_eq!(GpuScene::layout_entries(3).len(), scene::BINDING_COUNT as usize);
    assert_eq!(gpu.bind_entries(3)[5].binding, 8);
    hit_parity(&ctx, &scene, "cbox hits", 20_000, 6);
}

#[test]
fn over_limit_scenes_are_too_large_not_a_panic() {
    let scene = procedural_scene();
    // Three scenes, each with a different largest buffer; a limit one byte below its size: the
    // error names that buffer, its size and the limit.
    let few_triangles = {
        let mut s = scene.clone();
        s.geometry.triangles.truncate(4);
        s.geometry.triangle_materials.truncate(4);
        s
    };
    let big_image = {
        let mut s = scene.clone();
        s.images[3] = furnace_scene::Image { width: 300, height: 200, texels: vec![[7, 8, 9, 10]; 60_000] };
        s
    };
    for (scene, what) in [(&scene, "triangle"), (&few_triangles, "vertex"), (&big_image, "texel")] {
        let b = SceneBuffers::new(scene, u64::MAX).unwrap();
        let bytes = match what {
            "triangle" => b.triangles.len() * 16,
            "vertex" => b.vertices.len() * 16,
            _ => b.texels.len() * 4,
        } as u64;
        let limit = bytes - 1;
        match SceneBuffers::new(scene, limit) {
            Err(GpuError::TooLarge { what: w, bytes: got, limit: l }) => {
                assert!(w.contains(what), "limit {limit}: expected the {what} buffer, got: {w}");
                assert_eq!((got, l), (bytes, limit));
                println!("{}", GpuError::TooLarge { what: w, bytes: got, limit: l });
            }
            other => panic!("limit {limit}: expected TooLarge for the {what} buffer, got {other:?}"),
        }
        assert!(SceneBuffers::new(scene, bytes).is_ok(), "{what}: fits at exactly its size");
    }
}

#[test]
fn only_what_shading_reads_is_stored() {
    let scene = procedural_scene();
    let b = SceneBuffers::new(&scene, u64::MAX).unwrap();
    // Five images in the file, all used: stored once each, however many slots use them.
    assert_eq!(b.image_count, 5);
    let texels: usize = scene.images.iter().map(|i| i.texels.len()).sum();
    assert_eq!(b.texels.len(), scene::TABLE_WORDS as usize + texels);
    // Without the normal maps: no tangents, and the normal-map-only image is not stored.
    let mut plain = scene.clone();
    for m in &mut plain.materials {
        m.normal_texture = None;
    }
    plain.geometry.tangents.clear();
    let p = SceneBuffers::new(&plain, u64::MAX).unwrap();
    assert!(p.tangents.is_empty());
    assert_eq!(p.image_count, 4, "image 2 is used by normal maps (and material 3's MR) only");
    // Untextured: no UVs.
    let cbox = SceneBuffers::new(&builtin::cornell_box().unwrap(), u64::MAX).unwrap();
    assert!(cbox.attributes.is_empty());
    assert_eq!(cbox.geometry_bytes(), 16 * (cbox.triangles.len() + cbox.vertices.len()) as u64);
}

#[test]
fn srgb_decode_and_octahedral_normals_match() {
    let Some(ctx) = test_context() else { return };
    let src = wgsl::compose(&[
        kernel::PREAMBLE,
        &scene::bindings(0, 3),
        &all_of_scene_wgsl(),
        r#"
@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let i = invocation_index(gid, groups);
    if i >= params.x { return; }
    output[4u * i] = bitcast<u32>(scene_srgb_to_linear(bitcast<f32>(input[i])));
    let n = scene_oct_decode(input[i]);
    output[4u * i + 1u] = bitcast<u32>(n.x);
    output[4u * i + 2u] = bitcast<u32>(n.y);
    output[4u * i + 3u] = bitcast<u32>(n.z);
}
"#,
    ]);
    // Inputs read both as a float in [0, 1] (sRGB) and as an octahedral code (every 16-bit
    // pattern pair is a valid code).
    let mut rng = Rng(9);
    let mut input: Vec<u32> = (0..=255u32).map(|i| (i as f32 / 255.0).to_bits()).collect();
    input.extend((0..100_000).map(|_| rng.f32().to_bits()));
    input.extend((0..50_000).map(|_| rng.next_u64() as u32));
    let buffers = SceneBuffers::new(&builtin::cornell_box().unwrap(), u64::MAX).unwrap();
    let n = input.len();
    let out = kernel::run_with(&ctx, &src, &input, &buffers.extra(), 4 * n, n as u32).unwrap();
    let (mut worst_srgb, mut worst_oct) = (0f32, 0f32);
    for (i, &w) in input.iter().enumerate() {
        let c = f32::from_bits(w);
        if (0.0..=1.0).contains(&c) {
            // pow on the GPU (exp2 ∘ log2, a few ULP) against powf (≤ 1 ULP): relative 2^-19 ≈
            // 1.9e-6, plus 1e-9 absolute near 0 (the linear segment divides: ≤ 2.5 ULP).
            let (gpu, cpu) = (f32::from_bits(out[4 * i]), srgb_to_linear(c));
            let err = (gpu - cpu).abs();
            worst_srgb = worst_srgb.max(err / (cpu * 2f32.powi(-19) + 1e-9));
            assert!(err <= cpu * 2f32.powi(-19) + 1e-9, "srgb_to_linear({c}): GPU {gpu}, CPU {cpu}");
        }
        let cpu = furnace_scene::oct_decode(w);
        let gpu = Vec3::new(
            f32::from_bits(out[4 * i + 1]),
            f32::from_bits(out[4 * i + 2]),
            f32::from_bits(out[4 * i + 3]),
        );
        // Two divisions by 32767 (≤ 2.5 ULP each in WGSL), a sqrt and a reciprocal: 1e-6 per
        // component of a unit vector (≈ 8 ULP at 1).
        let err = (gpu - cpu).abs().max_element();
        worst_oct = worst_oct.max(err / 1e-6);
        assert!(err <= 1e-6, "oct_decode({w:#x}): GPU {gpu}, CPU {cpu}");
    }
    println!("srgb_to_linear worst error / tolerance {worst_srgb:.3}; oct_decode {worst_oct:.3}");
}

/// Every struct shared with the WGSL (generated from the Rust), by naga reflection against the
/// Rust layout.
/// The scene module with every feature composed (vertex colours and UV sets read).
fn all_of_scene_wgsl() -> String {
    wgsl::select(wgsl::SCENE, |name| name != "INSTANCES")
}

#[test]
fn shared_structs_match_the_wgsl() {
    let src = wgsl::compose(&[&scene::bindings(0, 0), &all_of_scene_wgsl()]);
    furnace_tests::layout::assert_gpu_struct::<GpuSceneTriangle>(&src);
    furnace_tests::layout::assert_gpu_struct::<GpuVertex>(&src);
    furnace_tests::layout::assert_gpu_struct::<GpuTextureRef>(&src);
    furnace_tests::layout::assert_gpu_struct::<GpuMaterial>(&src);
}

// ---------------------------------------------------------------------------------------------
// The light BVH: light_bvh.wgsl against furnace_scene::LightBvh.

/// One case per invocation: point (3), receiving side (3), `u`, item — 8 words; out: the
/// sampled item and its pmf, the pmf of the given item along its path, the root's importance.
fn light_bvh_kernel(base: usize) -> String {
    let body = format!(
        r#"
@group(0) @binding(3) var<storage, read> emitters: array<vec4<u32>>;
const BASE: u32 = {base}u;
@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {{
    let i = invocation_index(gid, groups);
    if i >= params.x {{ return; }}
    let r = 8u * i;
    let p = vec3<f32>(bitcast<f32>(input[r]), bitcast<f32>(input[r + 1u]), bitcast<f32>(input[r + 2u]));
    let n = vec3<f32>(bitcast<f32>(input[r + 3u]), bitcast<f32>(input[r + 4u]), bitcast<f32>(input[r + 5u]));
    let u = bitcast<f32>(input[r + 6u]);
    let item = input[r + 7u];
    let s = light_bvh_sample(BASE, p, n, u);
    output[4u * i] = s.item;
    output[4u * i + 1u] = bitcast<u32>(s.pmf);
    output[4u * i + 2u] = bitcast<u32>(light_bvh_pmf(BASE, emitters[item].yz, p, n));
    output[4u * i + 3u] = bitcast<u32>(light_bvh_importance(light_bvh_node(BASE, 0u), p, n));
}}
"#
    );
    wgsl::compose(&[
        kernel::PREAMBLE,
        &furnace_gpu::integrator::light_bvh_consts_wgsl(),
        wgsl::LIGHT_BVH,
        &body,
    ])
}

/// The light BVH of the 64-emitter box (7 levels) and of DamagedHelmet's 15 452 emissive
/// triangles (deeper, uneven), at 2·10⁴ random points, receiving sides and `u` each, from the
/// scene's bounds widened by half their size (inside and outside every node).
///
/// Tolerances: the importance is the same f32 formula, its WGSL division and `sqrt` allowed
/// 2.5 ulp (WGSL's bound) — a few 10⁻⁷ relative, bound at 10⁻⁵. A pmf is a product of one
/// ratio per level: 10⁻⁴ relative holds 30 levels of that error with room. The descent compares
/// `u` with a ratio, so a `u` within rounding of a boundary may take the other child: at most
/// 0.1 % of choices may differ (lavapipe: none).
#[test]
fn light_bvh_matches_the_cpu() {
    let Some(ctx) = test_context() else { return };
    for path in
        ["references/lights/cbox_many_lights.gltf", "scenes/DamagedHelmet/glTF-Binary/DamagedHelmet.glb"]
    {
        let scene = Scene::load(furnace_tests::data::data_dir().join(path)).unwrap();
        let emitters = furnace_scene::Emitters::new(&scene).unwrap();
        let bvh = emitters.light_bvh(&scene);
        let words = furnace_gpu::integrator::light_bvh_words(&emitters, &bvh);
        let (lo, hi) = scene.geometry.bounds();
        let (centre, size) = ((lo + hi) / 2.0, hi - lo);
        let mut rng = Rng(0x11_9b7);
        let n = 20_000;
        let mut input = Vec::with_capacity(8 * n);
        let mut cases = Vec::with_capacity(n);
        for _ in 0..n {
            let p = centre + size * Vec3::new(rng.f32() - 0.5, rng.f32() - 0.5, rng.f32() - 0.5) * 1.5;
            let normal = rng.unit_vector();
            let u = rng.f32();
            let item = (rng.u32() as usize) % emitters.len();
            input.extend(p.to_array().map(f32::to_bits));
            input.extend(normal.to_array().map(f32::to_bits));
            input.extend([u.to_bits(), item as u32]);
            cases.push((p, normal, u, item));
        }
        let got =
            kernel::run_with(&ctx, &light_bvh_kernel(emitters.len()), &input, &[&words], 4 * n, n as u32)
                .unwrap();
        let rel = |a: f32, b: f32| if a == b { 0.0 } else { (a - b).abs() / a.abs().max(b.abs()) };
        let (mut imp_err, mut pmf_err, mut sample_err, mut differ, mut found) = (0f32, 0f32, 0f32, 0, 0);
        let mut worst = String::new();
        for (k, &(p, normal, u, item)) in cases.iter().enumerate() {
            let g = &got[4 * k..4 * k + 4];
            let root = bvh.nodes()[0].bounds.importance(p, normal);
            imp_err = imp_err.max(rel(root, f32::from_bits(g[3])));
            let e = rel(bvh.pmf(p, normal, item), f32::from_bits(g[2]));
            if e > pmf_err {
                worst = format!(
                    "pmf of item {item} at {p}, n {normal}: rust {} wgsl {}",
                    bvh.pmf(p, normal, item),
                    f32::from_bits(g[2])
                );
            }
            pmf_err = pmf_err.max(e);
            let wgsl_pmf = f32::from_bits(g[1]);
            match bvh.sample(p, normal, u) {
                Some((i, pmf)) if i as u32 == g[0] && wgsl_pmf > 0.0 => {
                    sample_err = sample_err.max(rel(pmf, wgsl_pmf));
                    found += 1;
                }
                None if wgsl_pmf == 0.0 => {}
                _ => differ += 1,
            }
        }
        eprintln!(
            "{path}: {} emitters, depth {}: importance {imp_err:e}, pmf {pmf_err:e} ({worst}), sampled pmf \
             {sample_err:e}, {found} sampled, {differ} choices differ",
            emitters.len(),
            bvh.depth()
        );
        assert!(imp_err <= 1e-5, "{path}: root importance differs by {imp_err:e}");
        assert!(pmf_err <= 1e-4, "{path}: pmf differs by {pmf_err:e}: {worst}");
        assert!(sample_err <= 1e-4, "{path}: sampled pmf differs by {sample_err:e}");
        assert!(differ * 1000 <= n, "{path}: {differ} of {n} choices differ");
        assert!(found * 2 > n, "{path}: only {found} of {n} points could sample a light");
    }
}

/// A kernel over `environment.wgsl` (its sampling half composed): per case a world direction and
/// a uniform pair in; out the radiance seen along the direction, the sample's direction, pdf
/// and radiance, and the pdf of the input direction.
fn environment_kernel(env: &furnace_scene::Environment) -> String {
    let (c, s) = env.rotation_cos_sin();
    let body = format!(
        r#"
@group(0) @binding(3) var<storage, read> environment: array<f32>;
@group(0) @binding(4) var<storage, read> environment_cdf: array<f32>;
@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {{
    let i = invocation_index(gid, groups);
    if i >= params.x {{ return; }}
    let env = EnvMap({w}u, {h}u, bitcast<f32>({k}u), bitcast<f32>({c}u), bitcast<f32>({s}u));
    let r = 5u * i;
    let d = vec3<f32>(bitcast<f32>(input[r]), bitcast<f32>(input[r + 1u]), bitcast<f32>(input[r + 2u]));
    let u = vec2<f32>(bitcast<f32>(input[r + 3u]), bitcast<f32>(input[r + 4u]));
    let seen = env_radiance(env, d);
    let smp = env_sample(env, u);
    let o = 11u * i;
    output[o] = bitcast<u32>(seen.x);
    output[o + 1u] = bitcast<u32>(seen.y);
    output[o + 2u] = bitcast<u32>(seen.z);
    output[o + 3u] = bitcast<u32>(smp.direction.x);
    output[o + 4u] = bitcast<u32>(smp.direction.y);
    output[o + 5u] = bitcast<u32>(smp.direction.z);
    output[o + 6u] = bitcast<u32>(smp.pdf);
    output[o + 7u] = bitcast<u32>(smp.radiance.x);
    output[o + 8u] = bitcast<u32>(smp.radiance.y);
    output[o + 9u] = bitcast<u32>(smp.radiance.z);
    output[o + 10u] = bitcast<u32>(env_pdf(env, d));
}}
"#,
        w = env.map.width(),
        h = env.map.height(),
        k = env.intensity.to_bits(),
        c = c.to_bits(),
        s = s.to_bits(),
    );
    let module = wgsl::select(wgsl::ENVIRONMENT, |name| name == "SAMPLES_ENVIRONMENT");
    wgsl::compose(&[kernel::PREAMBLE, &module, &body])
}

/// The environment twins on maps of 1 × 1, 7 × 5 (odd, not 2:1), 64 × 2 (rows far wider than
/// tall), a random 16 × 8 rotated 37°, and the reference's 512 × 256 sky with its 1° sun, at
/// 2·10⁴ random directions and uniform pairs each (directions include the −Z seam and points
/// 10⁻⁴ from the poles; exactly at a pole the lookup's u is atan2(0, 0), which WGSL leaves
/// undefined: a set of measure zero).
///
/// Tolerances: the lookup's `atan2` and `acos` are the GPU's (WGSL bounds them to a few ulp of
/// the angle; a texel is 2π/W of it), then the same bilinear arithmetic: a shifted position
/// moves the value by at most (ulp × W) × the largest neighbour difference, relative 10⁻³ of
/// the map's maximum at 512 columns. The sampled directions come from the same CDF cells (the
/// search compares the same f32 values) and the GPU's `sin`/`cos`: 10⁻⁵ absolute. pdfs are the
/// same cell's CDF differences over the GPU's `sqrt`: 10⁻⁴ relative. A direction's pdf may be a
/// neighbouring cell's where the GPU's `atan2`/`acos` put the direction across a cell
/// edge (lavapipe: 0.6 % of directions on the 512-column map, 0.02 % on the small ones): any
/// other pdf fails, and at most 2 % may take a neighbour.
#[test]
fn environment_matches_the_cpu() {
    use furnace_scene::{Environment, EnvironmentMap};
    use std::sync::Arc;
    let Some(ctx) = test_context() else { return };
    let mut rng = Rng(0xe_4f1);
    let mut random_map = |w: u32, h: u32| {
        let texels = (0..w * h).map(|_| Vec3::new(rng.f32(), rng.f32(), rng.f32()) * 4.0).collect();
        Arc::new(EnvironmentMap::new(w, h, texels, format!("random {w}×{h}")).unwrap().0)
    };
    let reference = furnace_tests::data::reference("envmap/envmap_spheres_env.exr");
    let sky = Arc::new(EnvironmentMap::load(&reference).unwrap().0);
    let envs = [
        Environment::new(Arc::new(EnvironmentMap::constant(Vec3::new(0.5, 1.0, 2.0)))),
        Environment::new(random_map(7, 5)),
        Environment::new(random_map(64, 2)),
        Environment { intensity: 2.5, rotation: 37f32.to_radians(), ..Environment::new(random_map(16, 8)) },
        Environment::new(sky),
    ];
    let mut rng = Rng(0x5eed);
    for env in &envs {
        let sampler = env.sampler(false).unwrap();
        let words = furnace_gpu::integrator::environment_words(env, Some(&sampler));
        let max = env.map.texels().iter().map(|t| t.max_element()).fold(0.0f32, f32::max) * env.intensity;
        let n = 20_000;
        let mut input = Vec::with_capacity(5 * n);
        let mut cases = Vec::with_capacity(n);
        for k in 0..n {
            let d = match k {
                // Next to the poles (exactly at one, u is atan2(0, 0): undefined in WGSL).
                0 => Vec3::new(1e-4, 1.0, 3e-4).normalize(),
                1 => Vec3::new(-2e-4, -1.0, 1e-4).normalize(),
                2 => Vec3::NEG_Z,
                3 => Vec3::new(1e-7, 0.0, -1.0).normalize(),
                _ => rng.unit_vector(),
            };
            let u = Vec2::new(rng.f32(), rng.f32());
            input.extend(d.to_array().map(f32::to_bits));
            input.extend(u.to_array().map(f32::to_bits));
            cases.push((d, u));
        }
        let got = kernel::run_with(
            &ctx,
            &environment_kernel(env),
            &input,
            &[&words[0], &words[1]],
            11 * n,
            n as u32,
        )
        .unwrap();
        let f = |k: usize| f32::from_bits(got[k]);
        let rel = |a: f32, b: f32| if a == b { 0.0 } else { (a - b).abs() / a.abs().max(b.abs()) };
        let (mut seen_err, mut dir_err, mut pdf_err, mut rad_err, mut pdf_differ) =
            (0f32, 0f32, 0f32, 0f32, 0);
        for (k, &(d, u)) in cases.iter().enumerate() {
            let o = 11 * k;
            let seen = env.radiance(d);
            let e = (seen - Vec3::new(f(o), f(o + 1), f(o + 2))).abs().max_element() / max;
            if e > 1e-3 {
                eprintln!("  lookup at {d}: cpu {seen}, gpu {:?}", [f(o), f(o + 1), f(o + 2)]);
            }
            seen_err = seen_err.max(e);
            match sampler.sample(env, u) {
                Some(s) => {
                    let gd = Vec3::new(f(o + 3), f(o + 4), f(o + 5));
                    dir_err = dir_err.max((s.direction - gd).abs().max_element());
                    pdf_err = pdf_err.max(rel(s.pdf, f(o + 6)));
                    let gr = Vec3::new(f(o + 7), f(o + 8), f(o + 9));
                    rad_err = rad_err.max((s.radiance - gr).abs().max_element() / max);
                }
                None => assert_eq!(f(o + 6), 0.0, "{}: the CPU has no sample for u = {u}", env.map.source()),
            }
            // The GPU's pdf of `d` is that of its cell or, where `d` lies within rounding of a
            // cell edge, of a neighbour.
            if rel(sampler.pdf(d), f(o + 10)) > 1e-4 {
                pdf_differ += 1;
                let m = env.to_map(d);
                let jacobian =
                    2.0 * std::f32::consts::PI * std::f32::consts::PI * (m.x * m.x + m.z * m.z).sqrt();
                let uv = furnace_scene::direction_to_uv(m);
                let (w, h) = (env.map.width() as i64, env.map.height() as i64);
                let (i, j) = ((uv.x * w as f32) as i64, (uv.y * h as f32) as i64);
                let neighbour = (-1..=1).flat_map(|a| (-1..=1).map(move |b| (a, b))).any(|(a, b)| {
                    let (ii, jj) = ((i + a).rem_euclid(w) as u32, (j + b).clamp(0, h - 1) as u32);
                    rel(sampler.distribution().cell_pdf(ii, jj) / jacobian, f(o + 10)) <= 1e-4
                });
                assert!(
                    neighbour,
                    "{}: the pdf of {d} is {} on the GPU, of no cell near the CPU's",
                    env.map.source(),
                    f(o + 10)
                );
            }
        }
        eprintln!(
            "{}: lookup {seen_err:e} of the maximum, sampled direction {dir_err:e}, pdf {pdf_err:e}, radiance \
             {rad_err:e}; {pdf_differ} of {n} direction pdfs differ",
            env.map.source()
        );
        assert!(seen_err <= 1e-3, "{}: lookup differs by {seen_err:e} of the maximum", env.map.source());
        assert!(dir_err <= 1e-5, "{}: sampled direction differs by {dir_err:e}", env.map.source());
        assert!(pdf_err <= 1e-4, "{}: sampled pdf differs by {pdf_err:e}", env.map.source());
        assert!(rad_err <= 1e-3, "{}: sampled radiance differs by {rad_err:e}", env.map.source());
        assert!(pdf_differ * 50 <= n, "{}: {pdf_differ} of {n} direction pdfs differ", env.map.source());
    }
}
