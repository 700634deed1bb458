//! Shared helpers of the brdf integration tests (each test binary uses some of them).
#![allow(dead_code)]

use std::path::PathBuf;

/// Writes `text` to `target/test-output/brdf/<name>` (created if needed) and returns the path,
/// so that a test can point a human at its table.
pub fn write_output(name: &str, text: &str) -> PathBuf {
    let manifest = PathBuf::from(env!("CARGO_MANIFEST_DIR"));
    let dir = manifest.parent().unwrap_or(&manifest).join("target/test-output/brdf");
    std::fs::create_dir_all(&dir).expect("create target/test-output/brdf");
    let path = dir.join(name);
    std::fs::write(&path, text).expect("write test output");
    path
}

/// The worst `error / tolerance` seen in a group, with the input that produced it.
#[derive(Default)]
pub struct Worst {
    pub ratio: f32,
    pub what: String,
}

impl Worst {
    /// Records `error / tolerance` (NaN counts as the worst).
    pub fn record(&mut self, error: f32, tolerance: f32, what: impl FnOnce() -> String) {
        let ratio = error / tolerance;
        if ratio > self.ratio || ratio.is_nan() {
            self.ratio = ratio;
            self.what = what();
        }
    }

    /// Appends a failure to `failures` if the worst ratio exceeds 1 (or is NaN).
    pub fn check(&self, label: &str, failures: &mut Vec<String>) {
        if !(self.ratio <= 1.0) {
            failures.push(format!("{label}: error {:.3}x its tolerance at {}", self.ratio, self.what));
        }
    }
}
