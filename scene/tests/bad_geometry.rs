//! Bad geometry in an otherwise valid glTF file (what the program does at each edge is tabled
//! in `docs/stability.md`):
//!
//! * a NaN or infinite vertex position is an error that names the file, the mesh primitive, the
//!   accessor and the vertex (the glTF Validator reports such files as invalid,
//!   ACCESSOR_INVALID_FLOAT); so is a finite position that the node's transform takes beyond
//!   f32's range;
//! * zero-area triangles (a point, collinear vertices, a repeated index) are dropped, counted
//!   and reported in one warning; the valid triangles beside them are kept unchanged;
//! * huge coordinates (1e30, f32::MAX) and tiny ones (1e-30) load with their triangles kept
//!   and exact unit face normals (before, the f32 area test `|cross|` overflowed or underflowed
//!   and dropped them as degenerate), and the scene warns when its coordinates leave the range
//!   in which rendering was measured to be scale invariant ([`MIN_COORDINATE`] …
//!   [`MAX_COORDINATE`]).
//!
//! The glTF files are written in memory (one buffer as a data URI). Rendering such scenes
//! without NaN or panic is checked in `furnace-tests`' `tests/stability.rs`.

use furnace_scene::{MAX_COORDINATE, MIN_COORDINATE, Scene, SceneError, oct_decode};
use glam::{Mat4, Vec3};

/// A glTF with one mesh of one primitive: `positions` (f32 VEC3) and `indices` (u32), instanced
/// by one node with `matrix` (column-major), optionally with NORMALs. The POSITION accessor's
/// min/max are over the finite values (JSON has no NaN).
fn gltf(positions: &[Vec3], indices: &[u32], matrix: Mat4, normals: bool) -> Vec<u8> {
    let mut bin: Vec<u8> = positions.iter().flat_map(|p| p.to_array()).flat_map(f32::to_le_bytes).collect();
    let pos_len = bin.len();
    let mut normal_view = String::new();
    let mut normal_attr = String::new();
    if normals {
        let off = bin.len();
        bin.extend(positions.iter().flat_map(|_| [0.0f32, 0.0, 1.0]).flat_map(f32::to_le_bytes));
        normal_view = format!(r#",{{"buffer":0,"byteOffset":{off},"byteLength":{}}}"#, bin.len() - off);
        normal_attr = r#","NORMAL":2"#.into();
    }
    let idx_off = bin.len();
    bin.extend(indices.iter().flat_map(|i| i.to_le_bytes()));
    let finite: Vec<Vec3> = positions.iter().copied().filter(|p| p.is_finite()).collect();
    let lo = finite.iter().fold(Vec3::splat(f32::MAX), |a, b| a.min(*b));
    let hi = finite.iter().fold(Vec3::splat(f32::MIN), |a, b| a.max(*b));
    let f = |v: Vec3| format!("[{:e},{:e},{:e}]", v.x, v.y, v.z);
    let normal_accessor = if normals {
        format!(r#",{{"bufferView":2,"componentType":5126,"count":{},"type":"VEC3"}}"#, positions.len())
    } else {
        String::new()
    };
    let m: Vec<String> = matrix.to_cols_array().iter().map(|x| format!("{x:e}")).collect();
    let json = format!(
        r#"{{"asset":{{"version":"2.0"}},"scene":0,"scenes":[{{"nodes":[0]}}],
"nodes":[{{"mesh":0,"matrix":[{}]}}],
"meshes":[{{"name":"bad","primitives":[{{"attributes":{{"POSITION":0{normal_attr}}},"indices":1}}]}}],
"buffers":[{{"byteLength":{},"uri":"data:application/octet-stream;base64,{}"}}],
"bufferViews":[{{"buffer":0,"byteOffset":0,"byteLength":{pos_len}}},{{"buffer":0,"byteOffset":{idx_off},"byteLength":{}}}{normal_view}],
"accessors":[{{"bufferView":0,"componentType":5126,"count":{},"type":"VEC3","min":{},"max":{}}},
{{"bufferView":1,"componentType":5125,"count":{},"type":"SCALAR"}}{normal_accessor}]}}"#,
        m.join(","),
        bin.len(),
        base64::encode(&bin),
        bin.len() - idx_off,
        positions.len(),
        f(lo),
        f(hi),
        indices.len()
    );
    json.into_bytes()
}

/// A unit quad in z = 0 (two triangles) scaled by `s`, then `extra` vertices and triangles.
fn quad_plus(s: f32, extra: &[Vec3], extra_tris: &[[u32; 3]]) -> (Vec<Vec3>, Vec<u32>) {
    let mut p = vec![Vec3::ZERO, Vec3::X * s, Vec3::new(s, s, 0.0), Vec3::Y * s];
    let mut i = vec![0, 1, 2, 0, 2, 3];
    let base = p.len() as u32;
    p.extend_from_slice(extra);
    for t in extra_tris {
        i.extend(t.iter().map(|k| k + base));
    }
    (p, i)
}

fn load(bytes: &[u8]) -> Result<Scene, SceneError> {
    Scene::from_slice(bytes, "bad.gltf")
}

