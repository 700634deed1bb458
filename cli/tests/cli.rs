//! End-to-end tests of the `furnace` binary.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn furnace(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_furnace")).args(args).output().expect("the furnace binary runs")
}

fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

/// A fresh, empty directory for one test.
fn temp_dir(name: &str) -> PathBuf {
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR")).join("furnace-cli").join(name);
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

fn data(path: &str) -> String {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../scene/tests/data").join(path).display().to_string()
}

#[test]
fn render_builtin_cornell_box_writes_png_and_exr() {
    let dir = temp_dir("render_builtin");
    let out = dir.join("x");
    let o = furnace(&[
        "render",
        "--width",
        "32",
        "--height",
        "32",
        "--spp",
        "4",
        "--quiet",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(dir.join("x.png").is_file());
    let (w, h, pixels, meta) = furnace_post::read_exr(dir.join("x.exr")).unwrap();
    assert_eq!((w, h), (32, 32));
    assert_eq!(meta.spp, Some(4));
    assert_eq!(meta.bounces, Some(4));
    assert_eq!(meta.sampler.as_deref(), Some("sobol"));
    assert_eq!(meta.scene.as_deref(), Some("<built-in cbox>"));
    assert_eq!(meta.rejected_samples, Some(0));
    assert!(meta.render_time_s.is_some_and(|t| t >= 0.0));
    let mean: f32 = pixels.iter().map(|p| p.x + p.y + p.z).sum::<f32>() / pixels.len() as f32;
    assert!(mean > 0.0 && mean.is_finite(), "mean {mean}");
    let png = image::open(dir.join("x.png")).unwrap();
    assert_eq!((png.width(), png.height()), (32, 32));
}

#[test]
fn out_with_extension_derives_the_other_file() {
    let dir = temp_dir("out_extension");
    let out = dir.join("y.exr");
    let o = furnace(&[
        "render",
        "--width",
        "8",
        "--height",
        "6",
        "--spp",
        "2",
        "--sampler",
        "cmj",
        "--bounces",
        "1",
        "--tonemap",
        "pbr-neutral",
        "--masking",
        "separable",
        "--compensation",
        "off",
        "--specular-sampling",
        "vndf",
        "--exposure",
        "-1",
        "--quiet",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(dir.join("y.png").is_file() && dir.join("y.exr").is_file());
    let (w, h, _, meta) = furnace_post::read_exr(&out).unwrap();
    assert_eq!((w, h, meta.spp, meta.bounces), (8, 6, Some(2), Some(1)));
    assert_eq!(meta.sampler.as_deref(), Some("cmj"));
}

#[test]
fn time_limit_stops_at_whole_passes_and_warns_for_fixed_n() {
    let dir = temp_dir("time_limit");
    let out = dir.join("t");
    let o = furnace(&[
        "render",
        "--width",
        "16",
        "--height",
        "16",
        "--spp",
        "1000000",
        "--sampler",
        "hammersley",
        "--time-limit",
        "0.5",
        "--quiet",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(stderr(&o).contains("warning: the hammersley sampler"), "{}", stderr(&o));
    let (_, _, _, meta) = furnace_post::read_exr(dir.join("t.exr")).unwrap();
    let spp = meta.spp.unwrap();
    assert!((4..1_000_000).contains(&spp) && spp % 4 == 0, "spp {spp}");
}

#[test]
fn missing_scene_is_one_line_and_exit_code_1() {
    let dir = temp_dir("missing");
    let o = furnace(&["render", "no-such-scene.glb", "--quiet", "--out", dir.join("m").to_str().unwrap()]);
    assert_eq!(o.status.code(), Some(1));
    let err = stderr(&o);
    assert!(err.starts_with("error: ") && err.contains("no-such-scene.glb"), "{err}");
    assert_eq!(err.trim_end().lines().count(), 1, "{err}");
    assert!(!dir.join("m.png").exists());

    let o = furnace(&["info", "no-such-scene.gltf"]);
    assert_eq!(o.status.code(), Some(1));
    assert!(stderr(&o).contains("no-such-scene.gltf"), "{}", stderr(&o));
}

#[test]
fn invalid_gltf_is_an_error_not_a_panic() {
    let dir = temp_dir("invalid");
    let bad = dir.join("bad.gltf");
    std::fs::write(&bad, "{ this is not json").unwrap();
    for cmd in ["render", "info"] {
        let o = furnace(&[cmd, bad.to_str().unwrap(), "--quiet"][..if cmd == "info" { 2 } else { 3 }]);
        assert_eq!(o.status.code(), Some(1), "{cmd}: {}", stderr(&o));
        let err = stderr(&o);
        assert!(err.starts_with("error: ") && err.contains("bad.gltf"), "{err}");
        assert!(!err.contains("panicked"), "{err}");
    }
    // A file the loader rejects structurally (no mesh).
    let o = furnace(&["info", &data("atteneder-edge-cases/Empty/Empty.gltf")]);
    assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
    assert!(stderr(&o).contains("Empty.gltf"), "{}", stderr(&o));
}

#[test]
fn info_prints_the_triangle_count() {
    let o = furnace(&["info", &data("Box/glTF-Binary/Box.glb")]);
    assert!(o.status.success(), "{}", stderr(&o));
    let text = String::from_utf8_lossy(&o.stdout);
    let line = text.lines().find(|l| l.starts_with("triangles")).unwrap_or_else(|| panic!("{text}"));
    assert_eq!(line.split_whitespace().nth(1), Some("12"), "{text}");
    assert!(text.contains("camera") && text.contains("bytes/triangle"), "{text}");
}

#[test]
fn info_on_the_cornell_box_file() {
    let o = furnace(&["info", &data("cbox/cbox.gltf")]);
    assert!(o.status.success(), "{}", stderr(&o));
    let text = String::from_utf8_lossy(&o.stdout);
    assert!(text.contains("20516"), "{text}");
    assert!(text.contains("sun") && text.contains("W/m²"), "{text}");
}

#[test]
fn bad_flag_values_fail_clearly() {
    for (args, needle) in [
        (&["render", "--tonemap", "bogus"][..], "bogus"),
        (&["render", "--sampler", "halton"][..], "halton"),
        (&["render", "--spp", "many"][..], "many"),
        (&["render", "--masking", "smith"][..], "smith"),
        (&["render", "--width", "0"][..], "0"),
        (&["render", "--nope"][..], "--nope"),
    ] {
        let o = furnace(args);
        assert_eq!(o.status.code(), Some(1), "{args:?}");
        let err = stderr(&o);
        assert!(err.starts_with("error: ") && err.contains(needle), "{args:?}: {err}");
        assert_eq!(err.trim_end().lines().count(), 1, "{args:?}: {err}");
        assert!(!err.contains("panicked"), "{err}");
    }
    let o = furnace(&["render", "--tonemap", "bogus"]);
    assert!(stderr(&o).contains("aces, pbr-neutral, clamp"), "{}", stderr(&o));
}

#[test]
fn unwritable_output_names_the_file() {
    let dir = temp_dir("unwritable");
    let out = dir.join("no/such/dir/z");
    let o = furnace(&[
        "render",
        "--width",
        "4",
        "--height",
        "4",
        "--spp",
        "1",
        "--quiet",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert_eq!(o.status.code(), Some(1));
    assert!(stderr(&o).contains("z.exr"), "{}", stderr(&o));
}

/// Renders the built-in Cornell box at `size`² and 4 spp with `seed` to `dir/name.exr`.
fn render_cbox(dir: &Path, name: &str, size: u32, seed: u32) -> String {
    let out = dir.join(name);
    let (size, seed) = (size.to_string(), seed.to_string());
    let o = furnace(&[
        "render",
        "--width",
        &size,
        "--height",
        &size,
        "--spp",
        "4",
        "--seed",
        &seed,
        "--quiet",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    dir.join(format!("{name}.exr")).display().to_string()
}

#[test]
fn compare_two_seeds_of_the_cornell_box() {
    let dir = temp_dir("compare");
    let a = render_cbox(&dir, "a", 16, 1);
    let b = render_cbox(&dir, "b", 16, 2);
    let map = dir.join("err.png");
    let o = furnace(&["compare", &a, &b, "--stderr", &b, "--error-map", map.to_str().unwrap()]);
    assert!(o.status.success(), "{}", stderr(&o));
    let text = String::from_utf8_lossy(&o.stdout);
    for key in ["RMSE", "relative MSE", "mean ratio", "z std", "|z| > 3"] {
        assert!(text.contains(key), "{key}: {text}");
    }
    let png = image::open(&map).unwrap();
    assert_eq!((png.width(), png.height()), (16, 16));
}

#[test]
fn compare_size_mismatch_names_both_files() {
    let dir = temp_dir("compare_mismatch");
    let a = render_cbox(&dir, "a", 16, 0);
    let b = render_cbox(&dir, "b", 8, 0);
    let o = furnace(&["compare", &a, &b]);
    assert_eq!(o.status.code(), Some(1));
    let err = stderr(&o);
    assert!(err.starts_with("error: ") && err.contains("a.exr") && err.contains("b.exr"), "{err}");
    assert_eq!(err.trim_end().lines().count(), 1, "{err}");
}
