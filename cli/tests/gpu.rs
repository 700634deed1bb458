//! End-to-end tests of `furnace render --backend gpu`: exact resume, Ctrl-C, resuming across
//! backends, and a machine without any GPU adapter.
//!
//! `--backend gpu` takes the best adapter there is, a software one included: in CI that is
//! Mesa's lavapipe (reported as "llvmpipe (LLVM …)"; `--adapter lavapipe` would not match it).
//! lavapipe is slow, so images are 8×8 or 16×16 with a few samples per pixel.
//!
//! Like the `furnace-gpu` tests, these need an adapter and **fail** without one unless
//! `FURNACE_SKIP_GPU_TESTS=1` is set (then they print that they skip and pass). The exception is
//! [`no_adapter_is_one_line_and_auto_falls_back_to_the_cpu`], which hides every adapter itself
//! and so runs everywhere.
//!
//! Resuming across backends (a render started on the CPU continued on the GPU, or the reverse)
//! is allowed: `--backend` is not among the settings that must match. Both integrators trace the
//! same sample indices of the same sampler, so the continuation adds exactly the samples that
//! were missing, computed by the other backend — an unbiased estimate of the same image, equal to
//! an uninterrupted render to float rounding of each path but not bit for bit.
//! [`resume_across_backends_adds_the_missing_samples_of_the_other_backend`] checks that
//! continuation to the bit.

use crate::common;

use common::*;
use std::path::{Path, PathBuf};
use std::process::{Command, Output};

/// `FURNACE_SKIP_GPU_TESTS=1`: this test is skipped (as `furnace_tests::gpu::test_context`).
fn skip_gpu() -> bool {
    let skip = std::env::var("FURNACE_SKIP_GPU_TESTS").is_ok_and(|v| v == "1");
    if skip {
        eprintln!("FURNACE_SKIP_GPU_TESTS=1: skipping a GPU test");
    }
    skip
}

/// `furnace render --width S --height S ARGS… --out DIR/NAME`; asserts success and that it
/// rendered on `backend` (from the summary line), returns the EXR's path.
fn render_ok(dir: &Path, name: &str, size: u32, backend: &str, args: &[&str]) -> PathBuf {
    let out = dir.join(name);
    let size = size.to_string();
    let mut all = vec!["render", "--backend", backend, "--width", &size, "--height", &size];
    all.extend_from_slice(args);
    all.extend_from_slice(&["--out", out.to_str().unwrap()]);
    let o = furnace(&all);
    assert!(o.status.success(), "{all:?}: {}", stderr(&o));
    assert_on(&o, backend);
    let exr = dir.join(format!("{name}.exr"));
    let record = backend_record(&exr);
    assert!(record.starts_with(&format!("{backend}: ")) && !record.contains(" → "), "{record}");
    exr
}

/// The file's `furnace.backend` record.
fn backend_record(exr: &Path) -> String {
    let meta = furnace_post::read_exr(exr).unwrap().3;
    meta.extra
        .get("furnace.backend")
        .cloned()
        .unwrap_or_else(|| panic!("{}: no furnace.backend", exr.display()))
}

/// `furnace render --backend BACKEND --resume FILE --spp SPP --out DIR/NAME`; asserts success
/// and the backend, returns the EXR's path.
fn resume_ok(dir: &Path, name: &str, file: &Path, backend: &str, spp: &str) -> PathBuf {
    let out = dir.join(name);
    let args = ["render", "--backend", backend, "--resume", file.to_str().unwrap(), "--spp", spp, "--out"];
    let o = Command::new(env!("CARGO_BIN_EXE_furnace")).args(args).arg(&out).output().unwrap();
    assert!(o.status.success(), "{args:?}: {}", stderr(&o));
    assert_on(&o, backend);
    // The record grows by this backend only when it differs from the last one, and then the
    // user is told that the result is no longer bit for bit an uninterrupted render.
    let exr = dir.join(format!("{name}.exr"));
    let (before, after) = (backend_record(file), backend_record(&exr));
    let last = after.rsplit(" → ").next().unwrap();
    assert!(last.starts_with(&format!("{backend}: ")), "{after}");
    let changed = before.rsplit(" → ").next() != Some(last);
    let expected = if changed { format!("{before} → {last}") } else { before };
    assert_eq!(after, expected);
    assert_eq!(stderr(&o).contains("note: continuing a render made on "), changed, "{}", stderr(&o));
    exr
}

