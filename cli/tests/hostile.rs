//! Hostile files and arguments given to the `furnace` binary: EXRs whose header claims a huge
//! image, FIFOs named as inputs, tampered resume records, out-of-range `--bounces`, `--out`
//! paths that name a directory, temporary files left by a killed render. Each must end in one
//! line `error: …` naming the file (and the attribute) with exit code 1, or a note saying what
//! was done; never a panic (101), an abort (134), a hang, or a lost output.

use crate::common::{furnace, stderr, temp_dir};
use exr::prelude::{AttributeValue, FlatSamples, Text, WritableImage, read_all_flat_layers_from_file};
use std::path::{Path, PathBuf};
use std::process::{Command, Output, Stdio};
use std::time::{Duration, Instant};

/// Asserts that `o` failed with exit code 1 and a single `error: ` line containing every one of
/// `needles`.
fn assert_one_line_error(o: &Output, needles: &[&str]) {
    let e = stderr(o);
    assert_eq!(o.status.code(), Some(1), "{e}");
    let lines: Vec<&str> = e.lines().filter(|l| !l.trim().is_empty()).collect();
    assert_eq!(lines.len(), 1, "one line expected:\n{e}");
    assert!(lines[0].starts_with("error: "), "{e}");
    for n in needles {
        assert!(lines[0].contains(n), "'{n}' not in: {e}");
    }
}

/// Runs `furnace ARGS`, killing it after `limit` (a hang fails the test instead of stopping it).
fn furnace_within(args: &[&str], limit: Duration) -> Output {
    let mut child = Command::new(env!("CARGO_BIN_EXE_furnace"))
        .args(args)
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let start = Instant::now();
    while child.try_wait().unwrap().is_none() {
        if start.elapsed() > limit {
            child.kill().unwrap();
            let _ = child.wait();
            panic!("furnace {args:?} did not end within {limit:?}");
        }
        std::thread::sleep(Duration::from_millis(20));
    }
    child.wait_with_output().unwrap()
}

/// How long a command that should fail at once may take: it reads a header or stats a path;
/// a few seconds for a loaded machine, far below a blocked read (forever).
const AT_ONCE: Duration = Duration::from_secs(60);

/// A small valid EXR (8 × 4) with its `dataWindow` patched to claim 100000 × 100000 pixels.
fn huge_exr(dir: &Path) -> PathBuf {
    let path = dir.join("huge.exr");
    furnace_post::write_exr(&path, 8, 4, &[glam::Vec3::ONE; 32], &furnace_post::Metadata::default()).unwrap();
    let mut bytes = std::fs::read(&path).unwrap();
    let key = b"dataWindow\0box2i\0";
    let at = bytes.windows(key.len()).position(|w| w == key).unwrap() + key.len() + 4;
    // box2i: xMin, yMin, xMax, yMax.
    bytes[at + 8..at + 12].copy_from_slice(&99_999i32.to_le_bytes());
    bytes[at + 12..at + 16].copy_from_slice(&99_999i32.to_le_bytes());
    std::fs::write(&path, bytes).unwrap();
    path
}

#[test]
fn an_exr_claiming_100000_squared_is_refused_by_every_reader() {
    let dir = temp_dir("hostile_huge");
    let huge = huge_exr(&dir);
    let h = huge.to_str().unwrap();
    let m = dir.join("m");
    for args in
        [vec!["compare", h, h], vec!["render", "--resume", h], vec!["merge", h, "-o", m.to_str().unwrap()]]
    {
        let o = furnace_within(&args, AT_ONCE);
        assert_one_line_error(&o, &["huge.exr", "'dataWindow'", "100000×100000", "16384 per side"]);
    }
}

#[test]
#[cfg(unix)]
fn a_fifo_named_as_an_input_is_refused_not_waited_for() {
    let dir = temp_dir("hostile_fifo");
    let fifo = dir.join("pipe.exr");
    assert!(Command::new("mkfifo").arg(&fifo).status().unwrap().success());
    let f = fifo.to_str().unwrap();
    let m = dir.join("m");
    for args in
        [vec!["compare", f, f], vec!["render", "--resume", f], vec!["merge", f, "-o", m.to_str().unwrap()]]
    {
        let o = furnace_within(&args, AT_ONCE);
        assert_one_line_error(&o, &["pipe.exr: a FIFO, not a regular file"]);
    }
}

