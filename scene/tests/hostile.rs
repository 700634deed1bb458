//! Hostile files (`tests/data/hostile/scene/`, described in `tests/data/hostile/README.md`):
//! each ends in one clear error naming the file and the glTF path, or loads with a warning
//! saying what was repaired; none panics, aborts, blocks or reads without end. FIFOs and device
//! files are made or named at test time.

use furnace_scene::{EnvironmentMap, LoadOptions, Projection, Scene, SceneError};
use glam::{Vec2, Vec3};
use std::path::PathBuf;
use std::sync::mpsc;
use std::time::Duration;

/// A file of `tests/data/hostile/scene/`.
fn hostile(name: &str) -> PathBuf {
    furnace_tests::data::data_dir().join("hostile/scene").join(name)
}

/// The error of loading `name` strictly (an image that cannot be used is an error, not a
/// warning).
fn load_err(name: &str) -> String {
    match Scene::load_with(hostile(name), &STRICT) {
        Ok(_) => panic!("{name} loaded"),
        Err(e) => e.to_string(),
    }
}

const STRICT: LoadOptions = LoadOptions { strict: true, variant: None, animation: None, time: None };

fn warnings(scene: &Scene) -> String {
    scene.warnings.iter().map(ToString::to_string).collect::<Vec<_>>().join("\n")
}

/// A camera whose `type` names the projection object it lacks is invalid glTF (gltf's
/// `Camera::projection` unwraps it and panicked): one error naming the camera, both ways round.
#[test]
fn a_camera_without_the_object_of_its_type_is_an_error() {
    for (file, name) in [
        ("camera_type_orthographic_perspective_object.gltf", "orthographic"),
        ("camera_type_perspective_orthographic_object.gltf", "perspective"),
    ] {
        let e = load_err(file);
        assert!(
            e.contains(file) && e.contains("cameras[0]") && e.contains(&format!("no \"{name}\" object")),
            "{e}"
        );
    }
}

/// Headers that claim 100 000 × 100 000 texels (a 55-byte `.hdr`, a 353-byte EXR whose data and
/// display windows lie, one whose data window alone does) are refused from the header; before,
/// the first asked the allocator for 120 GB and aborted.
#[test]
fn environment_maps_with_huge_headers_are_refused_before_decoding() {
    let e = EnvironmentMap::load(hostile("huge_header.hdr")).unwrap_err().to_string();
    assert!(e.contains("huge_header.hdr") && e.contains("100000 × 100000") && e.contains("2²⁸"), "{e}");
    let e = EnvironmentMap::load(hostile("huge_windows.exr")).unwrap_err().to_string();
    assert!(e.contains("huge_windows.exr") && e.contains("100000 × 100000"), "{e}");
    let e = EnvironmentMap::load(hostile("huge_data_window.exr")).unwrap_err().to_string();
    assert!(e.contains("huge_data_window.exr"), "{e}");

    let e = load_err("environment_huge_header.gltf");
    assert!(
        e.contains("environment_huge_header.gltf")
            && e.contains("scenes[0].extras.environment.uri")
            && e.contains("huge_header.hdr"),
        "{e}"
    );
    // The same bytes from memory.
    let bytes = std::fs::read(hostile("huge_header.hdr")).unwrap();
    let e = EnvironmentMap::from_bytes(&bytes, "in-memory.hdr").unwrap_err().to_string();
    assert!(e.contains("in-memory.hdr") && e.contains("100000 × 100000"), "{e}");
}

/// A PNG texture whose header claims 100 000 × 100 000 texels is refused from its header,
/// naming the image and the size: an error when loading strictly, else a warning and the
/// material without its texture.
#[test]
fn a_texture_with_a_huge_header_is_refused() {
    let e = load_err("texture_huge_dimensions.gltf");
    assert!(e.contains("images[0]") && e.contains("100000 × 100000") && e.contains("16384"), "{e}");
    let s = Scene::load(hostile("texture_huge_dimensions.gltf")).unwrap();
    let w = warnings(&s);
    assert!(w.contains("images[0]") && w.contains("100000 × 100000") && w.contains("left out"), "{w}");
    assert!(s.materials.iter().all(|m| m.base_color_texture.is_none()));
}

/// A buffer, image or environment URI that is an absolute path is refused (`Path::join` would
/// have read `/etc/passwd`), percent-encoded or not; the error names the URI, never the content.
#[test]
fn absolute_uris_are_refused() {
    for (file, path) in [
        ("buffer_absolute_uri.gltf", "buffers[0].uri"),
        ("buffer_absolute_uri_percent_encoded.gltf", "buffers[0].uri"),
        ("environment_absolute_uri.gltf", "scenes[0].extras.environment.uri"),
    ] {
        let e = load_err(file);
        assert!(e.contains(file) && e.contains(path) && e.contains("absolute path"), "{e}");
        assert!(!e.contains("root:"), "{e}");
    }
}

