//! Compressed meshes: `KHR_draco_mesh_compression` and `EXT_meshopt_compression` files load to
//! the same triangles as their uncompressed twins (within the compression's quantisation), and
//! truncated or corrupted payloads are errors that name the file and the glTF path, never
//! panics.

use furnace_scene::{Scene, SceneError};
use furnace_tests::Rng;
use glam::{Vec2, Vec3};
use gltf::json::Value;

/// A scene of the workspace's test data (`tests/data/scenes/`).
fn data(p: &str) -> std::path::PathBuf {
    furnace_tests::data::scene(p)
}

/// The seed of the corruption tests.
const SEED: u64 = 0xd1ac_0c0d;

/// A scene's triangles in world space, each with its UVs (zeros without UVs) and shading
/// normals.
fn triangles(s: &Scene) -> Vec<([Vec3; 3], [Vec2; 3], [Vec3; 3])> {
    let g = &s.geometry;
    (0..g.triangle_count())
        .map(|t| {
            let p = g.triangle(t).expect("a triangle");
            let corners = [(0.0, 0.0), (1.0, 0.0), (0.0, 1.0)];
            let uv = corners.map(|(b1, b2)| if g.uvs.is_empty() { Vec2::ZERO } else { g.uv(t, b1, b2) });
            let n = corners.map(|(b1, b2)| g.shading_normal(t, b1, b2).expect("shading normals"));
            (p, uv, n)
        })
        .collect()
}

/// Checks that `got` has the triangles of `want`, in any order and starting at any corner but
/// wound the same way: positions within `pos_tol`, UVs within `uv_tol`, shading normals within
/// `normal_tol` (Euclidean distance of the unit vectors).
fn same_triangles(want: &Scene, got: &Scene, pos_tol: f32, uv_tol: f32, normal_tol: f32) {
    let (want, got) = (triangles(want), triangles(got));
    assert_eq!(want.len(), got.len(), "triangle counts");
    let mut used = vec![false; got.len()];
    let mut worst = (0.0f32, 0.0f32, 0.0f32);
    for (w, (wp, wuv, wn)) in want.iter().enumerate() {
        let centre = (wp[0] + wp[1] + wp[2]) / 3.0;
        // The nearest unused triangle by centroid, then the rotation of its corners that fits.
        let (g, _) = got
            .iter()
            .enumerate()
            .filter(|(g, _)| !used[*g])
            .map(|(g, (gp, _, _))| (g, ((gp[0] + gp[1] + gp[2]) / 3.0 - centre).length()))
            .min_by(|a, b| a.1.total_cmp(&b.1))
            .expect("an unused triangle");
        let (gp, guv, gn) = &got[g];
        let fit = (0..3)
            .map(|r| {
                let d = |k: usize| {
                    let j = (k + r) % 3;
                    (
                        (wp[k] - gp[j]).abs().max_element(),
                        (wuv[k] - guv[j]).abs().max_element(),
                        (wn[k] - gn[j]).length(),
                    )
                };
                let (a, b, c) = (d(0), d(1), d(2));
                (a.0.max(b.0).max(c.0), a.1.max(b.1).max(c.1), a.2.max(b.2).max(c.2))
            })
            .min_by(|a, b| a.0.total_cmp(&b.0))
            .expect("three rotations");
        assert!(
            fit.0 <= pos_tol && fit.1 <= uv_tol && fit.2 <= normal_tol,
            "triangle {w} {wp:?}: nearest is {gp:?}, off by {fit:?} (tolerances {pos_tol}, {uv_tol}, {normal_tol})"
        );
        used[g] = true;
        worst = (worst.0.max(fit.0), worst.1.max(fit.1), worst.2.max(fit.2));
    }
    println!("worst position, UV and normal differences: {worst:?}");
}

