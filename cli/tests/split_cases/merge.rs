//! Split renders: `furnace render --samples A..B` and `furnace merge` (a module of `cli.rs`, so
//! that it links into that test binary).

use super::render_ok;
use crate::common::*;
use furnace_render::merge_bound;
use std::path::{Path, PathBuf};

/// The built-in Cornell box at 16×16 (a CPU pass is 4 spp there) with `args`.
fn part(dir: &Path, name: &str, args: &[&str]) -> PathBuf {
    render_ok(dir, name, 16, args)
}

/// `furnace merge PARTS… --out DIR/NAME [extra]`.
fn merge(dir: &Path, name: &str, parts: &[&Path], extra: &[&str]) -> std::process::Output {
    let out = dir.join(name);
    let mut args: Vec<&str> = vec!["merge", "--quiet"];
    args.extend(parts.iter().map(|p| p.to_str().unwrap()));
    args.extend_from_slice(&["--out", out.to_str().unwrap()]);
    args.extend_from_slice(extra);
    furnace(&args)
}

/// The merged film equals the single run's: the same counts, rejected samples and metadata
/// (render time and merge records aside), every `f64` sum within [`merge_bound`] of the single
/// run's (relative to the pixel's sum: radiance is never negative), and the `f32` image within
/// one ulp (the means of sums that differ by ≤ 2·10⁻¹⁵ relative round to the same `f32` or a
/// neighbour). Returns how many of the image's values differ at all.
fn assert_merge_equals_one_run(merged: &Path, single: &Path) -> usize {
    let m = furnace_post::read_exr_with_state(merged).unwrap();
    let s = furnace_post::read_exr_with_state(single).unwrap();
    let (fm, fs) = (m.state.unwrap(), s.state.unwrap());
    assert_eq!(fm.counts(), fs.counts());
    assert_eq!(fm.rejected(), fs.rejected());
    for (i, (a, b)) in fm.sums().iter().zip(fs.sums()).enumerate() {
        let bound = merge_bound(fs.counts()[i]) * b.max_element().max(0.0);
        let diff = (*a - *b).abs().max_element();
        assert!(diff <= bound, "pixel {i}: merged {a} single {b}: |Δ| {diff:e} > bound {bound:e}");
    }
    let mut differ = 0;
    for (a, b) in m.pixels.iter().zip(&s.pixels) {
        for c in 0..3 {
            let (x, y) = (a[c].to_bits(), b[c].to_bits());
            assert!(x.abs_diff(y) <= 1, "f32 image: {} vs {}", a[c], b[c]);
            differ += usize::from(x != y);
        }
    }
    assert_eq!(fm.aov_sums().is_some(), fs.aov_sums().is_some());
    let (mut mm, mut ms) = (m.metadata, s.metadata);
    for meta in [&mut mm, &mut ms] {
        meta.render_time_s = None;
        meta.extra.remove("furnace.merged_parts");
    }
    assert_eq!(mm, ms);
    differ
}

