//! `EXT_mesh_gpu_instancing`: each instance places its node's mesh (the Khronos
//! SimpleInstancing cubes where its TRANSLATION accessor puts them), an instance places it as a
//! node of the same TRS would (mirrored ones included), the triangle budget counts instances,
//! and malformed attributes are errors naming their glTF path.

use furnace_scene::{Scene, SceneError};
use glam::{Mat4, Quat, Vec3};

const EXT: &str = "EXT_mesh_gpu_instancing";

/// An accessor of the test files: `componentType`, `type`, `normalized`, `count` and its bytes
/// (no buffer view when `None`: all zeros).
struct Acc {
    component: u32,
    kind: &'static str,
    normalized: bool,
    count: u64,
    bytes: Option<Vec<u8>>,
}

fn floats(kind: &'static str, values: &[f32]) -> Acc {
    let width = if kind == "VEC4" { 4 } else { 3 };
    Acc {
        component: 5126,
        kind,
        normalized: false,
        count: (values.len() / width) as u64,
        bytes: Some(values.iter().flat_map(|v| v.to_le_bytes()).collect()),
    }
}

/// A file of one triangle, (0,0,0) (1,0,0) (0,1,0) without normals (accessor 0), placed by
/// node 0 (`node`, JSON); `extra` are accessors 1, 2, ….
fn gltf(node: &str, extra: &[Acc]) -> Vec<u8> {
    let mut bin: Vec<u8> = [[0.0f32, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]]
        .iter()
        .flatten()
        .flat_map(|c| c.to_le_bytes())
        .collect();
    let mut views = vec![r#"{"buffer":0,"byteOffset":0,"byteLength":36}"#.to_string()];
    let mut accessors = vec![
        r#"{"bufferView":0,"componentType":5126,"count":3,"type":"VEC3","min":[0,0,0],"max":[1,1,0]}"#
            .to_string(),
    ];
    for a in extra {
        let view = a.bytes.as_ref().map(|b| {
            while !bin.len().is_multiple_of(4) {
                bin.push(0);
            }
            views.push(format!(r#"{{"buffer":0,"byteOffset":{},"byteLength":{}}}"#, bin.len(), b.len()));
            bin.extend(b);
            format!(r#""bufferView":{},"#, views.len() - 1)
        });
        accessors.push(format!(
            r#"{{{}"componentType":{},"normalized":{},"count":{},"type":"{}"}}"#,
            view.unwrap_or_default(),
            a.component,
            a.normalized,
            a.count,
            a.kind
        ));
    }
    format!(
        r#"{{"asset":{{"version":"2.0"}},"extensionsUsed":["{EXT}"],"scene":0,"scenes":[{{"nodes":[0]}}],
"nodes":[{node}],"meshes":[{{"primitives":[{{"attributes":{{"POSITION":0}}}}]}}],
"buffers":[{{"byteLength":{},"uri":"data:application/octet-stream;base64,{}"}}],
"bufferViews":[{}],"accessors":[{}]}}"#,
        bin.len(),
        base64::encode(&bin),
        views.join(","),
        accessors.join(",")
    )
    .into_bytes()
}

/// A node of mesh 0 with the extension's `attributes` (JSON object body).
fn instanced(attributes: &str) -> String {
    format!(r#"{{"mesh":0,"extensions":{{"{EXT}":{{"attributes":{{{attributes}}}}}}}}}"#)
}

fn load(bytes: &[u8]) -> Result<Scene, SceneError> {
    Scene::from_slice(bytes, "inst.gltf")
}

/// The f32 values of accessor `index` of a `.gltf` with one `.bin` (tightly packed floats).
fn accessor_floats(gltf_path: &std::path::Path, index: usize) -> Vec<f32> {
    let doc = gltf::Gltf::open(gltf_path).unwrap();
    let acc = doc.accessors().nth(index).unwrap();
    let view = acc.view().unwrap();
    assert!(view.stride().is_none() && acc.data_type() == gltf::accessor::DataType::F32);
    let bin = std::fs::read(gltf_path.with_file_name("SimpleInstancing_data.bin")).unwrap();
    let start = view.offset() + acc.offset();
    let n = acc.count() * acc.dimensions().multiplicity();
    bin[start..start + 4 * n].chunks_exact(4).map(|b| f32::from_le_bytes([b[0], b[1], b[2], b[3]])).collect()
}

/// The 125 cubes: one cube stored once and placed 125 times; copied into world space
/// ([`Scene::flattened`]), 125 × its triangles, each instance's vertices its cube's, placed by
/// its TRANSLATION, ROTATION and SCALE: the cube's corner at the origin lands on the
/// translation.
#[test]
fn simple_instancing_places_125_cubes() {
    let path = furnace_tests::data::scene("SimpleInstancing/glTF/SimpleInstancing.gltf");
    let loaded = Scene::load(&path).unwrap();
    assert!(loaded.warnings.is_empty(), "{:?}", loaded.warnings);
    assert_eq!((loaded.instancing.meshes.len(), loaded.instancing.instances.len()), (1, 125));
    assert_eq!(loaded.geometry.triangles.len(), 12);
    let scene = loaded.flattened();
    // The cube: 36 indices (accessor 0) into 24 vertices (accessor 1) with normals, so each
    // instance copies its 24 vertices in order.
    let cube: Vec<Vec3> = accessor_floats(&path, 1).chunks_exact(3).map(Vec3::from_slice).collect();
    let cube_vertices = cube.len();
    assert_eq!(cube_vertices, 24);
    let per_cube = 36 / 3;
    assert_eq!(scene.geometry.triangles.len(), 125 * per_cube);
    assert_eq!(scene.geometry.positions.len(), 125 * cube_vertices);
    let corner = cube.iter().position(|&p| p == Vec3::ZERO).expect("a corner at the origin");

    let t = accessor_floats(&path, 3);
    let r = accessor_floats(&path, 4);
    let s = accessor_floats(&path, 5);
    assert_eq!((t.len(), r.len(), s.len()), (375, 500, 375));
    for i in 0..125 {
        let translation = Vec3::from_slice(&t[3 * i..3 * i + 3]);
        let rotation = Quat::from_slice(&r[4 * i..4 * i + 4]).normalize();
        let scale = Vec3::from_slice(&s[3 * i..3 * i + 3]);
        let placed = &scene.geometry.positions[i * cube_vertices..(i + 1) * cube_vertices];
        // R·S·0 + t is t exactly.
        assert_eq!(placed[corner], translation, "instance {i}");
        let m = Mat4::from_scale_rotation_translation(scale, rotation, translation);
        for (k, (&p, &q)) in placed.iter().zip(&cube).enumerate() {
            // f32 rounding of a rotation and scale of coordinates up to 12: a few ulps of 12.
            assert!((p - m.transform_point3(q)).abs().max_element() < 1e-5, "instance {i} vertex {k}: {p}");
        }
    }
    assert_eq!(
        loaded.extensions,
        [furnace_scene::ExtensionUse { name: EXT.into(), required: false }],
        "the file lists the extension as used"
    );
    assert!(loaded.extensions[0].honoured());
}

/// An instance places the mesh as a node of the same TRS does: the same positions (within
/// rounding: the two matrices are composed by different code) and the same triangles, wound the
/// other way round under a mirroring scale as a mirroring node winds them.
#[test]
fn an_instance_places_its_mesh_as_a_node_would() {
    let (t, r, s) = (Vec3::new(1.0, 2.0, 3.0), Quat::from_rotation_y(0.7), Vec3::new(-1.0, 2.0, 0.5));
    let node = format!(
        r#"{{"mesh":0,"translation":[{},{},{}],"rotation":[{},{},{},{}],"scale":[{},{},{}]}}"#,
        t.x, t.y, t.z, r.x, r.y, r.z, r.w, s.x, s.y, s.z
    );
    let by_node = load(&gltf(&node, &[])).unwrap();
    let attributes = r#""TRANSLATION":1,"ROTATION":2,"SCALE":3"#;
    let accessors =
        [floats("VEC3", &t.to_array()), floats("VEC4", &r.to_array()), floats("VEC3", &s.to_array())];
    let by_instance = load(&gltf(&instanced(attributes), &accessors)).unwrap();
    assert_eq!(by_instance.geometry.positions.len(), by_node.geometry.positions.len());
    // In order: a mirror reorders each triangle's vertices, so a winding unlike the node's
    // would put other vertices side by side here.
    for (a, b) in by_instance.geometry.positions.iter().zip(&by_node.geometry.positions) {
        // A few ulps of coordinates below 4.
        assert!((*a - *b).abs().max_element() < 1e-6, "{a} vs {b}");
    }
    // The mirror reverses the winding, so the face normal is the mirrored triangle's +z.
    let g = &by_instance.geometry;
    let [a, b, c] = g.triangles[0].map(|i| g.positions[i as usize]);
    let n = (b - a).cross(c - a).normalize();
    let expected = (Mat4::from_scale_rotation_translation(s, r, t).transform_vector3(Vec3::Z)).normalize();
    assert!(n.dot(expected) > 0.999, "winding {n} vs the placed +z {expected}");
}

/// Several instances, the node's transform applied after each instance's, and a ROTATION of
/// normalised shorts read as the float rotation within its quantisation.
#[test]
fn instances_compose_with_the_node_and_read_quantised_rotations() {
    let q = Quat::from_rotation_z(std::f32::consts::FRAC_PI_2);
    let shorts: Vec<u8> =
        q.to_array().iter().flat_map(|&c| ((c * 32767.0).round() as i16).to_le_bytes()).collect();
    let translations = floats("VEC3", &[0.0, 0.0, 0.0, 10.0, 0.0, 0.0]);
    let two =
        Acc { component: 5122, kind: "VEC4", normalized: true, count: 2, bytes: Some(shorts.repeat(2)) };
    let node = format!(
        r#"{{"mesh":0,"translation":[0,0,5],"extensions":{{"{EXT}":{{"attributes":{{"TRANSLATION":1,"ROTATION":2}}}}}}}}"#
    );
    let loaded = load(&gltf(&node, &[translations, two])).unwrap();
    assert_eq!(loaded.instancing.instances.len(), 2, "one mesh placed twice");
    let scene = loaded.flattened();
    let p = &scene.geometry.positions;
    assert_eq!(p.len(), 6, "two flat triangles");
    // (1, 0, 0) turned a quarter about z is (0, 1, 0); then the instance's and the node's
    // translations. Normalised shorts hold cos 45° within 1/32767: 1e-4 bounds the error.
    for (i, x) in [(0, 0.0), (1, 10.0)] {
        let b = p[3 * i + 1];
        assert!((b - Vec3::new(x, 1.0, 5.0)).abs().max_element() < 1e-4, "instance {i}: {b}");
        assert_eq!(p[3 * i], Vec3::new(x, 0.0, 5.0), "instance {i}'s origin");
    }
}

/// A small file naming a billion instances is refused by the instance budget (2²⁴) before
/// anything is read or allocated for them.
#[test]
fn the_instance_budget_is_checked_before_reading() {
    let billion = Acc { component: 5126, kind: "VEC3", normalized: false, count: 1_000_000_000, bytes: None };
    let bytes = gltf(&instanced(r#""TRANSLATION":1"#), &[billion]);
    assert!(bytes.len() < 2000, "a small file");
    let msg = load(&bytes).expect_err("a billion instances load").to_string();
    for part in ["inst.gltf", "scenes[0]", "1000000000 times", "2²⁴"] {
        assert!(msg.contains(part), "{msg:?} does not say {part:?}");
    }
}

/// Malformed attributes: an error naming the file and the attribute's glTF path.
#[test]
fn malformed_attributes_are_errors_naming_the_path() {
    let path = |name: &str| format!("nodes[0].extensions.{EXT}.attributes{name}");
    let cases: Vec<(String, Vec<Acc>, String, &str)> = vec![
        (
            r#""TRANSLATION":1,"SCALE":2"#.into(),
            vec![floats("VEC3", &[0.0; 6]), floats("VEC3", &[1.0; 9])],
            path(".SCALE"),
            "3 instances, but",
        ),
        (r#""ROTATION":1"#.into(), vec![floats("VEC3", &[0.0; 3])], path(".ROTATION"), "must be VEC4"),
        (
            r#""ROTATION":1"#.into(),
            vec![Acc {
                component: 5121,
                kind: "VEC4",
                normalized: true,
                count: 1,
                bytes: Some(vec![0, 0, 0, 255]),
            }],
            path(".ROTATION"),
            "normalised U8",
        ),
        (
            r#""TRANSLATION":1"#.into(),
            vec![floats("VEC3", &[0.0, f32::NAN, 0.0])],
            path(".TRANSLATION"),
            "NaN",
        ),
        (r#""SCALE":1"#.into(), vec![floats("VEC3", &[1.0, f32::INFINITY, 1.0])], path(".SCALE"), "inf"),
        (r#""ROTATION":1"#.into(), vec![floats("VEC4", &[0.0; 4])], path(".ROTATION"), "zero quaternion"),
        (r#""TRANSLATION":7"#.into(), vec![], path(".TRANSLATION"), "accessors"),
        (r#""_ID":1"#.into(), vec![floats("VEC3", &[0.0; 3])], path(""), "none of TRANSLATION"),
        (
            r#""TRANSLATION":1,"SCALE":2"#.into(),
            vec![floats("VEC3", &[0.0; 3]), floats("VEC3", &[1e30; 3])],
            path(""),
            "beyond f32's range",
        ),
    ];
    for (attributes, accessors, path, message) in cases {
        // The last case's node scales by 1e30 too: finite parts, an infinite product.
        let node =
            instanced(&attributes).replacen("{\"mesh\":0", "{\"mesh\":0,\"scale\":[1e30,1e30,1e30]", 1);
        let node = if message == "beyond f32's range" { node } else { instanced(&attributes) };
        let err = load(&gltf(&node, &accessors)).expect_err(&attributes);
        let msg = err.to_string();
        assert!(matches!(err, SceneError::Invalid { .. }), "{msg}");
        for part in ["inst.gltf", &path, message] {
            assert!(msg.contains(part), "{attributes}: {msg:?} does not say {part:?}");
        }
    }
    let no_attributes = format!(r#"{{"mesh":0,"extensions":{{"{EXT}":{{}}}}}}"#);
    let msg = load(&gltf(&no_attributes, &[])).expect_err("no attributes").to_string();
    assert!(msg.contains(&path("")) && msg.contains("missing"), "{msg}");
}

/// The built-in forest (`forest:N`): the same seed builds the same scene, another seed another;
/// three plant meshes stored once (about 2·10⁴, 10⁵ and 10⁴ triangles) placed by N instances
/// over world-space terrain, every instance within the scene's bounds.
#[test]
fn the_forest_is_seeded_and_instanced() {
    use furnace_scene::builtin::forest;
    let a = forest(40, 7);
    assert_eq!(a.content_hash(), forest(40, 7).content_hash());
    assert_ne!(a.content_hash(), forest(40, 8).content_hash());
    let inst = &a.instancing;
    assert_eq!((inst.meshes.len(), inst.instances.len(), inst.world_triangles), (3, 40, 131_072));
    let sizes: Vec<usize> = inst.meshes.iter().map(|r| r.len()).collect();
    assert_eq!(sizes, [19_392, 100_048, 10_000]);
    let (lo, hi) = a.bounds();
    let half = 0.5 * (40.0f32 * 36.0).sqrt().max(20.0);
    assert!(lo.x >= -half - 4.0 && hi.x <= half + 4.0 && hi.y < 30.0, "{lo} {hi}");
    // Every plant stands on the terrain: its instance's origin within the terrain's square.
    for i in &inst.instances {
        let t = i.world_from_object.translation;
        assert!(t.x.abs() <= half && t.z.abs() <= half, "{t}");
    }
}