/// The quantisation of a Draco attribute, recovered from its decoded values: Draco stores
/// `q = round((v − min) / range × (2^bits − 1))` per component (one `range`, the largest extent
/// of any component), so the decoded values lie on a grid of step `range / (2^bits − 1)` from
/// each component's minimum. Returns the one bit count whose grid holds every value and the
/// grid's step.
fn draco_quantisation(stream: &[u8], unique_id: u32) -> (u32, f32) {
    let mut mesh = draco_core::Mesh::new();
    draco_core::MeshDecoder::new()
        .decode(&mut draco_core::DecoderBuffer::new(stream), &mut mesh)
        .expect("the Draco stream decodes");
    let att = mesh.attribute_by_unique_id(unique_id).expect("the attribute");
    let n = usize::from(att.num_components());
    let v = att.read_f32s(mesh.num_points(), n);
    let column = |c: usize| v.iter().skip(c).step_by(n).copied();
    let mins: Vec<f32> = (0..n).map(|c| column(c).fold(f32::MAX, f32::min)).collect();
    let range = (0..n).map(|c| column(c).fold(f32::MIN, f32::max) - mins[c]).fold(0.0, f32::max);
    let on_grid: Vec<(u32, f32)> = (1..=30u32)
        .map(|bits| (bits, range / ((1u64 << bits) - 1) as f32))
        .filter(|&(_, step)| {
            // 1e-2 of a step: f32 dequantisation is exact to a few ulp of the values, far below.
            v.iter().enumerate().all(|(i, &x)| {
                let q = f64::from(x - mins[i % n]) / f64::from(step);
                (q - q.round()).abs() < 1e-2
            })
        })
        .collect();
    assert_eq!(on_grid.len(), 1, "exactly one quantisation fits: {on_grid:?}");
    on_grid[0]
}

/// Whether the normals of Draco attribute `unique_id` lie on the octahedral grid of step
/// `1 / steps` (`steps` = 2^(bits − 1) − 1): their octahedral coordinates (the upper half folded
/// over the lower as Draco does) times `steps` are integers, to 1e-3 (f32 normalisation).
fn octahedral_on_grid(stream: &[u8], unique_id: u32, steps: f64) -> bool {
    let mut mesh = draco_core::Mesh::new();
    draco_core::MeshDecoder::new()
        .decode(&mut draco_core::DecoderBuffer::new(stream), &mut mesh)
        .expect("the Draco stream decodes");
    let att = mesh.attribute_by_unique_id(unique_id).expect("the attribute");
    att.read_f32s(mesh.num_points(), 3).chunks_exact(3).all(|n| {
        let l1 = f64::from(n[0].abs() + n[1].abs() + n[2].abs());
        let (x, y, z) = (f64::from(n[0]) / l1, f64::from(n[1]) / l1, f64::from(n[2]) / l1);
        let (u, v) =
            if z >= 0.0 { (x, y) } else { ((1.0 - y.abs()) * x.signum(), (1.0 - x.abs()) * y.signum()) };
        [u * steps, v * steps].iter().all(|q| (q - q.round()).abs() < 1e-3)
    })
}

#[test]
fn draco_duck_matches_the_uncompressed_duck() {
    let plain = Scene::load(data("Duck/glTF/Duck.gltf")).expect("Duck loads");
    let draco = Scene::load(data("Duck/glTF-Draco/Duck.gltf")).expect("Draco Duck loads");
    assert!(draco.warnings.is_empty(), "{:?}", draco.warnings);
    assert_eq!(draco.geometry.triangle_count(), 4212);
    let stream = std::fs::read(data("Duck/glTF-Draco/Duck.bin")).expect("Duck.bin");
    // The extension maps POSITION to Draco attribute 1 and TEXCOORD_0 to 2 (Duck.gltf).
    let (pos_bits, pos_step) = draco_quantisation(&stream[..10_366], 1);
    let (uv_bits, uv_step) = draco_quantisation(&stream[..10_366], 2);
    println!(
        "Draco quantisation: positions {pos_bits} bits (step {pos_step}), UVs {uv_bits} bits (step {uv_step})"
    );
    // Rounding to the grid moves a value by at most half a step; the node scales the model by
    // 0.01 into world space. Slack of 1e-6: the f32 rounding of the two world transforms of
    // coordinates up to 1.7 (a few ulp of 2).
    let pos_tol = 0.01 * pos_step / 2.0 + 1e-6;
    // Half a UV step, and 1e-6 for the f32 rounding of values up to 1.
    let uv_tol = uv_step / 2.0 + 1e-6;
    // Normals: Draco stores them as octahedral coordinates (u, v) on a grid of step 1/127 (8
    // bits; checked below). Rounding moves each coordinate by at most 0.5/127, which moves the
    // octahedron's point (u, v, 1 − |u| − |v|) by at most √6 · 0.5/127 (the third coordinate
    // moves by the sum of the first two); normalising stretches by at most √3 (that point's
    // length is at least 1/√3). 2e-4 more: the scene's own 16-bit octahedral encoding.
    assert!(octahedral_on_grid(&stream[..10_366], 0, 127.0), "Draco normals are 8-bit octahedral");
    let normal_tol = 0.5 / 127.0 * 6f32.sqrt() * 3f32.sqrt() + 2e-4;
    same_triangles(&plain, &draco, pos_tol, uv_tol, normal_tol);
}

