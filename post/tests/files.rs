//! EXR and PNG files: round trips, metadata, the Mitsuba reference, and atomic-write behaviour.

use furnace_post::{Metadata, PostError, read_exr, write_exr, write_png};
use glam::Vec3;
use std::fs;
use std::path::{Path, PathBuf};

/// A fresh, empty scratch directory under `target/test-output/post/`.
fn scratch(name: &str) -> PathBuf {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../target/test-output/post").join(name);
    let _ = fs::remove_dir_all(&dir);
    fs::create_dir_all(&dir).unwrap();
    dir
}

fn entries(dir: &Path) -> Vec<String> {
    let mut v: Vec<String> =
        fs::read_dir(dir).unwrap().map(|e| e.unwrap().file_name().to_string_lossy().into_owned()).collect();
    v.sort();
    v
}

/// A test image with awkward floats: subnormals, −0, ∞, NaN with a payload, extremes.
fn test_image(w: u32, h: u32) -> Vec<Vec3> {
    let special = [
        0.0,
        -0.0,
        f32::MIN_POSITIVE,
        f32::from_bits(1), // smallest subnormal
        f32::MAX,
        f32::INFINITY,
        f32::NEG_INFINITY,
        f32::from_bits(0x7fc0_1234), // NaN with a payload
        0.1,
        1.0 / 3.0,
        12345.678,
        -2.5,
    ];
    (0..w * h)
        .map(|i| {
            let f = |k: u32| {
                let j = (i * 3 + k) as usize;
                if j < special.len() { special[j] } else { (j as f32 * 0.618_034).fract() * 10.0 }
            };
            Vec3::new(f(0), f(1), f(2))
        })
        .collect()
}

fn full_metadata() -> Metadata {
    let mut m = Metadata {
        spp: Some(4096),
        sampler: Some("sobol".into()),
        bounces: Some(4),
        seed: Some(u64::MAX - 1),
        scene: Some("cbox.glb".into()),
        render_time_s: Some(12.345_678_901_234_567),
        rejected_samples: Some(3),
        extra: Default::default(),
    };
    m.extra.insert("furnace.gitRevision".into(), "abc123".into());
    m.extra.insert("note".into(), "UTF-8: Grüße, ∑ — ok".into());
    m
}

#[test]
fn exr_round_trip_is_bit_identical() {
    let dir = scratch("exr-round-trip");
    let path = dir.join("img.exr");
    let (w, h) = (37, 23); // odd sizes, not a multiple of any block size
    let pixels = test_image(w, h);
    let meta = full_metadata();
    write_exr(&path, w, h, &pixels, &meta).unwrap();
    let (rw, rh, back, back_meta) = read_exr(&path).unwrap();
    assert_eq!((rw, rh), (w, h));
    assert_eq!(back.len(), pixels.len());
    for (i, (a, b)) in pixels.iter().zip(&back).enumerate() {
        let bits = |v: &Vec3| v.to_array().map(f32::to_bits);
        assert_eq!(bits(a), bits(b), "pixel {i}: wrote {a}, read {b}");
    }
    assert_eq!(back_meta, meta);
    assert_eq!(entries(&dir), vec!["img.exr".to_string()], "no temporary file left");
}

#[test]
fn exr_empty_metadata_round_trips() {
    let dir = scratch("exr-empty-meta");
    let path = dir.join("img.exr");
    write_exr(&path, 1, 1, &[Vec3::new(1.0, 2.0, 3.0)], &Metadata::default()).unwrap();
    let (w, h, px, meta) = read_exr(&path).unwrap();
    assert_eq!((w, h, px), (1, 1, vec![Vec3::new(1.0, 2.0, 3.0)]));
    assert_eq!(meta, Metadata::default());
}

#[test]
fn exr_overwrite_replaces_whole_file() {
    let dir = scratch("exr-overwrite");
    let path = dir.join("img.exr");
    write_exr(&path, 4, 4, &[Vec3::ONE; 16], &Metadata::default()).unwrap();
    write_exr(&path, 2, 3, &[Vec3::splat(0.5); 6], &Metadata::default()).unwrap();
    let (w, h, px, _) = read_exr(&path).unwrap();
    assert_eq!((w, h), (2, 3));
    assert!(px.iter().all(|&p| p == Vec3::splat(0.5)));
    assert_eq!(entries(&dir), vec!["img.exr".to_string()]);
}

