//! Vertex attributes besides position and normal: `COLOR_0` in each of glTF's encodings
//! (float, normalised unsigned byte and short; RGB and RGBA), white where a primitive lacks it,
//! and the UV sets the materials sample (`TEXCOORD_1` of the Khronos MultiUVTest).

use furnace_scene::{Scene, VertexAttributes};
use glam::Vec4;

fn data(p: &str) -> std::path::PathBuf {
    furnace_tests::data::scene(p)
}

/// One triangle per entry of `colors` (side by side in x), each its own primitive with
/// `COLOR_0` given as `(componentType, type, bytes)`, or none.
fn triangles_with_colors(colors: &[Option<(u32, &str, Vec<u8>)>]) -> Vec<u8> {
    let mut bin = Vec::new();
    let (mut views, mut accessors, mut primitives) = (vec![], vec![], vec![]);
    for (k, color) in colors.iter().enumerate() {
        let x = 2.0 * k as f32;
        let off = bin.len();
        for p in [[x, 0.0, 0.0], [x + 1.0, 0.0, 0.0], [x, 1.0, 0.0]] {
            bin.extend(p.iter().flat_map(|c: &f32| c.to_le_bytes()));
        }
        views.push(format!(r#"{{"buffer":0,"byteOffset":{off},"byteLength":36}}"#));
        accessors.push(format!(
            r#"{{"bufferView":{},"componentType":5126,"count":3,"type":"VEC3","min":[{x},0,0],"max":[{},1,0]}}"#,
            views.len() - 1,
            x + 1.0
        ));
        let position = accessors.len() - 1;
        let mut attributes = format!(r#""POSITION":{position}"#);
        if let Some((component, kind, bytes)) = color {
            while bin.len() % 4 != 0 {
                bin.push(0);
            }
            let off = bin.len();
            bin.extend(bytes);
            views.push(format!(r#"{{"buffer":0,"byteOffset":{off},"byteLength":{}}}"#, bytes.len()));
            let normalized = if *component == 5126 { "" } else { r#","normalized":true"# };
            accessors.push(format!(
                r#"{{"bufferView":{},"componentType":{component}{normalized},"count":3,"type":"{kind}"}}"#,
                views.len() - 1
            ));
            attributes += &format!(r#","COLOR_0":{}"#, accessors.len() - 1);
        }
        primitives.push(format!(r#"{{"attributes":{{{attributes}}}}}"#));
    }
    while bin.len() % 4 != 0 {
        bin.push(0);
    }
    format!(
        r#"{{"asset":{{"version":"2.0"}},"scene":0,"scenes":[{{"nodes":[0]}}],"nodes":[{{"mesh":0}}],
"meshes":[{{"primitives":[{}]}}],
"buffers":[{{"byteLength":{},"uri":"data:application/octet-stream;base64,{}"}}],
"bufferViews":[{}],"accessors":[{}]}}"#,
        primitives.join(","),
        bin.len(),
        base64::encode(&bin),
        views.join(","),
        accessors.join(",")
    )
    .into_bytes()
}

/// The colour of triangle `t`'s vertex `v` (0, 1, 2) as the renderer interpolates it.
fn vertex_color(s: &Scene, t: usize, v: usize) -> Vec4 {
    let (b1, b2) = [(0.0, 0.0), (1.0, 0.0), (0.0, 1.0)][v];
    s.geometry.attributes(t, b1, b2).color
}

#[test]
fn vertex_colors_decode_in_every_encoding() {
    let rgb8 = vec![255u8, 0, 0, 0, 128, 0, 0, 0, 51];
    let rgba16: Vec<u8> = [65535u16, 0, 0, 32768, 0, 65535, 0, 65535, 13107, 13107, 13107, 0]
        .iter()
        .flat_map(|c| c.to_le_bytes())
        .collect();
    let rgba32: Vec<u8> = [0.25f32, 0.5, 0.75, 1.0, 1.0, 0.0, 0.5, 0.2, 0.0, 0.0, 0.0, 0.0]
        .iter()
        .flat_map(|c| c.to_le_bytes())
        .collect();
    let json = triangles_with_colors(&[
        Some((5121, "VEC3", rgb8)),
        Some((5123, "VEC4", rgba16)),
        Some((5126, "VEC4", rgba32)),
        None,
    ]);
    let s = Scene::from_slice(&json, "colors.gltf").expect("loads");
    assert_eq!(s.geometry.colors.len(), s.geometry.positions.len());
    let expected = [
        // u8 normalised: c / 255; RGB gets alpha 1.
        [
            Vec4::new(1.0, 0.0, 0.0, 1.0),
            Vec4::new(0.0, 128.0 / 255.0, 0.0, 1.0),
            Vec4::new(0.0, 0.0, 0.2, 1.0),
        ],
        // u16 normalised: c / 65535.
        [
            Vec4::new(1.0, 0.0, 0.0, 32768.0 / 65535.0),
            Vec4::new(0.0, 1.0, 0.0, 1.0),
            Vec4::new(0.2, 0.2, 0.2, 0.0),
        ],
        [Vec4::new(0.25, 0.5, 0.75, 1.0), Vec4::new(1.0, 0.0, 0.5, 0.2), Vec4::ZERO],
        // No COLOR_0: opaque white.
        [Vec4::ONE; 3],
    ];
    for (t, vertices) in expected.iter().enumerate() {
        for (v, e) in vertices.iter().enumerate() {
            let got = vertex_color(&s, t, v);
            // Stored as unorm16: within half a step of 1/65535 (and the decode's rounding).
            assert!(
                (got - *e).abs().max_element() <= 0.5 / 65535.0 + 1e-7,
                "triangle {t} vertex {v}: {got} vs {e}"
            );
        }
    }
    // Interpolated inside the triangle, as barycentrics weigh the vertices.
    let mid = s.geometry.attributes(2, 0.25, 0.25).color;
    let e = 0.5 * Vec4::new(0.25, 0.5, 0.75, 1.0) + 0.25 * Vec4::new(1.0, 0.0, 0.5, 0.2);
    assert!((mid - e).abs().max_element() < 1e-4, "{mid} vs {e}");
    // A scene without COLOR_0 stores none, and its hits read white.
    let plain = triangles_with_colors(&[None]);
    let s = Scene::from_slice(&plain, "plain.gltf").expect("loads");
    assert!(s.geometry.colors.is_empty());
    assert_eq!(s.geometry.attributes(0, 0.3, 0.3), VertexAttributes::default());
}

/// BoxVertexColors: the file's RGB colours, alpha 1; the default material's base colour is
/// multiplied by them.
#[test]
fn box_vertex_colors_multiply_the_base_colour() {
    let s = Scene::load(data("BoxVertexColors/glTF/BoxVertexColors.gltf")).expect("loads");
    assert_eq!(s.geometry.colors.len(), s.geometry.positions.len());
    let distinct: std::collections::HashSet<[u16; 4]> = s.geometry.colors.iter().copied().collect();
    assert!(distinct.len() > 4, "the box's faces have several colours: {distinct:?}");
    assert!(s.geometry.colors.iter().all(|c| c[3] == u16::MAX), "RGB colours are opaque");
    let at = s.geometry.attributes(0, 0.2, 0.3);
    let m = &s.materials[s.geometry.triangle_materials[0] as usize];
    let ms = m.evaluate(&at, &s.textures, &s.images);
    assert_eq!(ms.base_color, m.base_color_factor.truncate() * at.color.truncate());
}

/// MultiUVTest: the emissive texture samples TEXCOORD_1, the base colour TEXCOORD_0: both sets
/// are stored, each as the file gives it.
#[test]
fn a_second_uv_set_is_stored_and_sampled() {
    let s = Scene::load(data("MultiUVTest/glTF/MultiUVTest.gltf")).expect("loads");
    let m = &s.materials[0];
    assert_eq!(m.base_color_texture.as_ref().unwrap().tex_coord, 0);
    assert_eq!(m.emissive_texture.as_ref().unwrap().tex_coord, 1);
    assert_eq!(s.geometry.uv_sets(), 2);
    assert!(!s.warnings.iter().any(|w| w.message.contains("TEXCOORD")), "{:?}", s.warnings);
    // The two sets differ (the file lays the cube's faces out twice).
    let g = &s.geometry;
    let differ = (0..g.positions.len()).filter(|&i| g.uvs[2 * i] != g.uvs[2 * i + 1]).count();
    assert!(differ > g.positions.len() / 2, "{differ} of {} vertices", g.positions.len());
    // A hit samples the emissive texture at UV1 and the base colour at UV0.
    let at = g.attributes(0, 0.25, 0.25);
    assert_ne!(at.uv[0], at.uv[1]);
    let ms = m.evaluate(&at, &s.textures, &s.images);
    let emissive = m.emissive_texture.as_ref().unwrap().sample_bilinear(at.uv[1], &s.textures, &s.images);
    assert_eq!(ms.emission, m.emissive * emissive.truncate());
    let base = m.base_color_texture.as_ref().unwrap().sample_bilinear(at.uv[0], &s.textures, &s.images);
    assert_eq!(ms.base_color, (m.base_color_factor * base).truncate());
}