/// The summary line names the backend that rendered (`…, gpu backend: …`).
fn assert_on(o: &Output, backend: &str) {
    let err = stderr(o);
    assert!(err.contains(&format!(" {backend} backend: ")), "expected a {backend} render: {err}");
    assert_eq!(err.contains("rendering on "), backend == "gpu", "adapter line: {err}");
}

#[test]
fn gpu_resume_two_plus_two_is_bit_identical_to_four() {
    if skip_gpu() {
        return;
    }
    let dir = temp_dir("gpu_resume_2_2");
    // Russian roulette on, 6 bounces: the paths use more sampler dimensions and branch on them.
    let settings = ["--russian-roulette", "on", "--bounces", "6", "--seed", "3"];
    let two = render_ok(&dir, "two", 16, "gpu", &[&settings[..], &["--spp", "2"]].concat());
    let four = render_ok(&dir, "four", 16, "gpu", &[&settings[..], &["--spp", "4"]].concat());
    // The uninterrupted render adds its 4 samples in one pass (a pass is up to 64 spp at 16×16),
    // the resumed one in two runs: the f64 film must agree across the boundary and the upload.
    let resumed = resume_ok(&dir, "two_two", &two, "gpu", "4");
    assert_same_render(&resumed, &four);
    assert_eq!(furnace_post::read_exr(&resumed).unwrap().3.spp, Some(4));
}

#[cfg(unix)]
#[test]
fn gpu_ctrl_c_saves_a_partial_render_that_resumes_exactly() {
    use std::io::Read;
    if skip_gpu() {
        return;
    }
    let dir = temp_dir("gpu_ctrl_c");
    let (mut child, mut reader, seen) = start_long_render(&dir.join("p"), 8, &["--backend", "gpu"]);
    assert!(seen.contains("rendering on "), "not on a GPU: {seen}");
    sigint(&child);
    let mut rest = String::new();
    reader.read_to_string(&mut rest).unwrap();
    let status = child.wait().unwrap();
    assert_eq!(status.code(), Some(130), "{rest}");
    assert!(rest.contains("interrupted") && rest.contains(" gpu backend: "), "{rest}");
    assert!(rest.contains("furnace render --resume"), "{rest}");
    assert!(dir.join("p.png").is_file());
    let exr = dir.join("p.exr");
    let (_, _, _, meta) = furnace_post::read_exr(&exr).unwrap();
    let spp = meta.spp.unwrap();
    // A GPU pass at 8×8 is 64 spp (2¹⁶ or 2²⁴ samples per pass, at most 64 spp): whole passes
    // only, at least one, far fewer than asked.
    assert!(spp >= 64 && spp % 64 == 0 && spp < 1_000_000, "spp {spp}");
    assert_eq!(meta.extra.get("furnace.target_spp").map(String::as_str), Some("1000000"));

    // Resume to one pass past the interruption, and compare with one uninterrupted render.
    let target = (spp + 64).to_string();
    let resumed = resume_ok(&dir, "resumed", &exr, "gpu", &target);
    let whole = render_ok(&dir, "whole", 8, "gpu", &["--spp", &target]);
    assert_same_render(&resumed, &whole);
}

/// Per-pixel `f64` sums (r, g, b) and counts of a furnace EXR's film.
fn film(path: &Path) -> (Vec<f64>, Vec<u64>) {
    let s = furnace_post::read_exr_with_state(path).unwrap().state.unwrap();
    (s.sums().iter().flat_map(|v| v.to_array()).collect(), s.counts().to_vec())
}

