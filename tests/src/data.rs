//! Where the test data lives: `tests/data/` of the repository, one copy of each asset, each with
//! its licence (`tests/data/README.md` lists them).
//!
//! * `references/` — images rendered by Mitsuba 3, an independent renderer, with their
//!   conventions (`references/README.md`): the Cornell box (`cbox/`), the white-furnace figures
//!   (`furnace/`).
//! * `scenes/` — glTF files written by others (Khronos samples, Cornell boxes, glTF-Validator and
//!   edge-case corpora).
//!
//! Tests write what a human needs to see on failure under [`output_dir`].

use std::path::{Path, PathBuf};

/// `tests/data/` of the repository.
pub fn data_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("data")
}

/// A scene of `tests/data/scenes/`, e.g. `scene("Box/glTF-Binary/Box.glb")`.
pub fn scene(relative: &str) -> PathBuf {
    data_dir().join("scenes").join(relative)
}

/// A file of `tests/data/references/`, e.g. `reference("cbox/cbox_ref_direct.exr")`.
pub fn reference(relative: &str) -> PathBuf {
    data_dir().join("references").join(relative)
}

/// `target/test-output/<name>/` (created): where failing tests and studies write images and
/// tables.
///
/// # Panics
/// If the folder cannot be created.
pub fn output_dir(name: &str) -> PathBuf {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../target/test-output").join(name);
    std::fs::create_dir_all(&dir).unwrap_or_else(|e| panic!("creating {}: {e}", dir.display()));
    dir
}