/// Runs `f` on another thread and fails if it takes more than 20 s (each case here finishes in
/// milliseconds; a FIFO would block for ever, `/dev/zero` read until memory ran out).
fn within_time<T: Send + 'static>(what: &str, f: impl FnOnce() -> T + Send + 'static) -> T {
    let (tx, rx) = mpsc::channel();
    std::thread::spawn(move || {
        let _ = tx.send(f());
    });
    rx.recv_timeout(Duration::from_secs(20)).unwrap_or_else(|_| panic!("{what}: still running after 20 s"))
}

/// Only regular files are read: a FIFO (as the scene, a buffer, an image, an environment map),
/// `/dev/zero` and `/dev/urandom` (directly and through a symbolic link beside the scene) are
/// one error each, promptly.
#[cfg(unix)]
#[test]
fn only_regular_files_are_read() {
    let dir = furnace_tests::data::output_dir("scene/hostile");
    let fifo = dir.join("fifo");
    let _ = std::fs::remove_file(&fifo);
    let made = std::process::Command::new("mkfifo").arg(&fifo).status().expect("mkfifo runs");
    assert!(made.success());
    let zero = dir.join("zero.bin");
    let _ = std::fs::remove_file(&zero);
    std::os::unix::fs::symlink("/dev/zero", &zero).unwrap();

    let f = fifo.clone();
    let e = within_time("Scene::load(FIFO)", move || Scene::load(&f).unwrap_err().to_string());
    assert!(e.contains("fifo") && e.contains("a FIFO"), "{e}");
    for dev in ["/dev/zero", "/dev/urandom"] {
        let e = within_time(dev, move || Scene::load(dev).unwrap_err().to_string());
        assert!(e.contains(dev) && e.contains("a device"), "{e}");
    }
    let f = fifo.clone();
    let e =
        within_time("EnvironmentMap::load(FIFO)", move || EnvironmentMap::load(&f).unwrap_err().to_string());
    assert!(e.contains("a FIFO"), "{e}");

    // Hostile scenes with their buffer, texture or environment URI pointed at the FIFO or at the
    // link to /dev/zero.
    let read = |f: &str| std::fs::read_to_string(hostile(f)).unwrap();
    let triangle = read("unused_emissive_material.gltf");
    let texture = read("texture_huge_dimensions.gltf");
    let cases = [
        ("buffer_fifo.gltf", replace_uri(&triangle, "data:application", "fifo"), "buffers[0]", "a FIFO"),
        (
            "buffer_zero.gltf",
            replace_uri(&triangle, "data:application", "zero.bin"),
            "buffers[0]",
            "a device",
        ),
        ("image_fifo.gltf", replace_uri(&texture, "data:image", "fifo"), "images[0]", "a FIFO"),
        ("image_zero.gltf", replace_uri(&texture, "data:image", "zero.bin"), "images[0]", "a device"),
        (
            "environment_fifo.gltf",
            read("environment_huge_header.gltf").replace("huge_header.hdr", "fifo"),
            "scenes[0].extras.environment.uri",
            "a FIFO",
        ),
    ];
    for (name, json, path, kind) in cases {
        let file = dir.join(name);
        std::fs::write(&file, json).unwrap();
        let e =
            within_time(name, move || Scene::load_with(&file, &STRICT).map(|_| ()).unwrap_err().to_string());
        assert!(e.contains(name) && e.contains(path) && e.contains(kind), "{e}");
    }
}

/// `json` with the first URI that starts with `prefix` replaced by `uri`.
fn replace_uri(json: &str, prefix: &str, uri: &str) -> String {
    let start = json.find(&format!("\"{prefix}")).expect("the URI") + 1;
    let end = start + json[start..].find('"').unwrap();
    format!("{}{uri}{}", &json[..start], &json[end..])
}

/// A buffer file shorter than its `byteLength` is an error naming both lengths; a longer one
/// is read up to its `byteLength` only.
#[test]
fn buffers_read_their_byte_length() {
    let dir = furnace_tests::data::output_dir("scene/hostile");
    let base = std::fs::read_to_string(hostile("unused_emissive_material.gltf")).unwrap();
    let positions: Vec<u8> =
        [-1.0f32, -1.0, 0.0, 1.0, -1.0, 0.0, 0.0, 1.0, 0.0].iter().flat_map(|f| f.to_le_bytes()).collect();
    let gltf = dir.join("buffer_file.gltf");
    std::fs::write(&gltf, replace_uri(&base, "data:application", "buffer_file.bin")).unwrap();

    std::fs::write(dir.join("buffer_file.bin"), &positions[..30]).unwrap();
    let e = Scene::load(&gltf).unwrap_err().to_string();
    assert!(e.contains("buffers[0]") && e.contains("30 bytes") && e.contains("byteLength 36"), "{e}");

    let mut longer = positions.clone();
    longer.extend(std::iter::repeat_n(0xAB, 1 << 16));
    std::fs::write(dir.join("buffer_file.bin"), &longer).unwrap();
    let s = Scene::load(&gltf).unwrap();
    assert_eq!(s.geometry.triangle_count(), 1);
}

