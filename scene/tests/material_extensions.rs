//! Material extensions that change which material a primitive gets: KHR_materials_pbrSpecularGlossiness
//! (converted to metallic-roughness at load time, checked against values computed by hand from
//! the Khronos converter's formulas) and KHR_materials_variants (the variant chosen by
//! `LoadOptions::variant`, the default without one, an unknown name refused).

use furnace_scene::{LoadOptions, Scene, SceneError};
use glam::{Vec3, Vec4};

/// One triangle's positions (3 × VEC3 float), base64.
const TRIANGLE: &str = "AAAAAAAAAAAAAAAAAACAPwAAAAAAAAAAAAAAAAAAgD8AAAAA";

/// A 1×1 white RGBA PNG, base64.
const WHITE_PNG: &str =
    "iVBORw0KGgoAAAANSUhEUgAAAAEAAAABCAYAAAAfFcSJAAAAC0lEQVR4nGP4DwQACfsD/fteaysAAAAASUVORK5CYII=";

/// A file of one triangle per entry of `primitives` (each a primitive's JSON without its
/// `attributes`), with `materials`, root `extensions` and one texture of a white image.
fn gltf(materials: &[String], primitives: &[&str], extensions: &str, used: &str) -> Vec<u8> {
    let prims: Vec<String> = primitives
        .iter()
        .map(|p| {
            let sep = if p.trim().is_empty() { "" } else { "," };
            format!(r#"{{"attributes":{{"POSITION":0}}{sep}{p}}}"#)
        })
        .collect();
    format!(
        r#"{{"asset":{{"version":"2.0"}},"extensionsUsed":[{used}],"extensions":{{{extensions}}},
"scene":0,"scenes":[{{"nodes":[0]}}],"nodes":[{{"mesh":0}}],
"meshes":[{{"primitives":[{}]}}],"materials":[{}],
"textures":[{{"source":0}}],"images":[{{"uri":"data:image/png;base64,{WHITE_PNG}"}}],
"buffers":[{{"byteLength":36,"uri":"data:application/octet-stream;base64,{TRIANGLE}"}}],
"bufferViews":[{{"buffer":0,"byteLength":36}}],
"accessors":[{{"bufferView":0,"componentType":5126,"count":3,"type":"VEC3","min":[0,0,0],"max":[1,1,0]}}]}}"#,
        prims.join(","),
        materials.join(",")
    )
    .into_bytes()
}

/// A material of KHR_materials_pbrSpecularGlossiness factors (and textures, JSON or "").
fn spec_gloss(diffuse: [f32; 4], specular: [f32; 3], glossiness: f32, textures: &str) -> String {
    format!(
        r#"{{"extensions":{{"KHR_materials_pbrSpecularGlossiness":{{"diffuseFactor":{diffuse:?},
"specularFactor":{specular:?},"glossinessFactor":{glossiness}{textures}}}}}}}"#
    )
}

