//! `furnace view` in a real window: an X server without a screen (Xvfb), the GPU integrator on
//! whatever adapter there is (Mesa's lavapipe in CI), the viewer driven through `--script -`
//! (standard input, each command acknowledged on stdout), and the window captured by
//! ImageMagick's `import`, as a user would see it.
//!
//! One session checks, in order:
//! 1. the window shows the film with post's display maths: the screenshot at 64 spp equals the
//!    PNG the viewer saves (`to_srgb8` of the film) within one code per channel;
//! 2. the film is `furnace render`'s image: against two independent CPU renders (R at 4× the
//!    samples, E at the same), T = Σ_blocks (V − R)² / Σ_blocks (E − R)² over 8×6-pixel block
//!    means of the three channels (V, E equally noisy, so T ≈ 1; a bias or a wrong film makes it
//!    grow). With ≈ 100 terms of similar size the ratio's 0.999 quantile is below 2.5
//!    (F(50, 50) gives 2.4 even at half the terms), and the image means agree within 2 %
//!    (the 64-spp image mean's noise is about 0.3 %);
//! 3. display changes (exposure) keep the accumulation, estimator changes (bounces) restart it,
//!    an orbit moves the image and restarts it;
//! 4. a save after the orbit is a `furnace render` file: `render --resume` continues it to the
//!    bit-identical film of `render --look-at … --yfov …` from scratch on the same adapter;
//! 5. resizing the window keeps a fixed-size film, centred.
//!
//! Without Xvfb, xwininfo or import the test fails with what to install (`.ci/run` installs
//! them); `FURNACE_SKIP_GPU_TESTS=1` skips it with the GPU tests.

use crate::common;

use common::*;
use std::io::{BufRead, BufReader, Write};
use std::path::{Path, PathBuf};
use std::process::{Child, ChildStdin, Command, Stdio};
use std::sync::mpsc::{Receiver, channel};
use std::time::Duration;

/// The film: small, so that lavapipe renders 64 spp in about a second.
const W: u32 = 48;
const H: u32 = 36;

/// An Xvfb server on a display of its own, stopped on drop.
struct Xvfb {
    child: Child,
    display: String,
}

impl Xvfb {
    fn start() -> Self {
        // A display number unlikely to be taken, different per process.
        let n = 90 + std::process::id() % 400;
        let display = format!(":{n}");
        let child = Command::new("Xvfb")
            .args([&display, "-screen", "0", "320x240x24", "-nolisten", "tcp"])
            .stdout(Stdio::null())
            .stderr(Stdio::null())
            .spawn()
            .unwrap_or_else(|e| {
                panic!("Xvfb: {e}: install Debian's xvfb (and x11-utils, imagemagick, libxkbcommon-x11-0) as .ci/run does")
            });
        let socket = PathBuf::from(format!("/tmp/.X11-unix/X{n}"));
        for _ in 0..100 {
            if socket.exists() {
                break;
            }
            std::thread::sleep(Duration::from_millis(100));
        }
        assert!(socket.exists(), "Xvfb did not start on {display}");
        Self { child, display }
    }
}

impl Drop for Xvfb {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

/// A running viewer: its stdin for commands, its stdout lines.
struct Viewer {
    child: Child,
    stdin: ChildStdin,
    lines: Receiver<String>,
    display: String,
    log: String,
}

/// An acknowledgement: `script: <cmd> -> spp=<n> resets=<k> frame=<f>`.
#[derive(Debug, Clone, Copy, PartialEq)]
struct Ack {
    spp: u32,
    resets: u64,
}

impl Viewer {
    fn start(x: &Xvfb, args: &[&str]) -> Self {
        let mut child = Command::new(env!("CARGO_BIN_EXE_furnace"))
            .arg("view")
            .args(args)
            .args(["--script", "-"])
            .env("DISPLAY", &x.display)
            .env_remove("WAYLAND_DISPLAY")
            .stdin(Stdio::piped())
            .stdout(Stdio::piped())
            .stderr(Stdio::inherit())
            .spawn()
            .expect("furnace view starts");
        let stdin = child.stdin.take().unwrap();
        let stdout = child.stdout.take().unwrap();
        let (tx, rx) = channel();
        std::thread::spawn(move || {
            for line in BufReader::new(stdout).lines().map_while(Result::ok) {
                if tx.send(line).is_err() {
                    return;
                }
            }
        });
        Self { child, stdin, lines: rx, display: x.display.clone(), log: String::new() }
    }