#[test]
fn resume_across_backends_adds_the_missing_samples_of_the_other_backend() {
    if skip_gpu() {
        return;
    }
    let dir = temp_dir("cross_backend");
    let size = 8;
    let cpu2 = render_ok(&dir, "cpu2", size, "cpu", &["--spp", "2"]);
    let cpu4 = render_ok(&dir, "cpu4", size, "cpu", &["--spp", "4"]);
    let gpu2 = render_ok(&dir, "gpu2", size, "gpu", &["--spp", "2"]);
    let gpu4 = render_ok(&dir, "gpu4", size, "gpu", &["--spp", "4"]);
    for (start, end, (first2, _), (other2, other4)) in
        [("cpu", "gpu", (&cpu2, &cpu4), (&gpu2, &gpu4)), ("gpu", "cpu", (&gpu2, &gpu4), (&cpu2, &cpu4))]
    {
        let resumed = resume_ok(&dir, &format!("{start}2_{end}4"), first2, end, "4");
        let record = backend_record(&resumed);
        assert!(
            record.starts_with(&format!("{start}: ")) && record.contains(&format!(" → {end}: ")),
            "{record}"
        );
        let (sums, counts) = film(&resumed);
        assert!(counts.iter().all(|&c| c == 4), "{start} → {end}: counts {counts:?}");
        assert_eq!(furnace_post::read_exr(&resumed).unwrap().3.spp, Some(4));
        // Expected: samples 0, 1 of the starting backend, then samples 2, 3 of the other one,
        // i.e. first2 + (other4 − other2). Sums of four f32 samples are exact in f64 unless
        // their exponents differ by more than 29 bits, so the two sides agree to a few f64
        // ulps: 1e-12 relative is 10⁴ ulps of headroom yet 10⁸ times below a sample's weight.
        let (a, _) = film(first2);
        let (b2, _) = film(other2);
        let (b4, _) = film(other4);
        let expected: Vec<f64> = (0..sums.len()).map(|i| a[i] + (b4[i] - b2[i])).collect();
        let tolerance = |e: f64| 1e-12 * e.abs().max(1.0);
        let bad: Vec<String> = (0..sums.len())
            .filter(|&i| (sums[i] - expected[i]).abs() > tolerance(expected[i]))
            .take(8)
            .map(|i| format!("pixel {} channel {}: {} vs {}", i / 3, i % 3, sums[i], expected[i]))
            .collect();
        assert!(
            bad.is_empty(),
            "{start} → {end}: the resumed film is not the {start}'s samples 0-1 plus the {end}'s \
             samples 2-3 ({}): {bad:#?}",
            resumed.display()
        );
        // The check can fail: continuing with samples 0, 1 again (a restart at index 0) would
        // give first2 + other2, which differs from the expectation in most pixels.
        let restart_matches =
            (0..sums.len()).filter(|&i| (a[i] + b2[i] - expected[i]).abs() <= tolerance(expected[i])).count();
        assert!(restart_matches < sums.len() / 2, "samples 2-3 look like samples 0-1: {restart_matches}");
    }
}

/// The environment of a machine without any adapter: no Vulkan driver (a missing ICD file)
/// and wgpu limited to Vulkan (otherwise it finds Mesa's OpenGL llvmpipe through EGL).
const NO_ADAPTER: [(&str, &str); 3] = [
    ("VK_ICD_FILENAMES", "/nonexistent/furnace-no-icd.json"),
    ("VK_DRIVER_FILES", "/nonexistent/furnace-no-icd.json"),
    ("WGPU_BACKEND", "vulkan"),
];