#[test]
fn bad_inputs_fail_cleanly_and_leave_nothing() {
    let dir = scratch("bad-inputs");
    let path = dir.join("img.exr");
    // Wrong pixel count.
    let err = write_exr(&path, 3, 3, &[Vec3::ZERO; 8], &Metadata::default()).unwrap_err();
    assert!(matches!(err, PostError::SizeMismatch { expected: 9, got: 8, .. }), "{err}");
    assert!(err.to_string().contains("img.exr"), "{err}");
    // Empty image.
    assert!(matches!(write_png(dir.join("e.png"), 0, 5, &[]), Err(PostError::SizeMismatch { .. })));
    // Reserved and invalid extra keys.
    for key in ["channels", "furnace.spp", "", "has space"] {
        let mut m = Metadata::default();
        m.extra.insert(key.into(), "x".into());
        let err = write_exr(&path, 1, 1, &[Vec3::ZERO], &m).unwrap_err();
        assert!(matches!(err, PostError::InvalidMetadataKey { .. }), "key '{key}': {err}");
    }
    // A target in a missing directory: an I/O error naming the file.
    let err = write_png(dir.join("missing/x.png"), 1, 1, &[[1, 2, 3]]).unwrap_err();
    assert!(matches!(err, PostError::Io { .. }) && err.to_string().contains("x.png"), "{err}");
    // Reading a file that is not an EXR (here: a truncated one).
    let good = dir.join("good.exr");
    write_exr(&good, 8, 8, &[Vec3::ONE; 64], &Metadata::default()).unwrap();
    let bytes = fs::read(&good).unwrap();
    let truncated = dir.join("truncated.exr");
    fs::write(&truncated, &bytes[..bytes.len() / 2]).unwrap();
    let err = read_exr(&truncated).unwrap_err();
    assert!(matches!(err, PostError::Exr { .. }) && err.to_string().contains("truncated.exr"), "{err}");
    let missing = read_exr(dir.join("nope.exr")).unwrap_err();
    assert!(matches!(missing, PostError::Io { .. }) && missing.to_string().contains("nope.exr"), "{missing}");
    assert_eq!(entries(&dir), vec!["good.exr".to_string(), "truncated.exr".to_string()]);
}

#[test]
fn invalid_furnace_attribute_is_reported() {
    // A furnace.spp that is not a number can only come from another writer; emulate one by
    // patching the text in a file we wrote (same length, so the header stays valid).
    let dir = scratch("bad-attr");
    let path = dir.join("img.exr");
    let m = Metadata { spp: Some(1234), ..Metadata::default() };
    write_exr(&path, 1, 1, &[Vec3::ZERO], &m).unwrap();
    let mut bytes = fs::read(&path).unwrap();
    let at = bytes.windows(4).position(|w| w == b"1234").unwrap();
    bytes[at..at + 4].copy_from_slice(b"12x4");
    fs::write(&path, bytes).unwrap();
    let err = read_exr(&path).unwrap_err();
    assert!(matches!(err, PostError::InvalidMetadataValue { .. }), "{err}");
    assert!(err.to_string().contains("furnace.spp") && err.to_string().contains("12x4"), "{err}");
}

#[test]
fn png_round_trip() {
    let dir = scratch("png");
    let path = dir.join("img.png");
    let (w, h) = (5u32, 3u32);
    let pixels: Vec<[u8; 3]> = (0..w * h).map(|i| [i as u8 * 17, 255 - i as u8, (i * i) as u8]).collect();
    write_png(&path, w, h, &pixels).unwrap();
    let img = image::open(&path).unwrap().to_rgb8();
    assert_eq!(img.dimensions(), (w, h));
    let back: Vec<[u8; 3]> = img.pixels().map(|p| p.0).collect();
    assert_eq!(back, pixels);
    assert_eq!(entries(&dir), vec!["img.png".to_string()]);
}

/// `image_mean_rgb` from the reference's JSON sidecar, parsed by hand (no JSON dependency).
fn json_mean_rgb(json: &str) -> [f64; 3] {
    let start = json.find("\"image_mean_rgb\"").expect("image_mean_rgb in the JSON");
    let open = start + json[start..].find('[').unwrap();
    let close = open + json[open..].find(']').unwrap();
    let v: Vec<f64> = json[open + 1..close].split(',').map(|s| s.trim().parse().unwrap()).collect();
    [v[0], v[1], v[2]]
}

#[test]
fn reads_mitsuba_reference() {
    let exr = furnace_tests::data::reference("cbox/cbox_ref_bounces4.exr");
    // Mitsuba 3.9.1 writes channels B, G, R as 32-bit float, PIZ-compressed, no alpha.
    let (w, h, pixels, meta) = read_exr(&exr).unwrap();
    assert_eq!((w, h), (256, 256));
    assert!(pixels.iter().all(|p| p.is_finite() && p.cmpge(Vec3::ZERO).all()));
    assert_eq!(meta.extra.get("generatedBy").map(String::as_str), Some("Mitsuba version 3.9.1"));
    assert_eq!(meta.spp, None);
    let mut sum = [0f64; 3];
    for p in &pixels {
        for k in 0..3 {
            sum[k] += f64::from(p[k]);
        }
    }
    let mean = sum.map(|s| s / pixels.len() as f64);
    let want = json_mean_rgb(
        &fs::read_to_string(furnace_tests::data::reference("cbox/cbox_ref_bounces4.json")).unwrap(),
    );
    // A file of another renderer has no resume state, and reads the same pixels with it.
    let back = furnace_post::read_exr_with_state(&exr).unwrap();
    assert_eq!((back.width, back.height, &back.pixels), (w, h, &pixels));
    assert!(back.state.is_none());
    // The sidecar's mean was computed from the same f32 pixels, so only the summation order
    // differs: agree to 1e-6 relative (channels would be swapped by ~20–60 % if B/R were mixed).
    for k in 0..3 {
        let rel = (mean[k] - want[k]).abs() / want[k];
        assert!(rel < 1e-6, "channel {k}: mean {} vs sidecar {} (rel {rel:e})", mean[k], want[k]);
    }
}