/// Renders the built-in Cornell box at 16² and 2 spp on the CPU to `dir/NAME.exr`.
fn small_render(dir: &Path, name: &str) -> PathBuf {
    let out = dir.join(name);
    let o = furnace(&[
        "render",
        "--width",
        "16",
        "--height",
        "16",
        "--spp",
        "2",
        "--backend",
        "cpu",
        "--quiet",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    dir.join(format!("{name}.exr"))
}

/// Sets text attribute `key` of the EXR `file` to `value` (as a hand-edited file would have it).
fn set_attribute(file: &Path, key: &str, value: &str) {
    let mut image = read_all_flat_layers_from_file(file).unwrap();
    image.layer_data[0].attributes.other.insert(Text::from(key), AttributeValue::Text(Text::from(value)));
    image.write().to_file(file).unwrap();
}

#[test]
fn resume_refuses_tampered_records_naming_the_attribute() {
    let dir = temp_dir("hostile_tampered");
    let resume = |file: &Path| {
        furnace_within(
            &["render", "--quiet", "--backend", "cpu", "--resume", file.to_str().unwrap()],
            AT_ONCE,
        )
    };
    for (key, value, needle) in [
        (
            "furnace.bounces",
            "4294967295",
            "attribute 'furnace.bounces' = 4294967295 is more than furnace renders",
        ),
        (
            "furnace.rejectedSamples",
            "18446744073709551615",
            "attribute 'furnace.rejectedSamples' = 18446744073709551615 is more than the 0 samples",
        ),
        ("furnace.renderTimeS", "NaN", "attribute 'furnace.renderTimeS' = NaN is not a time in seconds"),
        ("furnace.spp", "4294967295", "attribute 'furnace.spp' = 4294967295 is more than the 2 samples"),
    ] {
        let file = small_render(&dir, key);
        set_attribute(&file, key, value);
        let o = resume(&file);
        assert_one_line_error(&o, &[&file.file_name().unwrap().to_string_lossy(), needle]);
        // `merge` reads the same record.
        let out = dir.join(format!("{key}.merged"));
        let o = furnace_within(&["merge", file.to_str().unwrap(), "-o", out.to_str().unwrap()], AT_ONCE);
        assert_eq!(o.status.code(), Some(1), "{key}: {}", stderr(&o));
    }

    // Cropped to 8 × 4, every channel alike (the state stays consistent with the image) and every
    // attribute kept, as an image tool's crop leaves it.
    let file = small_render(&dir, "cropped");
    let mut image = read_all_flat_layers_from_file(&file).unwrap();
    let layer = &mut image.layer_data[0];
    let keep = |i: usize| i % 16 < 8 && i / 16 < 4;
    for c in layer.channel_data.list.iter_mut() {
        c.sample_data = match &c.sample_data {
            FlatSamples::F32(v) => {
                FlatSamples::F32(v.iter().enumerate().filter(|(i, _)| keep(*i)).map(|(_, x)| *x).collect())
            }
            FlatSamples::U32(v) => {
                FlatSamples::U32(v.iter().enumerate().filter(|(i, _)| keep(*i)).map(|(_, x)| *x).collect())
            }
            FlatSamples::F16(v) => {
                FlatSamples::F16(v.iter().enumerate().filter(|(i, _)| keep(*i)).map(|(_, x)| *x).collect())
            }
        };
    }
    layer.size = exr::prelude::Vec2(8, 4);
    image.write().to_file(&file).unwrap();
    let o = resume(&file);
    assert_one_line_error(
        &o,
        &["cropped.exr", "attribute 'furnace.resume.size' records a 16×16 film but the data window is 8×4"],
    );
}

#[test]
fn bounces_past_the_limit_are_refused_by_every_command() {
    let dir = temp_dir("hostile_bounces");
    let reference = dir.join("r.exr");
    for args in [
        vec!["render", "--bounces", "1000000"],
        vec!["view", "--bounces", "1025"],
        vec!["bench", "--bounces", "4294967295"],
        vec!["chart", "--reference", reference.to_str().unwrap(), "--bounces", "1025"],
    ] {
        let o = furnace_within(&args, AT_ONCE);
        assert_one_line_error(&o, &["--bounces", "at most 1024 scattering events per path"]);
    }
    // A reference's record is held to the same limit by `chart`.
    let reference = small_render(&dir, "r");
    set_attribute(&reference, "furnace.bounces", "4294967295");
    let study = dir.join("study");
    let o = furnace_within(
        &[
            "chart",
            "--reference",
            reference.to_str().unwrap(),
            "--spp",
            "1",
            "--out",
            study.to_str().unwrap(),
        ],
        AT_ONCE,
    );
    assert_one_line_error(
        &o,
        &["r.exr: attribute 'furnace.bounces' = 4294967295 is more than furnace renders"],
    );
}

#[test]
fn negative_values_parse_without_equals() {
    let dir = temp_dir("hostile_negative");
    let out = dir.join("neg");
    let o = furnace(&[
        "render",
        "--width",
        "8",
        "--height",
        "8",
        "--spp",
        "1",
        "--backend",
        "cpu",
        "--quiet",
        "--exposure",
        "-1",
        "--env-rotation",
        "-90",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let meta = furnace_post::read_exr_metadata(dir.join("neg.exr")).unwrap().2;
    assert_eq!(meta.extra.get("furnace.exposure_ev").map(String::as_str), Some("-1"));
    assert_eq!(meta.extra.get("furnace.env_rotation_deg").map(String::as_str), Some("-90"));
    // A negative value where none is valid: the value's own message, not "unexpected argument".
    let o = furnace(&["render", "--sun-angle", "-1"]);
    assert_one_line_error(&o, &["sun's angular diameter must be between 0 and 180 degrees (got -1)"]);
}

/// The names in `dir`, sorted.
fn entries(dir: &Path) -> Vec<String> {
    let mut v: Vec<String> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    v.sort();
    v
}

#[test]
fn an_out_naming_a_directory_is_refused_before_rendering() {
    let dir = temp_dir("hostile_out_dir");
    let sub = dir.join("sub");
    std::fs::create_dir(&sub).unwrap();
    let s = sub.to_str().unwrap();
    for (out, why) in [
        (format!("{s}/"), "names a directory, not a file"),
        (format!("{s}/."), "names a directory, not a file"),
        (s.to_string(), "is a directory"),
        (format!("{s}/.exr"), "has no file name before its extension"),
        ("/".to_string(), "names a directory, not a file"),
    ] {
        let o = furnace_within(
            &["render", "--width", "8", "--height", "8", "--spp", "1", "--backend", "cpu", "--out", &out],
            AT_ONCE,
        );
        assert_one_line_error(&o, &[&format!("--out '{out}' {why}"), "give a file path"]);
        assert!(!stderr(&o).contains("/.exr and"), "{}", stderr(&o));
        assert!(entries(&sub).is_empty(), "{out}: {:?}", entries(&sub));
    }
    assert_eq!(entries(&dir), ["sub"]);
    let o = furnace_within(&["render", "--out", &format!("{s}/no/such/x")], AT_ONCE);
    assert_one_line_error(&o, &[&format!("the directory {s}/no/such does not exist")]);
    // `merge` checks its --out the same way.
    let o = furnace_within(&["merge", "part.exr", "-o", &format!("{s}/")], AT_ONCE);
    assert_one_line_error(&o, &["names a directory, not a file"]);
}

#[test]
fn an_output_that_cannot_be_written_is_found_before_rendering_and_nothing_is_lost() {
    let dir = temp_dir("hostile_out_png_dir");
    let exr = small_render(&dir, "r");
    let before = std::fs::read(&exr).unwrap();
    // The PNG's name taken by a directory: the render would end in a failed rename.
    std::fs::remove_file(dir.join("r.png")).unwrap();
    std::fs::create_dir(dir.join("r.png")).unwrap();
    let out = dir.join("r");
    let o = furnace_within(
        &[
            "render",
            "--width",
            "16",
            "--height",
            "16",
            "--spp",
            "4",
            "--backend",
            "cpu",
            "--out",
            out.to_str().unwrap(),
        ],
        AT_ONCE,
    );
    assert_one_line_error(&o, &["r.png: an output of --out", "is a directory"]);
    assert_eq!(std::fs::read(&exr).unwrap(), before, "the finished EXR was replaced");
    assert_eq!(entries(&dir), ["r.exr", "r.png"]);
}

#[test]
fn temporaries_of_a_killed_render_are_removed_by_the_next_one() {
    let dir = temp_dir("hostile_stale");
    // What a render killed while writing its outputs leaves: its temporary files, named after
    // the outputs and the dead process (no process has the largest pid).
    let stale = [format!(".r.exr.furnace-tmp-{}.3", u32::MAX), format!(".r.png.furnace-tmp-{}.4", u32::MAX)];
    for name in &stale {
        std::fs::write(dir.join(name), b"partial").unwrap();
    }
    std::fs::write(dir.join(".other.exr.furnace-tmp-1.0"), b"not ours").unwrap();
    let out = dir.join("r");
    let o = furnace(&[
        "render",
        "--width",
        "8",
        "--height",
        "8",
        "--spp",
        "1",
        "--backend",
        "cpu",
        "--quiet",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let e = stderr(&o);
    for name in &stale {
        assert!(e.contains(&format!("note: removed {}", dir.join(name).display())), "{e}");
    }
    assert_eq!(entries(&dir), [".other.exr.furnace-tmp-1.0", "r.exr", "r.png"]);
}

#[test]
#[cfg(unix)]
fn a_render_killed_during_checkpoints_leaves_nothing_after_the_next_run() {
    let dir = temp_dir("hostile_kill9");
    let out = dir.join("k");
    // A checkpoint after every pass of a 384² film (its EXR takes a while to compress): SIGKILL
    // often finds a write in flight. Up to 5 tries for one that leaves temporary files; the next
    // run must remove whatever was left.
    let mut left = 0;
    for attempt in 1..=5 {
        let (mut child, _reader, _) =
            crate::common::start_long_render(&out, 384, &["--backend", "cpu", "--checkpoint", "0.001"]);
        std::thread::sleep(Duration::from_millis(150 * attempt));
        assert!(Command::new("kill").args(["-KILL", &child.id().to_string()]).status().unwrap().success());
        let _ = child.wait();
        left = entries(&dir).into_iter().filter(|n| n.contains(".furnace-tmp-")).count();
        println!("SIGKILL {attempt} during checkpoints left {left} temporary files");
        if left > 0 {
            break;
        }
    }
    let o = furnace(&[
        "render",
        "--width",
        "8",
        "--height",
        "8",
        "--spp",
        "1",
        "--backend",
        "cpu",
        "--quiet",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert_eq!(stderr(&o).matches("note: removed").count(), left, "{}", stderr(&o));
    assert_eq!(entries(&dir), ["k.exr", "k.png"]);
}

#[test]
#[cfg(unix)]
fn a_resume_record_naming_a_fifo_as_scene_or_map_is_refused_not_waited_for() {
    // The scene and the environment map a file was rendered from are loaded by the scene crate,
    // which reads regular files only; resume must not open them itself first.
    let dir = temp_dir("hostile_record_fifo");
    let fifo = dir.join("pipe.glb");
    assert!(Command::new("mkfifo").arg(&fifo).status().unwrap().success());
    for key in ["furnace.scene", "furnace.env"] {
        let file = small_render(&dir, key);
        set_attribute(&file, key, fifo.to_str().unwrap());
        let o = furnace_within(
            &["render", "--quiet", "--backend", "cpu", "--resume", file.to_str().unwrap()],
            AT_ONCE,
        );
        assert_one_line_error(&o, &["pipe.glb", "FIFO"]);
    }
}