/// `furnace render --gpus 0,0 …`: two devices on the one adapter lavapipe exposes (as separate
/// as two GPUs for the code that shares the passes), against one device. Every pixel's samples
/// are the same values summed in another order, so the `f64` sums agree to
/// [`furnace_render::merge_bound`] and the counts exactly.
#[test]
fn two_devices_render_one_image_and_resume() {
    if skip_gpu() {
        return;
    }
    let dir = temp_dir("gpus");
    let run = |name: &str, args: &[&str]| {
        let out = dir.join(name);
        let mut all = vec!["render", "--backend", "gpu", "--width", "16", "--height", "16", "--bounces", "3"];
        all.extend_from_slice(args);
        all.extend_from_slice(&["--out", out.to_str().unwrap()]);
        let o = furnace(&all);
        assert!(o.status.success(), "{all:?}: {}", stderr(&o));
        (dir.join(format!("{name}.exr")), stderr(&o))
    };
    let (two, err) = run("two", &["--gpus", "0,0", "--spp", "4"]);
    assert!(err.contains("rendering on gpus: 2 × ") && err.contains(" gpus backend: "), "{err}");
    assert!(err.contains("warning: --gpus names adapter 0 more than once"), "{err}");
    assert!(backend_record(&two).starts_with("gpus: 2 × "), "{}", backend_record(&two));
    let (one, _) = run("one", &["--spp", "4"]);
    let (resumed, _) = run("resumed", &["--gpus", "0,0", "--resume", two.to_str().unwrap(), "--spp", "8"]);
    let (eight, _) = run("eight", &["--spp", "8"]);
    for (a, b, n) in [(&two, &one, 4), (&resumed, &eight, 8)] {
        let ((sa, ca), (sb, cb)) = (film(a), film(b));
        assert_eq!(ca, cb, "{}: counts", a.display());
        assert!(ca.iter().all(|&c| c == n));
        let bound = furnace_render::merge_bound(n);
        for (i, (x, y)) in sa.iter().zip(&sb).enumerate() {
            assert!((x - y).abs() <= bound * y.abs(), "{}: value {i}: {x} vs {y}", a.display());
        }
    }
    // A device lost before the second pass (FURNACE_LOSE_GPU): a warning, and the other
    // renders its samples again. At 16×16 a lavapipe device's pass is 64 spp, so a pass of the
    // two is 128: device 1 held 64..128 and was given 192..256.
    let lose = |spp: &str, name: &str| {
        let out = dir.join(name);
        let o = std::process::Command::new(env!("CARGO_BIN_EXE_furnace"))
            .args(["render", "--backend", "gpu", "--width", "16", "--height", "16", "--bounces", "3"])
            .args(["--gpus", "0,0", "--spp", spp, "--out", out.to_str().unwrap()])
            .env("FURNACE_LOSE_GPU", "1@1")
            .output()
            .unwrap();
        (o, dir.join(format!("{name}.exr")))
    };
    let (o, lost) = lose("256", "lost");
    let err = stderr(&o);
    assert!(o.status.success(), "{err}");
    assert!(
        err.contains("warning: GPU 1 (") && err.contains("left the render: the GPU device was lost"),
        "{err}"
    );
    assert!(err.contains("the other GPUs rendered its samples 64..128, 192..256 again"), "{err}");
    let (whole, _) = run("whole", &["--spp", "256"]);
    let ((sa, ca), (sb, cb)) = (film(&lost), film(&whole));
    assert_eq!(ca, cb, "every pixel has its 256 samples");
    let bound = furnace_render::merge_bound(256);
    assert!(sa.iter().zip(&sb).all(|(x, y)| (x - y).abs() <= bound * y.abs()));
    // On one device the fault injection does nothing, and says so.
    let o = std::process::Command::new(env!("CARGO_BIN_EXE_furnace"))
        .args(["render", "--backend", "gpu", "--width", "8", "--height", "8", "--spp", "4", "--gpus", "0"])
        .args(["--out", dir.join("one").to_str().unwrap()])
        .env("FURNACE_LOSE_GPU", "0@0")
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(stderr(&o).contains("warning: FURNACE_LOSE_GPU is ignored"), "{}", stderr(&o));
    // A list entry that names no adapter: the error lists those present.
    let o = furnace(&[
        "render",
        "--gpus",
        "0,no-such-gpu",
        "--spp",
        "1",
        "--out",
        dir.join("x").to_str().unwrap(),
    ]);
    assert!(!o.status.success());
    assert!(stderr(&o).contains("matching \"no-such-gpu\"; adapters present: 0: "), "{}", stderr(&o));
}