    /// Sends a command and waits for its acknowledgement (lavapipe compiles pipelines in
    /// seconds; two minutes is a hang). Returns the ack and the lines printed before it.
    fn send(&mut self, command: &str) -> (Ack, Vec<String>) {
        writeln!(self.stdin, "{command}").unwrap();
        self.stdin.flush().unwrap();
        let mut before = Vec::new();
        loop {
            let line = match self.lines.recv_timeout(Duration::from_secs(120)) {
                Ok(l) => l,
                Err(_) => {
                    let _ = self.child.kill();
                    panic!(
                        "no acknowledgement of '{command}' within 120 s; the viewer printed:\n{}",
                        self.log
                    );
                }
            };
            self.log.push_str(&line);
            self.log.push('\n');
            if let Some(rest) = line.strip_prefix(&format!("script: {command} -> ")) {
                let field =
                    |k: &str| rest.split_whitespace().find_map(|w| w.strip_prefix(k)).unwrap().to_string();
                return (
                    Ack { spp: field("spp=").parse().unwrap(), resets: field("resets=").parse().unwrap() },
                    before,
                );
            }
            before.push(line);
        }
    }

    /// The window's pixels, as captured from the X server.
    fn screenshot(&self, path: &Path) -> image::RgbImage {
        let tree = Command::new("xwininfo")
            .args(["-root", "-tree"])
            .env("DISPLAY", &self.display)
            .output()
            .expect("xwininfo (Debian's x11-utils) runs");
        let text = String::from_utf8_lossy(&tree.stdout);
        let id = text
            .lines()
            .find(|l| l.contains("\"furnace — "))
            .and_then(|l| l.split_whitespace().next())
            .unwrap_or_else(|| panic!("no furnace window in:\n{text}"))
            .to_string();
        let ok = Command::new("import")
            .args(["-window", &id, path.to_str().unwrap()])
            .env("DISPLAY", &self.display)
            .status()
            .expect("import (Debian's imagemagick) runs")
            .success();
        assert!(ok, "import failed");
        image::open(path).unwrap().to_rgb8()
    }

