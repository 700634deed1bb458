//! What every step of one load shares: the file's name and base directory, and the warnings.

use crate::accessor::Located;
use crate::error::{SceneError, Warning};
use std::collections::HashSet;
use std::path::Path;

/// One load's file, base directory and warnings (each path and message at most once).
pub(super) struct Ctx<'a> {
    pub(super) file: &'a str,
    pub(super) base: Option<&'a Path>,
    pub(super) warnings: Vec<Warning>,
    /// An image that cannot be used is an error (else a warning: see [`crate::LoadOptions`]).
    pub(super) strict: bool,
    seen: HashSet<(String, String)>,
}

impl<'a> Ctx<'a> {
    pub(super) fn new(file: &'a str, base: Option<&'a Path>, strict: bool) -> Self {
        Self { file, base, warnings: Vec::new(), strict, seen: HashSet::new() }
    }
}

impl Ctx<'_> {
    pub(super) fn warn(&mut self, path: impl Into<String>, message: impl Into<String>) {
        let (path, message) = (path.into(), message.into());
        if self.seen.insert((path.clone(), message.clone())) {
            self.warnings.push(Warning { path, message });
        }
    }
    pub(super) fn invalid(&self, (path, message): Located) -> SceneError {
        SceneError::Invalid { file: self.file.to_string(), path, message }
    }
}