/// `furnace bench --gpus 0,0`: the devices' loads (each one's rate and busy share, the wait for
/// the slowest, the collection time) in the table and the JSON.
#[test]
fn bench_on_two_devices_reports_each_devices_load() {
    if skip_gpu() {
        return;
    }
    let args = ["bench", "--gpus", "0,0", "--width", "16", "--height", "16", "--spp", "8", "--bounces", "2"];
    let o = furnace(&[&args[..], &["--json", "-"]].concat());
    assert!(o.status.success(), "{}", stderr(&o));
    let err = stderr(&o);
    assert!(err.contains("GPU 0: ") && err.contains("GPU 1: ") && err.contains("busy "), "{err}");
    assert!(err.contains("of their time waiting for the slowest of a share"), "{err}");
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).expect("stdout is JSON");
    assert_eq!(v["backend"], "gpus");
    let devices = v["gpus"].as_array().expect("a list of devices");
    assert_eq!(devices.len(), 2);
    for (k, d) in devices.iter().enumerate() {
        assert_eq!(d["index"].as_u64(), Some(k as u64));
        // A device is busy for part of its shares' time (rounded, so at most 1).
        assert!(d["busy"].as_f64().is_some_and(|b| b > 0.0 && b <= 1.0), "{d}");
        assert!(d["msamples_per_s"].as_f64().is_some_and(|r| r > 0.0), "{d}");
    }
    assert!(v["gpus_idle"].as_f64().is_some_and(|i| (0.0..1.0).contains(&i)), "{v}");
    assert!(v["gpus_one_collection_seconds"].as_f64().is_some_and(|c| c > 0.0), "{v}");
    // One device reports no loads.
    let o =
        furnace(&["bench", "--backend", "gpu", "--width", "8", "--height", "8", "--spp", "1", "--json", "-"]);
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).expect("stdout is JSON");
    assert!(v["gpus"].is_null() && v["gpus_idle"].is_null(), "{v}");
}

#[test]
fn no_adapter_is_one_line_and_auto_falls_back_to_the_cpu() {
    let dir = temp_dir("no_adapter");
    let run = |backend: &str, name: &str| {
        Command::new(env!("CARGO_BIN_EXE_furnace"))
            .args(["render", "--backend", backend, "--width", "8", "--height", "8", "--spp", "1", "--out"])
            .arg(dir.join(name))
            .envs(NO_ADAPTER)
            .output()
            .unwrap()
    };
    let o = run("gpu", "g");
    let err = stderr(&o);
    assert_eq!(o.status.code(), Some(1), "{err}");
    assert!(err.starts_with("error: no GPU adapter found"), "{err}");
    assert!(err.contains("install a Vulkan driver"), "the error says what to do: {err}");
    assert_eq!(err.trim_end().lines().count(), 1, "{err}");
    assert!(!err.contains("panicked"), "{err}");
    assert!(!dir.join("g.exr").exists() && !dir.join("g.png").exists());

    // auto: no hardware adapter, so the CPU integrator, without a word about GPUs.
    let o = run("auto", "a");
    assert!(o.status.success(), "{}", stderr(&o));
    assert_on(&o, "cpu");
    assert!(!stderr(&o).contains("error"), "{}", stderr(&o));
    assert!(dir.join("a.exr").is_file() && dir.join("a.png").is_file());
}