#[test]
fn non_finite_positions_are_an_error_naming_the_vertex() {
    for (bad, shown) in [
        (Vec3::new(f32::NAN, 0.0, 0.0), "NaN"),
        (Vec3::new(0.0, f32::INFINITY, 0.0), "inf"),
        (Vec3::new(0.0, 0.0, f32::NEG_INFINITY), "-inf"),
    ] {
        for normals in [false, true] {
            // The bad vertex (index 4) is used by a triangle; the error must come anyway.
            let (p, i) = quad_plus(1.0, &[bad, Vec3::ONE, Vec3::new(1.0, 2.0, 0.0)], &[[0, 1, 2]]);
            let err = load(&gltf(&p, &i, Mat4::IDENTITY, normals)).expect_err("a NaN/∞ position loads");
            let msg = err.to_string();
            assert!(matches!(err, SceneError::Invalid { .. }), "{msg}");
            for part in
                ["bad.gltf", "meshes[0].primitives[0].attributes.POSITION", "accessors[0]", "vertex 4", shown]
            {
                assert!(msg.contains(part), "{msg:?} does not name {part:?}");
            }
            assert_eq!(msg.lines().count(), 1, "{msg}");
        }
        // Also when no triangle uses it: the accessor is invalid.
        let (p, i) = quad_plus(1.0, &[bad], &[]);
        assert!(load(&gltf(&p, &i, Mat4::IDENTITY, false)).is_err());
    }
}

#[test]
fn a_transform_past_f32_range_is_an_error_naming_node_and_vertex() {
    // 1e30 × 1e10 = 1e40 > f32::MAX: finite data, finite matrix, infinite world position.
    let (p, i) = quad_plus(1e10, &[], &[]);
    let err = load(&gltf(&p, &i, Mat4::from_scale(Vec3::splat(1e30)), false)).expect_err("overflow loads");
    let msg = err.to_string();
    for part in ["bad.gltf", "nodes[0]", "meshes[0].primitives[0]", "vertex 1", "inf", "3.4e38"] {
        assert!(msg.contains(part), "{msg:?} does not name {part:?}");
    }
}

#[test]
fn zero_area_triangles_are_dropped_counted_and_reported() {
    let extra = [Vec3::new(2.0, 2.0, 0.0), Vec3::new(3.0, 3.0, 0.0), Vec3::new(4.0, 4.0, 0.0)];
    // A point (one vertex thrice), a repeated index, three collinear vertices.
    let tris = [[0, 0, 0], [0, 1, 0], [0, 1, 2]];
    for normals in [false, true] {
        let (p, i) = quad_plus(1.0, &extra, &tris);
        let scene = load(&gltf(&p, &i, Mat4::IDENTITY, normals)).expect("zero-area triangles load");
        assert_eq!(scene.dropped_triangles, 3, "normals {normals}");
        assert_eq!(scene.geometry.triangle_count(), 2, "the quad is kept");
        let w: Vec<String> = scene.warnings.iter().map(ToString::to_string).collect();
        assert!(w.iter().any(|w| w.contains("3 zero-area triangles dropped")), "{w:?}");
        for t in 0..2 {
            let [a, b, c] = scene.geometry.triangle(t).unwrap();
            assert!((b - a).cross(c - a).length() > 0.0);
        }
    }
    // Only zero-area triangles: nothing to render, said so.
    let p = [Vec3::ZERO, Vec3::X, Vec3::X * 2.0];
    let err = load(&gltf(&p, &[0, 1, 2], Mat4::IDENTITY, false)).expect_err("nothing to render");
    assert!(err.to_string().contains("all 1 triangles have zero area"), "{err}");
}

/// Huge and tiny coordinates: triangles kept, unit face normals exact (+z), the warning about
/// the measured range given exactly outside it.
#[test]
fn huge_and_tiny_coordinates_keep_their_triangles() {
    let mut rows = vec![];
    for s in [1e-30f32, 1e-12, 1e-4, 1e-3, 1.0, 1e6, 1e12, 1e13, 1e19, 1e30, f32::MAX / 2.0] {
        let (p, i) = quad_plus(s, &[], &[]);
        let scene = load(&gltf(&p, &i, Mat4::IDENTITY, false)).unwrap_or_else(|e| panic!("s = {s:e}: {e}"));
        assert_eq!((scene.geometry.triangle_count(), scene.dropped_triangles), (2, 0), "s = {s:e}");
        for n in &scene.geometry.normals {
            // Octahedral encoding of +z is exact.
            assert_eq!(oct_decode(*n), Vec3::Z, "s = {s:e}");
        }
        let w: Vec<String> = scene.warnings.iter().map(ToString::to_string).collect();
        let warned_big = w.iter().any(|w| w.contains("scale the scene down"));
        let warned_small = w.iter().any(|w| w.contains("scale the scene up"));
        let max = s; // the quad's largest coordinate
        assert_eq!(warned_big, max > MAX_COORDINATE, "s = {s:e}: {w:?}");
        assert_eq!(warned_small, max < MIN_COORDINATE, "s = {s:e}: {w:?}");
        rows.push(format!("{s:e}: {w:?}"));
    }
    println!("{}", rows.join("\n"));
    // The quad spanning ±f32::MAX: its edges overflow f32 (2·MAX = ∞) but the f64 normal holds.
    let p = [
        Vec3::new(-f32::MAX, -f32::MAX, 0.0),
        Vec3::new(f32::MAX, -f32::MAX, 0.0),
        Vec3::new(0.0, f32::MAX, 0.0),
    ];
    let scene = load(&gltf(&p, &[0, 1, 2], Mat4::IDENTITY, false)).expect("±f32::MAX loads");
    assert_eq!(scene.geometry.triangle_count(), 1);
    assert_eq!(oct_decode(scene.geometry.normals[0]), Vec3::Z);
}