#[test]
fn parts_merge_into_the_single_run() {
    let dir = temp_dir("split_merge");
    // Progressive (sobol, with AOVs) and fixed-N (hammersley: the parts need N) samplers; uneven
    // parts given out of order; the first part from 0 enters the merged film bit for bit.
    for (tag, extra) in
        [("sobol", &["--aovs", "--seed", "5"][..]), ("hammersley", &["--sampler", "hammersley"][..])]
    {
        let with = |more: &[&'static str]| -> Vec<&'static str> { [extra, more].concat() };
        let single = part(&dir, &format!("{tag}_single"), &with(&["--spp", "12"]));
        let a = part(&dir, &format!("{tag}_a"), &with(&["--samples", "0..5", "--spp", "12"]));
        let b = part(&dir, &format!("{tag}_b"), &with(&["--samples", "5..9", "--spp", "12"]));
        let c = part(&dir, &format!("{tag}_c"), &with(&["--samples", "9..12", "--spp", "12"]));
        let (_, _, _, meta) = furnace_post::read_exr(&b).unwrap();
        assert_eq!(meta.spp, Some(4), "a part's spp is the samples it holds");
        assert_eq!(meta.extra.get("furnace.sample_range").map(String::as_str), Some("5..9"));
        let o = merge(&dir, &format!("{tag}_merged"), &[&c, &a, &b], &[]);
        assert!(o.status.success(), "{}", stderr(&o));
        let merged = dir.join(format!("{tag}_merged.exr"));
        assert!(dir.join(format!("{tag}_merged.png")).is_file());
        let differ = assert_merge_equals_one_run(&merged, &single);
        // 16×16×3 values, each a mean of 12 samples: a 1-ulp difference needs a sum within
        // ≈ 2⁻⁵² of an f32 rounding boundary, which none of the 768 here is (seeds fixed).
        assert_eq!(differ, 0, "{tag}: {differ} f32 values differ");
        // The merge is an ordinary render: it resumes, to what a single run gives to rounding.
        let more = dir.join(format!("{tag}_merged_16"));
        let o = furnace(&[
            "render",
            "--quiet",
            "--resume",
            merged.to_str().unwrap(),
            "--spp",
            if tag == "sobol" { "16" } else { "12" },
            "--out",
            more.to_str().unwrap(),
        ]);
        assert!(o.status.success(), "{}", stderr(&o));
        if tag == "sobol" {
            let single16 = part(&dir, "sobol_single_16", &with(&["--spp", "16"]));
            assert_merge_equals_one_run(&dir.join("sobol_merged_16.exr"), &single16);
        }
    }
}

#[test]
fn a_stopped_part_resumes_to_its_end() {
    let dir = temp_dir("split_resume");
    // A time limit stops the part after its first pass (4 of its 8 samples at 16×16).
    let partial = part(&dir, "late", &["--samples", "4..12", "--time-limit", "0.001"]);
    let (_, _, _, meta) = furnace_post::read_exr(&partial).unwrap();
    assert_eq!(meta.spp, Some(4));
    assert_eq!(meta.extra.get("furnace.target_spp").map(String::as_str), Some("12"), "N defaults to B");
    let early = part(&dir, "early", &["--samples", "0..4", "--spp", "12"]);
    let single = part(&dir, "single", &["--spp", "12"]);
    // Missing 8..12: the merge names the part that stopped and how to continue it.
    let o = merge(&dir, "m", &[&early, &partial], &[]);
    assert_eq!(o.status.code(), Some(1));
    let err = stderr(&o);
    assert!(
        err.contains("samples missing from the 12-sample render: samples 8..12 (part ")
            && err
                .contains("late.exr (4..12) stopped at sample 8: continue it with `furnace render --resume"),
        "{err}"
    );
    assert!(!dir.join("m.exr").exists() && !dir.join("m.png").exists(), "a refused merge writes nothing");
    let o = furnace(&["render", "--quiet", "--resume", partial.to_str().unwrap()]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert_eq!(furnace_post::read_exr(&partial).unwrap().3.spp, Some(8), "resumed to its end, in place");
    // Resuming a finished part renders nothing (what a requeued task that had finished does).
    let o = furnace(&["render", "--resume", partial.to_str().unwrap()]);
    assert!(o.status.success() && stderr(&o).contains("already holds every sample of its part 4..12"));
    let o = merge(&dir, "m", &[&partial, &early], &[]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert_merge_equals_one_run(&dir.join("m.exr"), &single);
}

#[test]
fn merge_refuses_what_is_not_one_render() {
    let dir = temp_dir("split_refuse");
    let a = part(&dir, "a", &["--samples", "0..8", "--spp", "12"]);
    let b = part(&dir, "b", &["--samples", "4..12", "--spp", "12"]);
    let c = part(&dir, "c", &["--samples", "8..12", "--spp", "12"]);
    let seed = part(&dir, "seed", &["--samples", "8..12", "--spp", "12", "--seed", "9"]);
    let one_line = |o: &std::process::Output| {
        assert_eq!(o.status.code(), Some(1));
        let e = stderr(o);
        assert_eq!(e.trim_end().lines().count(), 1, "{e}");
        e
    };
    let e = one_line(&merge(&dir, "m", &[&a, &b], &[]));
    assert!(
        e.contains("overlapping parts")
            && e.contains("a.exr and ")
            && e.contains("b.exr both hold samples 4..8"),
        "{e}"
    );
    let e = one_line(&merge(&dir, "m", &[&a, &seed], &[]));
    assert!(
        e.contains("seed.exr: not a part of the render of ") && e.contains("seed is 0 there but 9 here"),
        "{e}"
    );
    let e = one_line(&merge(&dir, "m", &[&a, &a], &[]));
    assert!(e.contains("overlapping parts"), "{e}");
    let e = one_line(&merge(&dir, "a", &[&a, &c], &[]));
    assert!(e.contains("a.exr: the output would replace this part"), "{e}");
    let not_furnace = dir.join("plain.exr");
    furnace_post::write_exr(&not_furnace, 1, 1, &[glam::Vec3::ONE], &furnace_post::Metadata::default())
        .unwrap();
    let e = one_line(&merge(&dir, "m", &[&a, &not_furnace], &[]));
    assert!(e.contains("plain.exr: no 'furnace.spp' attribute"), "{e}");
    assert!(!dir.join("m.exr").exists(), "nothing written");

    // Gaps: refused, then merged with --allow-gaps into a file that says what it holds.
    let first = part(&dir, "first", &["--samples", "0..4", "--spp", "12"]);
    let e = one_line(&merge(&dir, "m", &[&first, &c], &[]));
    assert!(e.contains("samples 4..8 (no part renders them)") && e.contains("--allow-gaps"), "{e}");
    let o = merge(&dir, "gappy", &[&first, &c], &["--allow-gaps"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let r = furnace_post::read_exr_with_state(dir.join("gappy.exr")).unwrap();
    assert_eq!(r.metadata.spp, Some(8));
    assert_eq!(r.metadata.extra.get("furnace.samples").map(String::as_str), Some("0..4,8..12"));
    assert!(r.state.unwrap().counts().iter().all(|&n| n == 8));
    let o = furnace(&["render", "--resume", dir.join("gappy.exr").to_str().unwrap()]);
    assert!(
        stderr(&o).contains("a merge of parts with samples missing (it holds samples 0..4,8..12)"),
        "{}",
        stderr(&o)
    );

    // Bad ranges.
    for (args, want) in [
        (
            &["--samples", "8..16", "--spp", "12"][..],
            "--samples 8..16 goes past the render's 12 samples per pixel",
        ),
        (&["--samples", "0..4", "--sampler", "cmj"][..], "needs the whole render's N: give --spp N"),
        (&["--samples", "4..4"][..], "A must be less than B"),
    ] {
        let mut all = vec!["render", "--width", "4", "--height", "4", "--out", "/nonexistent/x"];
        all.extend_from_slice(args);
        let e = one_line(&furnace(&all));
        assert!(e.contains(want), "{args:?}: {e}");
    }
}

/// `--checkpoint` saves while rendering: a process killed without warning (SIGKILL) leaves a
/// resumable file, and SIGTERM (a scheduler's cancel) saves like Ctrl-C.
#[cfg(unix)]
#[test]
fn checkpoints_and_sigterm_keep_the_work() {
    use std::io::Read;
    let dir = temp_dir("checkpoint");
    let out = dir.join("k");
    let (mut child, _reader, _) = start_long_render(&out, 32, &["--checkpoint", "0.05"]);
    let exr = dir.join("k.exr");
    let start = std::time::Instant::now();
    while !exr.exists() {
        assert!(start.elapsed().as_secs() < 60, "no checkpoint written in 60 s");
        std::thread::sleep(std::time::Duration::from_millis(20));
    }
    child.kill().unwrap();
    child.wait().unwrap();
    let spp = furnace_post::read_exr(&exr).unwrap().3.spp.unwrap();
    let target = (spp + 4).to_string();
    let o = furnace(&["render", "--quiet", "--resume", exr.to_str().unwrap(), "--spp", &target]);
    assert!(o.status.success(), "{}", stderr(&o));
    let whole = render_ok(&dir, "whole", 32, &["--spp", &target]);
    assert_same_render(&exr, &whole);

    let (child, mut reader, _) = start_long_render(&dir.join("t"), 32, &[]);
    let ok = std::process::Command::new("kill").args(["-TERM", &child.id().to_string()]).status().unwrap();
    assert!(ok.success());
    let mut child = child;
    let mut rest = String::new();
    reader.read_to_string(&mut rest).unwrap();
    assert_eq!(child.wait().unwrap().code(), Some(130), "{rest}");
    assert!(rest.contains("interrupted") && dir.join("t.exr").is_file(), "{rest}");
}

/// Without the `denoise` feature, `merge --denoise` says in one line how to get it, before it
/// reads a part.
#[cfg(not(feature = "denoise"))]
#[test]
fn merge_denoise_without_the_feature_says_how_to_get_it() {
    let dir = temp_dir("merge_denoise_missing");
    let o = merge(&dir, "m", &[&dir.join("absent.exr")], &["--denoise"]);
    assert_eq!(o.status.code(), Some(1));
    let err = stderr(&o);
    assert!(err.contains("--features denoise") && !err.contains("absent.exr"), "{err}");
}

/// With the feature: the merged image of parts with AOVs is denoised (guided), as `render
/// --denoise` writes it: PATH.denoised.png and the EXR's denoised layer beside the exact film.
#[cfg(feature = "denoise")]
#[test]
fn merge_denoises_the_merged_image() {
    let dir = temp_dir("merge_denoise");
    let a = part(&dir, "a", &["--aovs", "--samples", "0..2", "--spp", "4", "--backend", "cpu"]);
    let b = part(&dir, "b", &["--aovs", "--samples", "2..4", "--spp", "4", "--backend", "cpu"]);
    let o = merge(&dir, "m", &[&a, &b], &["--denoise", "--denoise-device", "cpu"]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(dir.join("m.denoised.png").is_file());
    let channels = exr::meta::MetaData::read_from_file(dir.join("m.exr"), false).unwrap().headers[0]
        .channels
        .list
        .iter()
        .map(|c| c.name.to_string())
        .collect::<Vec<_>>();
    assert!(channels.iter().any(|c| c == "denoised.R"), "{channels:?}");
    let r = furnace_post::read_exr_with_state(dir.join("m.exr")).unwrap();
    assert!(r.state.unwrap().has_aovs(), "the guides' AOVs are merged too");
}