#[test]
fn specular_glossiness_converts_to_metallic_roughness() {
    // (diffuse, specular, glossiness) → (base colour, metallic, roughness). Worked by hand:
    // L(grey g) = g, k = 1 − max(specular); metallic solves 0.04 m² + b m + (0.04 − s) = 0
    // with b = d·k/0.96 + s − 0.08.
    let cases = [
        // Pure dielectric (specular 0.04): b = d − 0.04 > 0 and c = 0 give m = 0; the base is
        // diffuse·0.96/0.96 = diffuse; alpha is the diffuse alpha.
        ([0.5, 0.25, 0.1, 0.6], [0.04; 3], 0.75, (Vec4::new(0.5, 0.25, 0.1, 0.6), 0.0, 0.25)),
        // Pure metal (diffuse black): D = (s − 0.08)² + 0.16 (s − 0.04) = s², so
        // m = (0.08 − s + s)/0.08 = 1 and the base is the specular colour.
        ([0.0, 0.0, 0.0, 1.0], [0.9, 0.6, 0.3], 1.0, (Vec4::new(0.9, 0.6, 0.3, 1.0), 1.0, 0.0)),
        // Specular below 0.04: a dielectric, m = 0, base = 0.8·0.98/0.96 = 0.81667.
        ([0.8, 0.8, 0.8, 1.0], [0.02; 3], 0.0, (Vec4::new(0.816_667, 0.816_667, 0.816_667, 1.0), 0.0, 1.0)),
        // Half and half: b = 0.25/0.96 + 0.42 = 0.680417, D = b² + 0.16·0.46 = 0.536567,
        // m = (√D − b)/0.08 = 0.651132; base = 0.25/0.96/(1 − m) = 0.746462 (from the specular
        // side, (0.5 − 0.04 (1 − m))/m gives the same).
        (
            [0.5, 0.5, 0.5, 1.0],
            [0.5; 3],
            0.4,
            (Vec4::new(0.746_462, 0.746_462, 0.746_462, 1.0), 0.651_132, 0.6),
        ),
    ];
    let materials: Vec<String> = cases.iter().map(|(d, s, g, _)| spec_gloss(*d, *s, *g, "")).collect();
    let prims: Vec<String> = (0..cases.len()).map(|i| format!(r#""material":{i}"#)).collect();
    let prims: Vec<&str> = prims.iter().map(String::as_str).collect();
    let used = r#""KHR_materials_pbrSpecularGlossiness""#;
    let scene = Scene::from_slice(&gltf(&materials, &prims, "", used), "specgloss.gltf").unwrap();
    for (i, (_, _, _, (base, metallic, roughness))) in cases.iter().enumerate() {
        let m = &scene.materials[i];
        // 1e-4: the hand values are rounded to 6 digits, and the pure metal's quadratic
        // cancels (b and √D are both ≈ 0.65 and differ by 0.08), losing about 3 of f32's
        // 7 digits.
        let tol = 1e-4;
        assert!(
            (m.base_color_factor - *base).abs().max_element() < tol,
            "case {i}: base colour {} != {base}",
            m.base_color_factor
        );
        assert!(
            (m.metallic_factor - metallic).abs() < tol,
            "case {i}: metallic {} != {metallic}",
            m.metallic_factor
        );
        assert!(
            (m.roughness_factor - roughness).abs() < tol,
            "case {i}: roughness {} != {roughness}",
            m.roughness_factor
        );
        assert!(m.base_color_texture.is_none() && m.metallic_roughness_texture.is_none());
        // The converted material is the plain metallic-roughness one: no specular override.
        assert_eq!((m.specular_factor, m.specular_color_factor), (1.0, Vec3::ONE));
    }
    let unsupported = scene.warnings.iter().any(|w| w.message.contains("pbrSpecularGlossiness"));
    assert!(!unsupported, "{:?}", scene.warnings);
}

/// A `width × height` RGBA PNG of `texels` (row-major), base64.
fn png(width: u32, height: u32, texels: &[[u8; 4]]) -> String {
    let image =
        image::RgbaImage::from_fn(width, height, |x, y| image::Rgba(texels[(y * width + x) as usize]));
    let mut bytes = std::io::Cursor::new(Vec::new());
    image.write_to(&mut bytes, image::ImageFormat::Png).unwrap();
    base64::encode(bytes.into_inner())
}

/// A file of one triangle (with `TEXCOORD_0` and `TEXCOORD_1`, so that any set may be
/// sampled) of material 0, with `materials`, `images` (base64 PNGs) and `textures` (JSON).
fn textured_gltf(materials: &[String], images: &[String], textures: &str, samplers: &str) -> Vec<u8> {
    // Positions, then two UV sets, of 3 vertices.
    let floats: [f32; 21] =
        [0., 0., 0., 1., 0., 0., 0., 1., 0., 0., 0., 1., 0., 0., 1., 0., 0., 1., 0., 0., 1.];
    let bin: Vec<u8> = floats.iter().flat_map(|f| f.to_le_bytes()).collect();
    let images: Vec<String> =
        images.iter().map(|i| format!(r#"{{"uri":"data:image/png;base64,{i}"}}"#)).collect();
    format!(
        r#"{{"asset":{{"version":"2.0"}},
"extensionsUsed":["KHR_materials_pbrSpecularGlossiness","KHR_texture_transform"],
"scene":0,"scenes":[{{"nodes":[0]}}],"nodes":[{{"mesh":0}}],
"meshes":[{{"primitives":[{{"attributes":{{"POSITION":0,"TEXCOORD_0":1,"TEXCOORD_1":2}},"material":0}}]}}],
"materials":[{}],"textures":{textures},"samplers":{samplers},"images":[{}],
"buffers":[{{"byteLength":84,"uri":"data:application/octet-stream;base64,{}"}}],
"bufferViews":[{{"buffer":0,"byteLength":36}},{{"buffer":0,"byteOffset":36,"byteLength":24}},
{{"buffer":0,"byteOffset":60,"byteLength":24}}],
"accessors":[{{"bufferView":0,"componentType":5126,"count":3,"type":"VEC3","min":[0,0,0],"max":[1,1,0]}},
{{"bufferView":1,"componentType":5126,"count":3,"type":"VEC2"}},
{{"bufferView":2,"componentType":5126,"count":3,"type":"VEC2"}}]}}"#,
        materials.join(","),
        images.join(","),
        base64::encode(&bin)
    )
    .into_bytes()
}

/// Diffuse and specular-glossiness texels (4 × 2, sRGB RGB, linear alpha) from dielectric
/// (specular below 0.04) to metal, and rough to glossy.
const DIFFUSE: [[u8; 4]; 8] = [
    [200, 30, 30, 255],
    [0, 0, 0, 255],
    [128, 128, 128, 128],
    [255, 255, 255, 255],
    [10, 200, 90, 255],
    [90, 60, 30, 0],
    [255, 0, 255, 255],
    [40, 40, 40, 255],
];
const SPEC_GLOSS: [[u8; 4]; 8] = [
    [20, 20, 20, 255],
    [250, 200, 120, 230],
    [59, 59, 59, 128],
    [128, 128, 128, 0],
    [255, 255, 255, 255],
    [180, 180, 180, 60],
    [0, 0, 0, 200],
    [70, 90, 110, 10],
];

/// The factors the material has when texel `i`'s values are its factors (no textures):
/// `diffuse × texel`, `specular × texel RGB`, `glossiness × texel alpha`.
fn texel_as_factors(i: usize, diffuse: [f32; 4], specular: [f32; 3], glossiness: f32) -> String {
    let lin = |v: u8| furnace_post::srgb_to_linear(f32::from(v) / 255.0);
    let (d, s) = (DIFFUSE[i], SPEC_GLOSS[i]);
    spec_gloss(
        [
            diffuse[0] * lin(d[0]),
            diffuse[1] * lin(d[1]),
            diffuse[2] * lin(d[2]),
            diffuse[3] * f32::from(d[3]) / 255.0,
        ],
        [specular[0] * lin(s[0]), specular[1] * lin(s[1]), specular[2] * lin(s[2])],
        glossiness * f32::from(s[3]) / 255.0,
        "",
    )
}

/// The specular-glossiness texture is baked per texel, as the factors are converted: each
/// texel of the new base colour and metallic-roughness images is what the factor conversion
/// gives for that texel's values, and the new textures keep the source's sampler, UV set and
/// transform.
#[test]
fn specular_glossiness_textures_are_baked_per_texel() {
    let (diffuse, specular, glossiness) = ([0.9, 0.8, 1.0, 1.0], [1.0, 0.9, 0.8], 0.7);
    let transform =
        r#""extensions":{"KHR_texture_transform":{"offset":[0.25,0],"scale":[2,2],"texCoord":1}}"#;
    let textures = format!(
        r#","diffuseTexture":{{"index":0,{transform}}},"specularGlossinessTexture":{{"index":1,{transform}}}"#
    );
    let material = spec_gloss(diffuse, specular, glossiness, &textures);
    let bytes = textured_gltf(
        &[material],
        &[png(4, 2, &DIFFUSE), png(4, 2, &SPEC_GLOSS)],
        r#"[{"source":0},{"source":1,"sampler":0}]"#,
        r#"[{"wrapS":33071,"wrapT":33648}]"#,
    );
    let scene = Scene::from_slice(&bytes, "sgtex.gltf").unwrap();
    assert!(scene.warnings.is_empty(), "{:?}", scene.warnings);
    let m = &scene.materials[0];
    assert_eq!((m.base_color_factor, m.metallic_factor, m.roughness_factor), (Vec4::ONE, 1.0, 1.0));
    let base = m.base_color_texture.expect("a baked base colour texture");
    let mr = m.metallic_roughness_texture.expect("a baked metallic-roughness texture");
    for (r, space) in [(base, furnace_scene::ColorSpace::Srgb), (mr, furnace_scene::ColorSpace::Linear)] {
        assert_eq!(r.color_space, space);
        // The source's UV set and transform; its sampler's wrap modes.
        assert_eq!(r.tex_coord, 1);
        let t = r.transform.expect("the transform carries over");
        assert_eq!((t.offset.x, t.scale.x), (0.25, 2.0));
        let tex = scene.textures[r.texture as usize];
        assert_eq!(
            (tex.wrap_s, tex.wrap_t),
            (furnace_scene::WrapMode::ClampToEdge, furnace_scene::WrapMode::MirroredRepeat)
        );
        assert_eq!((scene.images[tex.image as usize].width, scene.images[tex.image as usize].height), (4, 2));
    }
    // The sources are sampled by no material any more: placeholders.
    assert!(scene.images[..2].iter().all(|i| i.width == 1 && i.height == 1));
    // Each texel against the factor conversion of its values.
    let materials: Vec<String> = (0..8).map(|i| texel_as_factors(i, diffuse, specular, glossiness)).collect();
    let factors =
        Scene::from_slice(&gltf(&materials, &[""], "", r#""KHR_materials_pbrSpecularGlossiness""#), "f.gltf")
            .unwrap();
    let texels = |r: furnace_scene::TextureRef| {
        &scene.images[scene.textures[r.texture as usize].image as usize].texels
    };
    let unorm = |v: f32| (v.clamp(0.0, 1.0) * 255.0).round() as i32;
    for i in 0..8 {
        let f = &factors.materials[i];
        let srgb = |v: f32| unorm(furnace_post::linear_to_srgb(v));
        let c = f.base_color_factor;
        let want_base = [srgb(c.x), srgb(c.y), srgb(c.z), unorm(c.w)];
        let want_mr = [unorm(f.roughness_factor), unorm(f.metallic_factor)];
        let (b, m) = (texels(base)[i], texels(mr)[i]);
        let got_base = b.map(i32::from);
        let got_mr = [i32::from(m[1]), i32::from(m[2])];
        // ±1 in the 8-bit code: the factor file's values are the texels' decoded and printed
        // again, so the two conversions may differ by an f32 rounding, which can move a value
        // across a quantisation boundary; a wrong conversion misses by far more.
        let close = |a: &[i32], b: &[i32]| a.iter().zip(b).all(|(x, y)| (x - y).abs() <= 1);
        assert!(
            close(&got_base, &want_base),
            "texel {i}: base colour {got_base:?}, factors give {want_base:?}"
        );
        assert!(
            close(&got_mr, &want_mr),
            "texel {i}: roughness, metallic {got_mr:?}, factors give {want_mr:?}"
        );
    }
    // The texels span dielectric to metal: the test sees both sides of the conversion.
    let metallic: Vec<u8> = texels(mr).iter().map(|t| t[2]).collect();
    assert!(metallic.contains(&0) && metallic.iter().any(|&m| m > 200), "{metallic:?}");
}

/// A new image only when the material needs one: a dielectric's diffuse texture stays the base
/// colour texture (exact: its base colour is the diffuse colour times a constant); a partly
/// metallic one's is baked. Textures of different UV sets cannot be baked texel by texel: the
/// diffuse texture stays, the metallic-roughness is baked with its mean colour, and a warning
/// says so.
#[test]
fn specular_glossiness_bakes_only_what_needs_it() {
    let load = |material: String, textures: &str| {
        let bytes =
            textured_gltf(&[material], &[png(4, 2, &DIFFUSE), png(4, 2, &SPEC_GLOSS)], textures, "[]");
        Scene::from_slice(&bytes, "sg.gltf").unwrap()
    };
    let both = r#"[{"source":0},{"source":1}]"#;
    let diffuse_only = r#","diffuseTexture":{"index":0}"#;
    let dielectric = load(spec_gloss([1.0; 4], [0.04; 3], 0.5, diffuse_only), both);
    let m = &dielectric.materials[0];
    assert_eq!(dielectric.textures.len(), 2, "no new texture for a dielectric");
    assert_eq!(m.base_color_texture.map(|t| t.texture), Some(0));
    assert!(m.metallic_roughness_texture.is_none());
    assert!((m.metallic_factor, m.roughness_factor) == (0.0, 0.5));

    let metal = load(spec_gloss([1.0; 4], [0.5; 3], 0.5, diffuse_only), both);
    let m = &metal.materials[0];
    assert_eq!(metal.textures.len(), 4, "base colour and metallic-roughness baked");
    assert_eq!(
        (m.base_color_texture.unwrap().texture, m.metallic_roughness_texture.unwrap().texture),
        (3, 2)
    );

    let apart = r#","diffuseTexture":{"index":0},"specularGlossinessTexture":{"index":1,"texCoord":1}"#;
    let scene = load(spec_gloss([1.0; 4], [1.0; 3], 1.0, apart), both);
    let m = &scene.materials[0];
    assert_eq!(m.base_color_texture.map(|t| (t.texture, t.tex_coord)), Some((0, 0)), "diffuse kept");
    let mr = m.metallic_roughness_texture.expect("metallic-roughness baked");
    assert_eq!((mr.texture, mr.tex_coord), (2, 1));
    let path = "materials[0].extensions.KHR_materials_pbrSpecularGlossiness";
    assert!(
        scene.warnings.iter().any(|w| w.path == path && w.message.contains("different UV sets")),
        "{:?}",
        scene.warnings
    );
}

/// Materials 0 (red), 1 (green), 2 (blue) and primitives mapped by variants "Day" (0) and
/// "Night" (1): primitive 0 (red) is green by day and blue by night, primitive 1 (red) green
/// by night, primitive 2 (no material) blue by day.
fn variants_file() -> Vec<u8> {
    let colour = |c: &str| format!(r#"{{"pbrMetallicRoughness":{{"baseColorFactor":[{c},1]}}}}"#);
    let materials = [colour("1,0,0"), colour("0,1,0"), colour("0,0,1")];
    let ext =
        |mappings: &str| format!(r#""extensions":{{"KHR_materials_variants":{{"mappings":[{mappings}]}}}}"#);
    let p0 =
        format!(r#""material":0,{}"#, ext(r#"{"variants":[0],"material":1},{"variants":[1],"material":2}"#));
    let p1 = format!(r#""material":0,{}"#, ext(r#"{"variants":[1],"material":1}"#));
    let p2 = ext(r#"{"variants":[0],"material":2}"#);
    let root = r#""KHR_materials_variants":{"variants":[{"name":"Day"},{"name":"Night"}]}"#;
    gltf(&materials, &[&p0, &p1, &p2], root, r#""KHR_materials_variants""#)
}

fn load_variant(bytes: &[u8], variant: Option<&str>) -> Result<Scene, SceneError> {
    let options = LoadOptions { variant: variant.map(str::to_string), ..LoadOptions::default() };
    Scene::from_slice_with(bytes, "variants.gltf", &options)
}

#[test]
fn variants_select_materials() {
    let bytes = variants_file();
    // Material 3 is glTF's default material, which primitive 2 has without a mapping.
    for (variant, want) in [
        (None, [0, 0, 3]),
        (Some("Day"), [1, 0, 2]),
        (Some("Night"), [2, 1, 3]),
        (Some("0"), [1, 0, 2]),
        (Some("1"), [2, 1, 3]),
    ] {
        let scene = load_variant(&bytes, variant).unwrap();
        assert_eq!(scene.geometry.triangle_materials, want, "variant {variant:?}");
        assert_eq!(scene.variants, ["Day", "Night"]);
        assert!(scene.warnings.is_empty(), "{:?}", scene.warnings);
    }
    let default = load_variant(&bytes, None).unwrap().content_hash();
    assert_ne!(load_variant(&bytes, Some("Day")).unwrap().content_hash(), default);
}

#[test]
fn unknown_variant_is_an_error_listing_the_variants() {
    let e = load_variant(&variants_file(), Some("Dusk")).unwrap_err();
    assert!(matches!(e, SceneError::UnknownVariant { .. }), "{e}");
    let msg = e.to_string();
    assert!(msg.contains("'Dusk'") && msg.contains("0 'Day'") && msg.contains("1 'Night'"), "{msg}");
    // An index past the last variant is not a variant either.
    assert!(matches!(load_variant(&variants_file(), Some("2")), Err(SceneError::UnknownVariant { .. })));
    // A file without the extension has no variants to choose from.
    let plain = gltf(&[r#"{}"#.to_string()], &[r#""material":0"#], "", "");
    let e = load_variant(&plain, Some("Day")).unwrap_err();
    assert!(e.to_string().contains("has no variants"), "{e}");
    assert!(load_variant(&plain, None).unwrap().variants.is_empty());
}

#[test]
fn bad_variant_mappings_are_errors_naming_them() {
    let root = r#""KHR_materials_variants":{"variants":[{"name":"A"}]}"#;
    let used = r#""KHR_materials_variants""#;
    let materials = ["{}".to_string()];
    for (mapping, path) in [
        (r#"{"variants":[0],"material":5}"#, "mappings[0].material"),
        (r#"{"variants":[3],"material":0}"#, "mappings[0].variants[0]"),
    ] {
        let prim = format!(r#""extensions":{{"KHR_materials_variants":{{"mappings":[{mapping}]}}}}"#);
        let bytes = gltf(&materials, &[&prim], root, used);
        match load_variant(&bytes, Some("A")) {
            Err(SceneError::Invalid { path: p, .. }) => assert!(p.ends_with(path), "{p}"),
            other => panic!("{mapping}: {other:?}"),
        }
        // Without a variant the mappings are not read: the primitive keeps its own material.
        assert!(load_variant(&bytes, None).is_ok());
    }
}

/// KHR_materials_clearcoat and KHR_materials_sheen read into `Material::layers`: factors,
/// textures (the sheen colour in sRGB, the others linear; `texCoord` and the transform read),
/// the coat's normal texture and its scale; no layer for a zero coat or a black sheen (the
/// content hash then unchanged); a factor out of range clamped and a texture index out of range
/// dropped, each with a warning naming its path; a file that requires both loads.
#[test]
fn clearcoat_and_sheen_are_read() {
    use furnace_scene::ColorSpace;
    let coat = r#"{"extensions":{"KHR_materials_clearcoat":{"clearcoatFactor":0.7,"clearcoatTexture":{"index":0,"texCoord":1},
"clearcoatRoughnessFactor":0.3,"clearcoatRoughnessTexture":{"index":0},"clearcoatNormalTexture":{"index":0,"scale":0.5}}}}"#;
    let sheen = r#"{"extensions":{"KHR_materials_sheen":{"sheenColorFactor":[1.0,0.5,0.25],"sheenColorTexture":{"index":0,
"extensions":{"KHR_texture_transform":{"scale":[2,2]}}},"sheenRoughnessFactor":0.6,"sheenRoughnessTexture":{"index":0}}}}"#;
    let off = r#"{"extensions":{"KHR_materials_clearcoat":{"clearcoatFactor":0},"KHR_materials_sheen":{"sheenColorFactor":[0,0,0]}}}"#;
    let bad = r#"{"extensions":{"KHR_materials_clearcoat":{"clearcoatFactor":1.5,"clearcoatTexture":{"index":9}}}}"#;
    let materials: Vec<String> = [coat, sheen, off, bad].iter().map(|s| s.to_string()).collect();
    let prims = [r#""material":0"#, r#""material":1"#, r#""material":2"#, r#""material":3"#];
    let used = r#""KHR_materials_clearcoat","KHR_materials_sheen""#;
    let mut bytes = gltf(&materials, &prims, "", used);
    // Required as well: both are supported.
    let text = String::from_utf8(bytes).unwrap().replacen(
        r#""extensionsUsed""#,
        r#""extensionsRequired":["KHR_materials_clearcoat","KHR_materials_sheen"],"extensionsUsed""#,
        1,
    );
    bytes = text.into_bytes();
    let scene = Scene::from_slice(&bytes, "layers.gltf").unwrap();
    let c = scene.materials[0].layers.clearcoat.as_ref().expect("a coat");
    assert_eq!((c.factor, c.roughness, c.normal_scale), (0.7, 0.3, 0.5));
    assert_eq!(c.texture.as_ref().map(|t| (t.tex_coord, t.color_space)), Some((1, ColorSpace::Linear)));
    assert!(c.roughness_texture.is_some() && c.normal_texture.is_some());
    assert!(scene.materials[0].layers.sheen.is_none());
    let s = scene.materials[1].layers.sheen.as_ref().expect("a sheen");
    assert_eq!((s.color, s.roughness), (Vec3::new(1.0, 0.5, 0.25), 0.6));
    let ct = s.color_texture.as_ref().expect("a sheen colour texture");
    assert_eq!(ct.color_space, ColorSpace::Srgb);
    assert_eq!(ct.transform.map(|t| t.scale), Some(glam::Vec2::splat(2.0)));
    assert!(scene.materials[2].layers.is_empty(), "a zero coat and a black sheen are no layers");
    let c = scene.materials[3].layers.clearcoat.as_ref().expect("a coat");
    assert_eq!(c.factor, 1.0, "clamped");
    assert!(c.texture.is_none(), "a texture index out of range is dropped");
    let paths: Vec<&str> = scene.warnings.iter().map(|w| w.path.as_str()).collect();
    assert!(paths.contains(&"materials[3].extensions.KHR_materials_clearcoat.clearcoatFactor"), "{paths:?}");
    assert!(paths.contains(&"materials[3].extensions.KHR_materials_clearcoat.clearcoatTexture"), "{paths:?}");
    // A file whose layers are all off hashes as one without the extensions (files from before
    // the layers keep their hash).
    let plain =
        Scene::from_slice(&gltf(&[off.to_string()], &[r#""material":0"#], "", used), "off.gltf").unwrap();
    let none =
        Scene::from_slice(&gltf(&["{}".to_string()], &[r#""material":0"#], "", ""), "none.gltf").unwrap();
    assert_eq!(plain.content_hash(), none.content_hash());
}

/// KHR_materials_iridescence: factors, textures and defaults read, also when required;
/// out-of-range values warn with the path; a factor of 0 is no film and keeps the hash.
#[test]
fn iridescence_is_read() {
    let film = r#"{"extensions":{"KHR_materials_iridescence":{"iridescenceFactor":0.8,"iridescenceTexture":{"index":0},
"iridescenceIor":1.6,"iridescenceThicknessMinimum":50,"iridescenceThicknessMaximum":700,
"iridescenceThicknessTexture":{"index":0,"texCoord":1}}}}"#;
    let defaults = r#"{"extensions":{"KHR_materials_iridescence":{"iridescenceFactor":1}}}"#;
    let off = r#"{"extensions":{"KHR_materials_iridescence":{"iridescenceIor":2.0}}}"#;
    let bad = r#"{"extensions":{"KHR_materials_iridescence":{"iridescenceFactor":1,"iridescenceIor":0.5,
"iridescenceThicknessMaximum":-3,"iridescenceTexture":{"index":7}}}}"#;
    let materials: Vec<String> = [film, defaults, off, bad].iter().map(|s| s.to_string()).collect();
    let prims = [r#""material":0"#, r#""material":1"#, r#""material":2"#, r#""material":3"#];
    let used = r#""KHR_materials_iridescence""#;
    let text = String::from_utf8(gltf(&materials, &prims, "", used)).unwrap().replacen(
        r#""extensionsUsed""#,
        r#""extensionsRequired":["KHR_materials_iridescence"],"extensionsUsed""#,
        1,
    );
    let scene = Scene::from_slice(text.as_bytes(), "film.gltf").unwrap();
    let i = scene.materials[0].iridescence.as_ref().expect("a film");
    assert_eq!((i.factor, i.ior, i.thickness_minimum, i.thickness_maximum), (0.8, 1.6, 50.0, 700.0));
    assert!(i.texture.is_some());
    assert_eq!(i.thickness_texture.as_ref().map(|t| t.tex_coord), Some(1));
    let d = scene.materials[1].iridescence.as_ref().expect("a film");
    assert_eq!(
        (d.ior, d.thickness_minimum, d.thickness_maximum),
        (1.3, 100.0, 400.0),
        "the extension's defaults"
    );
    assert!(scene.materials[2].iridescence.is_none(), "factor 0 (the default): no film");
    let b = scene.materials[3].iridescence.as_ref().expect("a film");
    assert_eq!((b.ior, b.thickness_maximum), (1.0, 0.0), "clamped");
    assert!(b.texture.is_none(), "a texture index out of range is dropped");
    let paths: Vec<&str> = scene.warnings.iter().map(|w| w.path.as_str()).collect();
    for key in ["iridescenceIor", "iridescenceThicknessMaximum", "iridescenceTexture"] {
        let path = format!("materials[3].extensions.KHR_materials_iridescence.{key}");
        assert!(paths.contains(&path.as_str()), "{path} not in {paths:?}");
    }
    let plain =
        Scene::from_slice(&gltf(&[off.to_string()], &[r#""material":0"#], "", used), "off.gltf").unwrap();
    let none =
        Scene::from_slice(&gltf(&["{}".to_string()], &[r#""material":0"#], "", ""), "none.gltf").unwrap();
    assert_eq!(plain.content_hash(), none.content_hash());
}

/// KHR_materials_diffuse_transmission read into `Material::diffuse_transmission`: factor,
/// texture (linear, A channel) and colour texture (sRGB); no lobe for a zero factor (the content
/// hash then unchanged); a factor and a colour out of range clamped and a texture index out of
/// range dropped, each with a warning naming its path; the surface two-sided, a solid with
/// KHR_materials_volume (no warning that the volume is ignored); a file that requires it loads.
#[test]
fn diffuse_transmission_is_read() {
    use furnace_scene::ColorSpace;
    const EXT: &str = "KHR_materials_diffuse_transmission";
    let full = format!(
        r#"{{"extensions":{{"{EXT}":{{"diffuseTransmissionFactor":0.25,"diffuseTransmissionTexture":{{"index":0,"texCoord":1}},
"diffuseTransmissionColorFactor":[1.0,0.9,0.85],"diffuseTransmissionColorTexture":{{"index":0}}}}}}}}"#
    );
    let off = format!(r#"{{"extensions":{{"{EXT}":{{"diffuseTransmissionColorFactor":[1.0,0.0,0.0]}}}}}}"#);
    let bad = format!(
        r#"{{"extensions":{{"{EXT}":{{"diffuseTransmissionFactor":1.5,"diffuseTransmissionColorFactor":[2.0,0.5,-1.0],
"diffuseTransmissionColorTexture":{{"index":9}}}}}}}}"#
    );
    let solid = format!(
        r#"{{"extensions":{{"{EXT}":{{"diffuseTransmissionFactor":1.0}},
"KHR_materials_volume":{{"thicknessFactor":0.1,"attenuationDistance":2.0,"attenuationColor":[0.5,1.0,1.0]}}}}}}"#
    );
    let materials = [full, off.clone(), bad, solid];
    let prims = [r#""material":0"#, r#""material":1"#, r#""material":2"#, r#""material":3"#];
    let used = format!(r#""{EXT}","KHR_materials_volume""#);
    let text = String::from_utf8(gltf(&materials, &prims, "", &used)).unwrap().replacen(
        r#""extensionsUsed""#,
        &format!(r#""extensionsRequired":["{EXT}"],"extensionsUsed""#),
        1,
    );
    let scene = Scene::from_slice(text.as_bytes(), "dt.gltf").unwrap();
    let d = scene.materials[0].diffuse_transmission.as_ref().expect("diffuse transmission");
    assert_eq!((d.factor, d.color), (0.25, Vec3::new(1.0, 0.9, 0.85)));
    assert_eq!(d.texture.as_ref().map(|t| (t.tex_coord, t.color_space)), Some((1, ColorSpace::Linear)));
    assert_eq!(d.color_texture.as_ref().map(|t| t.color_space), Some(ColorSpace::Srgb));
    assert!(scene.materials[0].double_sided && !scene.materials[0].volume);
    assert!(scene.materials[1].diffuse_transmission.is_none(), "factor 0 (the default) is no lobe");
    assert!(!scene.materials[1].double_sided);
    let d = scene.materials[2].diffuse_transmission.as_ref().expect("diffuse transmission");
    assert_eq!((d.factor, d.color), (1.0, Vec3::new(1.0, 0.5, 0.0)), "clamped");
    assert!(d.color_texture.is_none(), "a texture index out of range is dropped");
    let m = &scene.materials[3];
    assert!(m.volume && m.diffuse_transmission.is_some(), "a translucent solid");
    assert!((m.absorption.x - 2f32.ln() / 2.0).abs() < 1e-6 && m.absorption.y == 0.0);
    let p = |i: usize, key: &str| format!("materials[{i}].extensions.{EXT}.{key}");
    let paths: Vec<&str> = scene.warnings.iter().map(|w| w.path.as_str()).collect();
    for key in
        ["diffuseTransmissionFactor", "diffuseTransmissionColorFactor", "diffuseTransmissionColorTexture"]
    {
        assert!(paths.contains(&p(2, key).as_str()), "{key}: {paths:?}");
    }
    assert!(!paths.iter().any(|p| p.contains("KHR_materials_volume")), "{paths:?}");
    // A material whose factor is 0 hashes as one without the extension.
    let plain = Scene::from_slice(&gltf(&[off], &[r#""material":0"#], "", &used), "off.gltf").unwrap();
    let none =
        Scene::from_slice(&gltf(&["{}".to_string()], &[r#""material":0"#], "", ""), "none.gltf").unwrap();
    assert_eq!(plain.content_hash(), none.content_hash());
}

/// KHR_materials_specular's textures: `specularTexture` read linear and its A channel
/// multiplying `specularFactor`, `specularColorTexture` read as sRGB multiplying
/// `specularColorFactor`, each at its own UV set; an index out of range is an error naming the
/// place; the textures are part of the scene's content.
#[test]
fn specular_textures_multiply_the_factors() {
    use furnace_scene::{ColorSpace, VertexAttributes};
    let texel = [[128u8, 64, 255, 51]];
    let material = |ext: &str| format!(r#"{{"extensions":{{"KHR_materials_specular":{{{ext}}}}}}}"#);
    let textured = material(
        r#""specularFactor":0.5,"specularTexture":{"index":0},"specularColorFactor":[1,0.5,2],
"specularColorTexture":{"index":0,"texCoord":1}"#,
    );
    let file = |m: &str| textured_gltf(&[m.to_string()], &[png(1, 1, &texel)], r#"[{"source":0}]"#, "[]");
    let scene = Scene::from_slice(&file(&textured), "specular.gltf").unwrap();
    assert!(scene.warnings.is_empty(), "{:?}", scene.warnings);
    let m = &scene.materials[0];
    let s = m.specular_textures.specular.expect("a specular texture");
    let c = m.specular_textures.color.expect("a specular colour texture");
    assert_eq!((s.color_space, s.tex_coord), (ColorSpace::Linear, 0));
    assert_eq!((c.color_space, c.tex_coord), (ColorSpace::Srgb, 1));
    let ms = m.evaluate(&VertexAttributes::from_uv(glam::Vec2::splat(0.5)), &scene.textures, &scene.images);
    // One texel: every lookup returns it exactly (8-bit value / 255, through the sRGB table
    // for the colour), so the products are exact up to f32 rounding of one multiply.
    let lin = |v: u8| furnace_post::srgb_to_linear(f32::from(v) / 255.0);
    assert!((ms.specular_factor - 0.5 * 51.0 / 255.0).abs() < 1e-6, "{}", ms.specular_factor);
    let expected = Vec3::new(lin(128), 0.5 * lin(64), 2.0 * lin(255));
    assert!((ms.specular_color - expected).abs().max_element() < 1e-6, "{} vs {expected}", ms.specular_color);
    // Factors alone: the textures' slots are empty and the factors come through unchanged.
    let factors = Scene::from_slice(
        &file(&material(r#""specularFactor":0.5,"specularColorFactor":[1,0.5,2]"#)),
        "f.gltf",
    )
    .unwrap();
    let f = &factors.materials[0];
    assert!(f.specular_textures.is_empty());
    let fs = f.evaluate(&VertexAttributes::from_uv(glam::Vec2::ZERO), &factors.textures, &factors.images);
    assert_eq!((fs.specular_factor, fs.specular_color), (0.5, Vec3::new(1.0, 0.5, 2.0)));
    assert_ne!(scene.content_hash(), factors.content_hash(), "the textures are content");
    // An index out of range is refused with its place in the file.
    let bad = material(r#""specularColorTexture":{"index":4}"#);
    let e = Scene::from_slice(&file(&bad), "bad.gltf").unwrap_err().to_string();
    assert!(e.contains("bad.gltf") && e.contains("specularColorTexture"), "{e}");
}

/// KHR_materials_anisotropy read: strength, rotation and texture (linear); a zero strength is
/// no anisotropy (the hash unchanged); a strength out of range clamped and a texture index out
/// of range dropped, each with a warning naming its path; a file that requires it loads, with
/// tangents stored for the direction (generated: the file has none) although nothing is
/// normal-mapped; the strength times the texture's B at a hit.
#[test]
fn anisotropy_is_read() {
    use furnace_scene::{ColorSpace, VertexAttributes};
    const EXT: &str = "KHR_materials_anisotropy";
    let texel = [[255u8, 128, 102, 255]];
    let material = |ext: &str| format!(r#"{{"extensions":{{"{EXT}":{{{ext}}}}}}}"#);
    let full = material(
        r#""anisotropyStrength":0.5,"anisotropyRotation":1.25,"anisotropyTexture":{"index":0,"texCoord":1}"#,
    );
    let file = |m: &str| {
        let text = String::from_utf8(textured_gltf(
            &[m.to_string()],
            &[png(1, 1, &texel)],
            r#"[{"source":0}]"#,
            "[]",
        ))
        .unwrap();
        text.replacen(
            r#""extensionsUsed":["#,
            &format!(r#""extensionsRequired":["{EXT}"],"extensionsUsed":["{EXT}","#),
            1,
        )
    };
    let scene = Scene::from_slice(file(&full).as_bytes(), "aniso.gltf").unwrap();
    assert!(scene.warnings.is_empty(), "{:?}", scene.warnings);
    let a = scene.materials[0].anisotropy.as_ref().expect("anisotropy");
    assert_eq!((a.strength, a.rotation), (0.5, 1.25));
    assert_eq!(a.texture.as_ref().map(|t| (t.tex_coord, t.color_space)), Some((1, ColorSpace::Linear)));
    assert_eq!(scene.geometry.tangents.len(), scene.geometry.positions.len(), "tangents for the direction");
    let ms = scene.materials[0].evaluate(
        &VertexAttributes::from_uv(glam::Vec2::ZERO),
        &scene.textures,
        &scene.images,
    );
    assert!((ms.anisotropy - 0.5 * 0.4).abs() < 1e-6, "strength × B (102/255): {}", ms.anisotropy);
    let bad = material(r#""anisotropyStrength":1.5,"anisotropyTexture":{"index":3}"#);
    let b = Scene::from_slice(file(&bad).as_bytes(), "bad.gltf").unwrap();
    let ba = b.materials[0].anisotropy.as_ref().expect("anisotropy");
    assert_eq!(ba.strength, 1.0, "clamped");
    assert!(ba.texture.is_none(), "a texture index out of range is dropped");
    let paths: Vec<&str> = b.warnings.iter().map(|w| w.path.as_str()).collect();
    for key in ["anisotropyStrength", "anisotropyTexture"] {
        let path = format!("materials[0].extensions.{EXT}.{key}");
        assert!(paths.contains(&path.as_str()), "{path} not in {paths:?}");
    }
    let off = Scene::from_slice(file(&material(r#""anisotropyRotation":2"#)).as_bytes(), "off.gltf").unwrap();
    assert!(off.materials[0].anisotropy.is_none(), "strength 0 (the default): none");
    assert!(off.geometry.tangents.is_empty(), "no tangents without a use");
    let none = Scene::from_slice(
        &textured_gltf(&["{}".to_string()], &[png(1, 1, &texel)], r#"[{"source":0}]"#, "[]"),
        "none.gltf",
    )
    .unwrap();
    assert_eq!(off.content_hash(), none.content_hash());
}

/// KHR_materials_dispersion read on a transmissive solid, also where required; 0 (no
/// dispersion, the hash unchanged) where it could have no effect: a sheet (no volume, with a
/// warning naming it), an index of 1, the default; a negative value a warning and 0.
#[test]
fn dispersion_is_read() {
    const EXT: &str = "KHR_materials_dispersion";
    let material = |volume: bool, ior: f32, dispersion: &str| {
        let volume = if volume { r#","KHR_materials_volume":{"thicknessFactor":1}"# } else { "" };
        format!(
            r#"{{"extensions":{{"KHR_materials_transmission":{{"transmissionFactor":1}},
"KHR_materials_ior":{{"ior":{ior}}}{volume},"{EXT}":{{{dispersion}}}}}}}"#
        )
    };
    let load = |m: String| {
        let text = String::from_utf8(gltf(&[m], &["\"material\":0"], "", "")).unwrap();
        let text = text.replacen(
            r#""extensionsUsed":["#,
            &format!(r#""extensionsRequired":["{EXT}"],"extensionsUsed":["{EXT}""#),
            1,
        );
        Scene::from_slice(text.as_bytes(), "prism.gltf").unwrap()
    };
    let prism = load(material(true, 1.5, r#""dispersion":0.36"#));
    assert!(prism.warnings.is_empty(), "{:?}", prism.warnings);
    assert_eq!(prism.materials[0].dispersion, 0.36);
    assert!(prism.disperses());
    let sheet = load(material(false, 1.5, r#""dispersion":0.36"#));
    assert_eq!(sheet.materials[0].dispersion, 0.0, "a sheet has no volume to disperse in");
    assert!(
        sheet.warnings.iter().any(|w| w.path == format!("materials[0].extensions.{EXT}")),
        "{:?}",
        sheet.warnings
    );
    let air = load(material(true, 1.0, r#""dispersion":1"#));
    assert_eq!(air.materials[0].dispersion, 0.0, "an index of 1 is 1 at every wavelength");
    let negative = load(material(true, 1.5, r#""dispersion":-1"#));
    assert_eq!(negative.materials[0].dispersion, 0.0);
    assert!(negative.warnings.iter().any(|w| w.path.ends_with("dispersion")), "{:?}", negative.warnings);
    let plain = load(material(true, 1.5, ""));
    assert_eq!(plain.materials[0].dispersion, 0.0, "0 by default");
    assert!(!plain.disperses());
    let without = load(
        material(true, 1.5, r#""dispersion":0"#).replace(&format!(r#","{EXT}":{{"dispersion":0}}"#), ""),
    );
    assert_ne!(prism.content_hash(), without.content_hash(), "the hash sees a dispersion");
    assert_eq!(plain.content_hash(), without.content_hash(), "a dispersion of 0 hashes as none");
}
