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

#[test]
fn specular_glossiness_textures() {
    let textures = r#","diffuseTexture":{"index":0},"specularGlossinessTexture":{"index":0}"#;
    let materials = [spec_gloss([1.0, 1.0, 1.0, 1.0], [0.04; 3], 0.5, textures)];
    let used = r#""KHR_materials_pbrSpecularGlossiness""#;
    let scene = Scene::from_slice(&gltf(&materials, &[r#""material":0"#], "", used), "sgtex.gltf").unwrap();
    let m = &scene.materials[0];
    let base = m.base_color_texture.as_ref().expect("diffuseTexture becomes the base colour texture");
    assert_eq!((base.texture, base.color_space), (0, furnace_scene::ColorSpace::Srgb));
    assert!(m.metallic_roughness_texture.is_none());
    let path = "materials[0].extensions.KHR_materials_pbrSpecularGlossiness.specularGlossinessTexture";
    assert!(
        scene.warnings.iter().any(|w| w.path == path && w.message.contains("factors alone")),
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