#[test]
fn draco_boxes_match_the_box() {
    let plain = Scene::load(data("Box/glTF/Box.gltf")).expect("Box loads");
    for f in ["Box/glTF-Draco/Box.gltf", "gltf-transform/BoxDraco.gltf"] {
        let s = Scene::load(data(f)).unwrap_or_else(|e| panic!("{f}: {e}"));
        // The box's corners are ±0.5 and its normals axis-aligned: both lie on any Draco grid
        // that spans them (the corners are its ends), so only f32 rounding of the node's
        // rotation remains (1e-6 for coordinates of 0.5).
        same_triangles(&plain, &s, 1e-6, 0.0, 1e-6);
    }
}

#[test]
fn meshopt_box_matches_the_box() {
    let plain = Scene::load(data("Box/glTF/Box.gltf")).expect("Box loads");
    for f in ["gltf-transform/BoxMeshopt.gltf", "gltf-transform/BoxMeshopt.glb"] {
        let s = Scene::load(data(f)).unwrap_or_else(|e| panic!("{f}: {e}"));
        assert!(s.warnings.is_empty(), "{f}: {:?}", s.warnings);
        // Positions are snorm16 (±32767 is ±1, scaled by 0.5 by the node): the corners are
        // exact, so 1e-6 is the f32 rounding of the nodes' rotation and scale.
        // Normals are OCTAHEDRAL-filtered snorm8: an axis is exact on the octahedron, and 1e-6
        // is the rounding of the filter's normalisation.
        same_triangles(&plain, &s, 1e-6, 0.0, 1e-6);
    }
}

/// A glTF file of the test data with its buffer 0 embedded as a data URI, after `edit` has
/// changed its JSON and that buffer's bytes: a scene in memory, loaded by [`Scene::from_slice`].
/// Its textures (external files, which a scene in memory cannot read) are left out.
fn embedded(gltf: &str, edit: impl FnOnce(&mut Value, &mut Vec<u8>)) -> Vec<u8> {
    let path = data(gltf);
    let text = std::fs::read_to_string(&path).expect("the glTF");
    let mut json: Value = gltf::json::deserialize::from_str(&text).expect("JSON");
    for key in ["images", "textures", "samplers"] {
        json.as_object_mut().expect("an object").remove(key);
    }
    for m in json["materials"].as_array_mut().into_iter().flatten() {
        if let Some(pbr) = m["pbrMetallicRoughness"].as_object_mut() {
            pbr.remove("baseColorTexture");
        }
    }
    let uri = json["buffers"][0]["uri"].as_str().expect("buffers[0].uri").to_string();
    let mut bin = std::fs::read(path.with_file_name(uri)).expect("the buffer");
    edit(&mut json, &mut bin);
    json["buffers"][0]["byteLength"] = Value::from(bin.len());
    json["buffers"][0]["uri"] =
        Value::from(format!("data:application/octet-stream;base64,{}", base64::encode(&bin)));
    gltf::json::serialize::to_vec(&json).expect("serialised")
}

/// What loading one corrupted payload gave.
#[derive(Default, Debug)]
struct Outcomes {
    loaded: usize,
    /// Errors at the compressed primitive's or view's extension.
    codec_errors: usize,
    /// The decoder panicked (caught by the loader's guard and reported as an error).
    guarded_panics: usize,
    /// Errors elsewhere (a decoded index out of range, no triangles left, …).
    other_errors: usize,
    /// The last of them.
    last_other: Option<String>,
}

impl Outcomes {
    /// Records `result`; an error at an extension of a path starting with `prefix` is the
    /// codec's, and must name the file.
    fn record(&mut self, result: Result<Scene, SceneError>, name: &str, prefix: &str) {
        match result {
            Ok(_) => self.loaded += 1,
            Err(SceneError::Invalid { file, path, message })
                if path.starts_with(prefix) && path.contains(".extensions.") =>
            {
                assert_eq!(file, name);
                if message.contains("panicked") {
                    self.guarded_panics += 1;
                }
                self.codec_errors += 1;
            }
            Err(e) => {
                self.other_errors += 1;
                self.last_other = Some(e.to_string());
            }
        }
    }
}

