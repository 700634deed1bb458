//! Helpers shared by the `furnace` binary's end-to-end tests (`cli.rs`, `gpu.rs`, `chart.rs`,
//! `view.rs`); each test module uses some of them.
#![allow(dead_code)]

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

/// Runs the `furnace` binary with `args`.
pub fn furnace(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_furnace")).args(args).output().expect("the furnace binary runs")
}

/// A run's standard error as text.
pub fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

/// A fresh, empty directory for one test (under the test binary's own folder). The tests of all
/// modules run in one binary, in parallel: every name must be unique among them.
pub fn temp_dir(name: &str) -> PathBuf {
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR")).join("furnace-cli").join(name);
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// The two EXRs hold the same render: RGB and film sums bit for bit, the same counts and
/// metadata (render time aside).
pub fn assert_same_render(a: &Path, b: &Path) {
    let ra = furnace_post::read_exr_with_state(a).unwrap();
    let rb = furnace_post::read_exr_with_state(b).unwrap();
    assert_eq!((ra.width, ra.height), (rb.width, rb.height));
    let bits = |v: &[glam::Vec3]| v.iter().flat_map(|p| p.to_array().map(f32::to_bits)).collect::<Vec<_>>();
    assert!(bits(&ra.pixels) == bits(&rb.pixels), "RGB differs: {} vs {}", a.display(), b.display());
    let (sa, sb) = (ra.state.unwrap(), rb.state.unwrap());
    let sum_bits = |f: &furnace_render::Film| {
        f.sums().iter().flat_map(|s| s.to_array().map(f64::to_bits)).collect::<Vec<_>>()
    };
    assert!(sum_bits(&sa) == sum_bits(&sb), "film sums differ: {} vs {}", a.display(), b.display());
    assert_eq!(sa.counts(), sb.counts());
    let aov_bits = |f: &furnace_render::Film| {
        f.aov_sums().map(|s| s.iter().flat_map(|p| p.to_array().map(f64::to_bits)).collect::<Vec<_>>())
    };
    assert!(aov_bits(&sa) == aov_bits(&sb), "AOV sums differ: {} vs {}", a.display(), b.display());
    let (mut ma, mut mb) = (ra.metadata, rb.metadata);
    ma.render_time_s = None;
    mb.render_time_s = None;
    assert_eq!(ma, mb);
}

/// Sends SIGINT (Ctrl-C) to `child`.
#[cfg(unix)]
pub fn sigint(child: &std::process::Child) {
    let ok = Command::new("kill").args(["-INT", &child.id().to_string()]).status().unwrap().success();
    assert!(ok, "kill -INT failed");
}

/// Reads `reader` line by line, appending to `seen`, until a line starts with `prefix`; panics
/// with everything read if the stream ends first (`what`: what was awaited).
#[cfg(unix)]
pub fn read_until(reader: &mut impl std::io::BufRead, prefix: &str, seen: &mut String, what: &str) {
    loop {
        let mut line = String::new();
        let n = reader.read_line(&mut line).unwrap();
        seen.push_str(&line);
        assert!(n > 0, "furnace ended before {what}:\n{seen}");
        if line.starts_with(prefix) {
            return;
        }
    }
}

/// Starts `furnace render ARGS --width S --height S --spp 1000000 --out OUT` with stderr piped
/// and returns once it reports its first pass (a `progress: ` line), with what it printed so far.
#[cfg(unix)]
// The caller waits for the child; on a failed read the test panics and the child, its stderr
// closed, ends at its next progress line.
#[allow(clippy::zombie_processes)]
pub fn start_long_render(
    out: &Path,
    size: u32,
    args: &[&str],
) -> (std::process::Child, std::io::BufReader<std::process::ChildStderr>, String) {
    let size = size.to_string();
    let mut child = Command::new(env!("CARGO_BIN_EXE_furnace"))
        .arg("render")
        .args(args)
        .args(["--width", &size, "--height", &size, "--spp", "1000000", "--out"])
        .arg(out)
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    let mut reader = std::io::BufReader::new(child.stderr.take().unwrap());
    let mut seen = String::new();
    read_until(&mut reader, "progress: ", &mut seen, "its first pass");
    (child, reader, seen)
}