    fn finish(mut self) {
        drop(self.stdin);
        let status = self.child.wait().unwrap();
        assert!(status.success(), "furnace view failed: {status}\n{}", self.log);
    }
}

/// Per-channel block means (8×6 pixels) of an EXR's image.
fn blocks(path: &Path) -> Vec<f64> {
    let (w, h, px, _) = furnace_post::read_exr(path).unwrap();
    assert_eq!((w, h), (W, H));
    let (bw, bh) = (8, 6);
    let mut out = Vec::new();
    for by in 0..h / bh {
        for bx in 0..w / bw {
            for c in 0..3 {
                let mut s = 0.0;
                for y in by * bh..(by + 1) * bh {
                    for x in bx * bw..(bx + 1) * bw {
                        s += f64::from(px[(y * w + x) as usize].to_array()[c]);
                    }
                }
                out.push(s / f64::from(bw * bh));
            }
        }
    }
    out
}

fn render(dir: &Path, name: &str, extra: &[&str]) -> PathBuf {
    let out = dir.join(name);
    let mut args =
        vec!["render", "--quiet", "--width", "48", "--height", "36", "--out", out.to_str().unwrap()];
    args.extend_from_slice(extra);
    let o = furnace(&args);
    assert!(o.status.success(), "furnace render {extra:?}: {}", stderr(&o));
    out.with_extension("exr")
}

fn mean_abs_diff(a: &image::RgbImage, b: &image::RgbImage) -> f64 {
    a.pixels()
        .zip(b.pixels())
        .flat_map(|(p, q)| (0..3).map(move |c| (f64::from(p[c]) - f64::from(q[c])).abs()))
        .sum::<f64>()
        / (3 * a.width() * a.height()) as f64
}

#[test]
fn the_viewer_shows_the_render_restarts_on_changes_and_saves_resumable_files() {
    if std::env::var("FURNACE_SKIP_GPU_TESTS").is_ok_and(|v| v == "1") {
        eprintln!("FURNACE_SKIP_GPU_TESTS=1: skipping the viewer's window test");
        return;
    }
    let dir = temp_dir("view");
    let x = Xvfb::start();
    let out = dir.join("view");
    let mut v = Viewer::start(
        &x,
        &["--width", "48", "--height", "36", "--spp", "64", "--out", out.to_str().unwrap()],
    );

    // 1. The converged window is the saved PNG.
    let (ack, _) = v.send("wait-spp 64");
    assert_eq!(ack, Ack { spp: 64, resets: 0 });
    v.send("key tab"); // hide the panels
    v.send("wait-frames 2");
    let shot = v.screenshot(&dir.join("shot_64spp.png"));
    assert_eq!(shot.dimensions(), (W, H), "the window is the film's size");
    let (_, said) = v.send("save");
    assert!(said.iter().any(|l| l.starts_with("saved ") && l.contains("(64 spp)")), "{said:?}");
    let png = image::open(out.with_extension("png")).unwrap().to_rgb8();
    let mut off = 0;
    for (p, q) in shot.pixels().zip(png.pixels()) {
        for c in 0..3 {
            let d = (i32::from(p[c]) - i32::from(q[c])).abs();
            assert!(d <= 1, "the window shows {p:?} where the saved PNG has {q:?} (see {})", dir.display());
            off += d;
        }
    }
    assert!(off as u32 * 100 <= 3 * W * H, "{off} channels one code off: more than rounding");

    // 2. The film is furnace render's image, by an independent backend.
    let viewer_exr = out.with_extension("exr");
    let r = render(&dir, "cpu_ref", &["--backend", "cpu", "--spp", "256", "--seed", "1"]);
    let e = render(&dir, "cpu_64", &["--backend", "cpu", "--spp", "64", "--seed", "2"]);
    let (bv, br, be) = (blocks(&viewer_exr), blocks(&r), blocks(&e));
    let num: f64 = bv.iter().zip(&br).map(|(a, b)| (a - b) * (a - b)).sum();
    let den: f64 = be.iter().zip(&br).map(|(a, b)| (a - b) * (a - b)).sum();
    let t = num / den;
    let mean = |v: &[f64]| v.iter().sum::<f64>() / v.len() as f64;
    let ratio = mean(&bv) / mean(&br);
    eprintln!("viewer vs CPU: T = {t:.3} over {} block means, image mean ratio {ratio:.4}", bv.len());
    assert!(
        t < 2.5,
        "the viewer's film is farther from the CPU reference than an independent CPU render: T = {t}"
    );
    assert!((ratio - 1.0).abs() < 0.02, "image mean ratio {ratio}");
    let meta = furnace_post::read_exr(&viewer_exr).unwrap().3;
    assert_eq!(meta.extra.get("furnace.camera").map(String::as_str), Some("0"));

    // 3. Display changes keep the samples; estimator changes and camera moves restart.
    let (ack, _) = v.send("set exposure 1");
    assert_eq!(ack, Ack { spp: 64, resets: 0 }, "exposure is a display change");
    v.send("wait-frames 2");
    let brighter = v.screenshot(&dir.join("shot_exposure.png"));
    let sum = |i: &image::RgbImage| {
        i.pixels().map(|p| u64::from(p[0]) + u64::from(p[1]) + u64::from(p[2])).sum::<u64>()
    };
    assert!(sum(&brighter) > sum(&shot) * 11 / 10, "+1 EV brightens the window");
    v.send("set exposure 0");
    v.send("set spp 16"); // the target from now on: accumulation stops there
    let (ack, _) = v.send("drag left 60 10");
    assert_eq!(ack, Ack { spp: 0, resets: 1 }, "an orbit restarts the accumulation");
    let (ack, _) = v.send("wait-spp 16");
    assert_eq!(ack, Ack { spp: 16, resets: 1 });
    v.send("wait-frames 2");
    let moved = v.screenshot(&dir.join("shot_orbit.png"));
    let d = mean_abs_diff(&moved, &shot);
    assert!(d > 10.0, "the orbit moved the image: mean difference {d:.1} codes");
    let (ack, _) = v.send("set bounces 2");
    assert_eq!(ack, Ack { spp: 0, resets: 2 }, "bounces restart the accumulation");
    let (ack, _) = v.send("wait-spp 16");
    assert_eq!(ack, Ack { spp: 16, resets: 2 });
    let moved_out = dir.join("moved");
    let (_, said) = v.send(&format!("save {}", moved_out.display()));
    assert!(said.iter().any(|l| l.starts_with("saved ")), "{said:?}");
    let (_, said) = v.send("key c");
    let camera =
        said.iter().find_map(|l| l.strip_prefix("camera: ")).expect("C prints the camera").to_string();

    // 5. Resizing keeps the fixed film, centred.
    v.send("resize 80 60");
    v.send("wait-frames 3");
    let (_, said) = v.send("print");
    assert!(said.iter().any(|l| l.contains("size=48x36")), "{said:?}");
    let wide = v.screenshot(&dir.join("shot_resized.png"));
    assert_eq!(wide.dimensions(), (80, 60));
    assert_eq!(wide.get_pixel(0, 0).0, [20, 20, 20], "the background around the film");
    v.send("quit");
    v.finish();

    // 4. The moved view's file resumes to what render makes from scratch with its camera.
    let moved_exr = moved_out.with_extension("exr");
    let meta = furnace_post::read_exr(&moved_exr).unwrap().3;
    let record = meta.extra.get("furnace.camera").cloned().unwrap();
    assert!(record.starts_with("look-at:"), "{record}");
    assert_eq!(meta.bounces, Some(2));
    let resumed = dir.join("resumed");
    let o = furnace(&[
        "render",
        "--quiet",
        "--backend",
        "gpu",
        "--resume",
        moved_exr.to_str().unwrap(),
        "--spp",
        "24",
        "--out",
        resumed.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let mut args: Vec<String> =
        ["--backend", "gpu", "--spp", "24", "--bounces", "2", "--exposure", "0"].map(String::from).to_vec();
    args.extend(camera.split_whitespace().map(String::from));
    let args: Vec<&str> = args.iter().map(String::as_str).collect();
    let fresh = render(&dir, "fresh", &args);
    let (a, b) = (
        furnace_post::read_exr_with_state(resumed.with_extension("exr")).unwrap(),
        furnace_post::read_exr_with_state(&fresh).unwrap(),
    );
    let bits = |v: &[glam::Vec3]| v.iter().flat_map(|p| p.to_array().map(f32::to_bits)).collect::<Vec<_>>();
    assert!(bits(&a.pixels) == bits(&b.pixels), "the resumed view differs from render --look-at ({camera})");
    assert_eq!(a.metadata.extra.get("furnace.camera"), b.metadata.extra.get("furnace.camera"));
}

#[test]
fn view_refuses_the_cpu_backend_and_bad_scripts() {
    let o = furnace(&["view", "--backend", "cpu"]);
    assert!(!o.status.success());
    assert!(stderr(&o).contains("needs a GPU adapter"), "{}", stderr(&o));
    let dir = temp_dir("view_bad_script");
    let script = dir.join("s.txt");
    std::fs::write(&script, "wait-spp 4\ndrag sideways 1 2\n").unwrap();
    let o = furnace(&["view", "--script", script.to_str().unwrap()]);
    assert!(!o.status.success());
    assert!(stderr(&o).contains("s.txt:2: 'drag': unknown button 'sideways'"), "{}", stderr(&o));
}