/// An emissive material no triangle uses does not switch the studio light off; the same
/// material on the triangle does.
#[test]
fn only_used_emissive_materials_are_lights() {
    let s = Scene::load(hostile("unused_emissive_material.gltf")).unwrap();
    assert!(!s.has_own_light(), "an unused emissive material lit the scene");
    let json = std::fs::read_to_string(hostile("unused_emissive_material.gltf"))
        .unwrap()
        .replace("\"POSITION\": 0", "\"POSITION\": 0}, \"material\": 0, \"x\": {");
    let s = Scene::from_slice(json.as_bytes(), "used_emissive.gltf").unwrap();
    assert!(s.has_own_light());
}

/// The ray through the image centre of a 64 × 64 image of camera 0.
fn centre_ray(s: &Scene) -> furnace_scene::Ray {
    s.cameras[0].generate_ray(Vec2::new(32.0, 32.0), 64, 64)
}

/// Camera nodes at (0, 0, 3) with a scale of 10³⁰ or 10⁻³⁰ look down −Z from there (in f32 the
/// squared column lengths overflowed or underflowed and the rotation became NaN: a black image,
/// or only "non-finite samples rejected"); a quaternion of norm 2·10⁹ is normalised with a
/// warning; a scale of 0 leaves no view axis: the camera is ignored with a warning naming the
/// node and the camera.
#[test]
fn degenerate_camera_transforms_are_repaired_or_refused() {
    for file in ["camera_scale_1e30.gltf", "camera_scale_1e-30.gltf", "camera_rotation_norm_2e9.gltf"] {
        let s = Scene::load(hostile(file)).unwrap();
        let r = centre_ray(&s);
        // Tolerance: f32 rounding of the rotation and translation, a few ulps.
        assert!((r.origin - Vec3::new(0.0, 0.0, 3.0)).length() < 1e-5, "{file}: {r:?}");
        assert!((r.direction - Vec3::NEG_Z).length() < 1e-5, "{file}: {r:?}");
    }
    let s = Scene::load(hostile("camera_rotation_norm_2e9.gltf")).unwrap();
    let w = warnings(&s);
    assert!(w.contains("nodes[1].rotation") && w.contains("normalised"), "{w}");

    let s = Scene::load(hostile("camera_scale_zero.gltf")).unwrap();
    assert!(s.cameras.is_empty());
    let w = warnings(&s);
    assert!(w.contains("nodes[1]") && w.contains("cameras[0]") && w.contains("camera ignored"), "{w}");
}

/// Orthographic magnifications: zero is an error (glTF: must not be zero), negative is used by
/// its magnitude with a warning, 10³⁸ loads with a warning that the view may be black.
#[test]
fn orthographic_magnifications_are_checked() {
    let e = load_err("ortho_xmag_zero.gltf");
    assert!(e.contains("ortho_xmag_zero.gltf") && e.contains("cameras[0].orthographic.xmag"), "{e}");

    let s = Scene::load(hostile("ortho_mag_negative.gltf")).unwrap();
    assert_eq!(s.cameras[0].projection, Projection::Orthographic { xmag: 1.0, ymag: 1.0 });
    let w = warnings(&s);
    assert!(w.contains("cameras[0].orthographic.ymag") && w.contains("negative"), "{w}");

    let s = Scene::load(hostile("ortho_mag_1e38.gltf")).unwrap();
    let w = warnings(&s);
    assert!(w.contains("cameras[0].orthographic.ymag") && w.contains("may be black"), "{w}");
}

/// Errors are `SceneError`s of the kinds a caller can sort: the hostile files give `invalid`,
/// `image`, `environment` or `io`, never anything else.
#[test]
fn hostile_files_give_typed_errors() {
    for entry in std::fs::read_dir(hostile("")).unwrap() {
        let path = entry.unwrap().path();
        if path.extension().is_none_or(|x| x != "gltf") {
            continue;
        }
        if let Err(e) = Scene::load(&path) {
            assert!(
                matches!(
                    e,
                    SceneError::Invalid { .. } | SceneError::Image { .. } | SceneError::Environment { .. }
                ),
                "{}: {e}",
                path.display()
            );
        }
    }
}

