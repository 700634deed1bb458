//! Atomic file replacement: write a temporary file beside the target, sync it, rename it over.
//!
//! A rename within one directory is atomic on POSIX file systems (and `MoveFileEx` with
//! replace on Windows), so a reader — or a crash — sees either the old file or the complete new
//! one, never a truncated image. If writing fails the temporary file is removed.

use crate::PostError;
use std::fs::{self, File, OpenOptions};
use std::io;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};

/// Distinguishes concurrent writes from one process (the pid distinguishes processes).
static COUNTER: AtomicU64 = AtomicU64::new(0);

/// The temporary path for `path`: `.<file name>.<pid>.<n>.tmp` in the same directory.
fn temp_path(path: &Path) -> PathBuf {
    let name = path.file_name().map(|n| n.to_string_lossy().into_owned()).unwrap_or_default();
    let n = COUNTER.fetch_add(1, Ordering::Relaxed);
    path.with_file_name(format!(".{name}.{}.{n}.tmp", std::process::id()))
}

/// Removes the temporary file on drop unless it was renamed into place.
struct TempGuard {
    path: PathBuf,
    armed: bool,
}

impl Drop for TempGuard {
    fn drop(&mut self) {
        if self.armed {
            // Best effort: the write already failed; a failure to clean up must not mask it.
            let _ = fs::remove_file(&self.path);
        }
    }
}

/// Writes `path` atomically: `write` fills a fresh temporary file in the same directory, which
/// is then synced and renamed to `path`. On any error (including a panic inside `write`) the
/// temporary file is removed and `path` is left as it was.
///
/// # Errors
/// [`PostError::Io`] naming `path`, or what `write` returns.
pub fn write_atomic(
    path: &Path,
    write: impl FnOnce(&mut File) -> Result<(), PostError>,
) -> Result<(), PostError> {
    let io_err = |source: io::Error| PostError::Io { path: path.to_path_buf(), source };
    if path.file_name().is_none() {
        return Err(io_err(io::Error::new(io::ErrorKind::InvalidInput, "not a file path")));
    }
    let tmp = temp_path(path);
    let mut file = OpenOptions::new().write(true).create_new(true).open(&tmp).map_err(io_err)?;
    let mut guard = TempGuard { path: tmp, armed: true };
    write(&mut file)?;
    file.sync_all().map_err(io_err)?;
    drop(file);
    fs::rename(&guard.path, path).map_err(io_err)?;
    guard.armed = false;
    Ok(())
}

/// Writes `bytes` to `path` atomically ([`write_atomic`]): a JSON report, a CSV, an SVG.
///
/// # Errors
/// [`PostError::Io`] naming `path`.
pub fn write_bytes_atomic(path: impl AsRef<Path>, bytes: &[u8]) -> Result<(), PostError> {
    use std::io::Write as _;
    let path = path.as_ref();
    write_atomic(path, |f| {
        f.write_all(bytes).map_err(|source| PostError::Io { path: path.to_path_buf(), source })
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::io::Write;

    fn scratch(name: &str) -> PathBuf {
        let dir = std::env::temp_dir().join(format!("furnace-post-atomic-{name}-{}", std::process::id()));
        let _ = fs::remove_dir_all(&dir);
        fs::create_dir_all(&dir).unwrap();
        dir
    }

    fn entries(dir: &Path) -> Vec<String> {
        let mut v: Vec<String> = fs::read_dir(dir)
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .collect();
        v.sort();
        v
    }

    #[test]
    fn final_path_appears_only_complete() {
        let dir = scratch("complete");
        let path = dir.join("out.bin");
        write_atomic(&path, |f| {
            f.write_all(b"first half").unwrap();
            // Mid-write: the data sits in a temporary file; the final path does not exist yet.
            assert!(!path.exists());
            assert_eq!(entries(&dir).len(), 1);
            f.write_all(b", second half").unwrap();
            Ok(())
        })
        .unwrap();
        assert_eq!(fs::read(&path).unwrap(), b"first half, second half");
        assert_eq!(entries(&dir), vec!["out.bin".to_string()]);
        fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn failed_write_leaves_old_file_and_no_temp() {
        let dir = scratch("failed");
        let path = dir.join("out.bin");
        fs::write(&path, b"old complete image").unwrap();
        let err = write_atomic(&path, |f| {
            f.write_all(b"partial").unwrap();
            Err(PostError::Io { path: path.clone(), source: io::Error::other("interrupted") })
        })
        .unwrap_err();
        assert!(err.to_string().contains("out.bin"), "{err}");
        assert_eq!(fs::read(&path).unwrap(), b"old complete image");
        assert_eq!(entries(&dir), vec!["out.bin".to_string()]);
        fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn panicking_write_leaves_no_temp() {
        let dir = scratch("panic");
        let path = dir.join("out.bin");
        let result = std::panic::catch_unwind(|| {
            let _ = write_atomic(&path, |f| {
                f.write_all(b"partial").unwrap();
                panic!("simulated crash inside the encoder");
            });
        });
        assert!(result.is_err());
        assert!(entries(&dir).is_empty(), "{:?}", entries(&dir));
        fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn missing_directory_names_the_file() {
        let path = std::env::temp_dir().join("furnace-post-no-such-dir-xyz").join("out.bin");
        let err = write_atomic(&path, |_| Ok(())).unwrap_err();
        assert!(matches!(err, PostError::Io { .. }));
        assert!(err.to_string().contains("out.bin"), "{err}");
    }
}