#[test]
fn truncated_and_corrupted_draco_payloads_are_errors() {
    let name = "Duck.gltf";
    let ext_path = "meshes[0].primitives[0].extensions.KHR_draco_mesh_compression";
    let full = 10_366;
    let mut rng = Rng::new(SEED);
    // Truncation: the bitstream (bufferViews[0]) cut to a shorter length (at least 1 byte: a
    // view has some); every cut loses data the decoder needs, so every one is an error at the
    // extension.
    let mut cuts: Vec<usize> = (1..64).collect();
    cuts.extend((0..200).map(|_| 1 + rng.index(full - 1)));
    for cut in cuts {
        let bytes = embedded("Duck/glTF-Draco/Duck.gltf", |json, _| {
            json["bufferViews"][0]["byteLength"] = Value::from(cut);
        });
        let mut o = Outcomes::default();
        o.record(Scene::from_slice(&bytes, name), name, ext_path);
        assert_eq!(o.codec_errors, 1, "cut to {cut} bytes: {o:?}");
    }
    // Corruption: 1 to 4 bytes of the bitstream set to random values. Loading may succeed
    // (the geometry is then wrong) or fail, but never panics.
    let mut o = Outcomes::default();
    for _ in 0..1000 {
        let bytes = embedded("Duck/glTF-Draco/Duck.gltf", |_, bin| {
            for _ in 0..1 + rng.index(4) {
                bin[rng.index(full)] = rng.below(256) as u8;
            }
        });
        o.record(Scene::from_slice(&bytes, name), name, ext_path);
    }
    println!("Draco corruptions: {o:?}");
    assert!(o.codec_errors > 0, "{o:?}");
}

#[test]
fn truncated_and_corrupted_meshopt_payloads_are_errors() {
    let name = "BoxMeshopt.gltf";
    let mut rng = Rng::new(SEED);
    // Truncation: each compressed view's stream (its extension's byteLength) cut shorter, to
    // every length from 1 byte.
    let text = std::fs::read_to_string(data("gltf-transform/BoxMeshopt.gltf")).expect("glTF");
    let json: Value = gltf::json::deserialize::from_str(&text).expect("JSON");
    let views = json["bufferViews"].as_array().expect("bufferViews").len();
    for v in 0..views {
        let ext_path = format!("bufferViews[{v}].extensions.EXT_meshopt_compression");
        let length = json["bufferViews"][v]["extensions"]["EXT_meshopt_compression"]["byteLength"]
            .as_u64()
            .expect("byteLength") as usize;
        for cut in 1..length {
            let bytes = embedded("gltf-transform/BoxMeshopt.gltf", |json, _| {
                json["bufferViews"][v]["extensions"]["EXT_meshopt_compression"]["byteLength"] =
                    Value::from(cut);
            });
            let mut o = Outcomes::default();
            o.record(Scene::from_slice(&bytes, name), name, &ext_path);
            assert_eq!(o.codec_errors, 1, "bufferViews[{v}] cut to {cut} bytes: {o:?}");
        }
    }
    // Corruption: 1 to 4 bytes of the compressed buffer set to random values.
    let mut o = Outcomes::default();
    for _ in 0..2000 {
        let bytes = embedded("gltf-transform/BoxMeshopt.gltf", |_, bin| {
            for _ in 0..1 + rng.index(4) {
                let i = rng.index(bin.len());
                bin[i] = rng.below(256) as u8;
            }
        });
        o.record(Scene::from_slice(&bytes, name), name, "bufferViews[");
    }
    println!("meshopt corruptions: {o:?}");
    assert!(o.codec_errors > 0 && o.guarded_panics == 0, "{o:?}");
}

#[test]
fn meshopt_stream_of_a_newer_codec_version_is_named() {
    // The vertex stream's header byte (0xa0 | version) raised to version 2.
    let bytes = embedded("gltf-transform/BoxMeshopt.gltf", |json, bin| {
        let offset = json["bufferViews"][2]["extensions"]["EXT_meshopt_compression"]["byteOffset"]
            .as_u64()
            .expect("byteOffset") as usize;
        assert_eq!(bin[offset], 0xa0, "a version-0 vertex stream");
        bin[offset] = 0xa2;
    });
    let e = Scene::from_slice(&bytes, "BoxMeshopt.gltf").expect_err("version 2 is refused");
    let text = e.to_string();
    assert!(
        text.starts_with(
            "BoxMeshopt.gltf: bufferViews[2].extensions.EXT_meshopt_compression: vertex codec version 2"
        ),
        "{text}"
    );
}