/// What the mutation fuzzer (`fuzz.rs`) found, kept: a 441-byte EXR whose display window claims
/// 4 × 50 323 202 texels (under the 2²⁸ cap; it took seconds and gigabytes to decode into
/// zeros) is refused from its size; a GLB image with neither a `uri` nor a `bufferView` (gltf's
/// `Image::source` panicked) is an error naming it; an image in a buffer view without its
/// `mimeType` is decoded with a warning (the format is recognised from the bytes).
#[test]
fn fuzz_findings_are_one_error_or_a_warning() {
    let t = std::time::Instant::now();
    let e = EnvironmentMap::load(hostile("exr_lying_display_window.exr")).unwrap_err().to_string();
    assert!(
        e.contains("exr_lying_display_window.exr") && e.contains("4 × 50323202") && e.contains("truncated"),
        "{e}"
    );
    // Refused from the header: milliseconds; a second means the texels were decoded.
    assert!(t.elapsed() < Duration::from_secs(1), "{:?}", t.elapsed());

    let e = load_err("image_without_source.glb");
    assert!(e.contains("images[0]") && e.contains("neither a uri nor a bufferView"), "{e}");

    let glb = std::fs::read(furnace_tests::data::scene("BoxTextured/glTF-Binary/BoxTextured.glb")).unwrap();
    let key = b"\"mimeType\":\"image/png\"";
    let at = glb.windows(key.len()).position(|w| w == key).expect("the image's mimeType");
    let mut without = glb.clone();
    // Blanks keep the JSON chunk's length, so the GLB stays valid but for the missing key; the
    // comma before it goes too.
    without[at - 1..at + key.len()].fill(b' ');
    let s = Scene::from_slice(&without, "no_mime_type.glb").unwrap();
    let w = warnings(&s);
    assert!(w.contains("images[0].mimeType") && w.contains("recognised from the bytes"), "{w}");
    assert_eq!(s.images[0].width, 256);
}

/// A small file whose 300 meshes of 2²⁰ triangles (one accessor) are placed by 300 nodes names
/// 3·10⁸ triangles to store: it is refused from the accessors' counts, before anything is read,
/// naming the scene and the count.
#[test]
fn a_scene_of_too_many_instanced_triangles_is_refused() {
    // 300 meshes on one accessor of 2²⁰ triangles, each placed once: stored 300 times.
    let nodes = 300;
    let list: Vec<String> = (0..nodes).map(|i| i.to_string()).collect();
    let json = format!(
        r#"{{"asset": {{"version": "2.0"}}, "scene": 0, "scenes": [{{"nodes": [{}]}}],
        "nodes": [{}], "meshes": [{}],
        "accessors": [{{"componentType": 5126, "count": {}, "type": "VEC3", "min": [0, 0, 0], "max": [0, 0, 0]}}]}}"#,
        list.join(","),
        (0..nodes).map(|i| format!(r#"{{"mesh": {i}}}"#)).collect::<Vec<_>>().join(","),
        vec![r#"{"primitives": [{"attributes": {"POSITION": 0}}]}"#; nodes].join(","),
        3 << 20
    );
    let t = std::time::Instant::now();
    let e = Scene::from_slice(json.as_bytes(), "instanced.gltf").unwrap_err().to_string();
    assert!(
        e.contains("instanced.gltf") && e.contains("scenes[0]") && e.contains(&format!("{}", nodes << 20)),
        "{e}"
    );
    // From the counts alone: milliseconds; reading 300 meshes of 2²⁰ triangles takes seconds.
    assert!(t.elapsed() < Duration::from_secs(1), "{:?}", t.elapsed());
}

/// A shared mesh placed by more instances than a scene may have (2²⁴) is refused from the
/// accessor's count, before the instances are read.
#[test]
fn a_scene_of_too_many_instances_is_refused() {
    let json = format!(
        r#"{{"asset": {{"version": "2.0"}}, "scene": 0, "scenes": [{{"nodes": [0]}}],
        "nodes": [{{"mesh": 0, "extensions": {{"EXT_mesh_gpu_instancing": {{"attributes": {{"TRANSLATION": 1}}}}}}}}],
        "meshes": [{{"primitives": [{{"attributes": {{"POSITION": 0}}}}]}}],
        "accessors": [{{"componentType": 5126, "count": 3, "type": "VEC3", "min": [0, 0, 0], "max": [0, 0, 0]}},
                      {{"componentType": 5126, "count": {}, "type": "VEC3"}}]}}"#,
        (1u64 << 24) + 1
    );
    let e = Scene::from_slice(json.as_bytes(), "forest.gltf").unwrap_err().to_string();
    assert!(e.contains("forest.gltf") && e.contains("scenes[0]") && e.contains("16777217"), "{e}");
}
