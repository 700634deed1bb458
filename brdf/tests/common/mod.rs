//! Shared helpers of the brdf integration tests.

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
