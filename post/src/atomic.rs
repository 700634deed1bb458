//! Atomic file replacement: write a temporary file beside the target, sync it, rename it over.
//!
//! A rename within one directory is atomic on POSIX file systems (and `MoveFileEx` with
//! replace on Windows), so a reader — or a crash — sees either the old file or the complete new
//! one, never a truncated image. If writing fails the temporary file is removed.
//!
//! Several files that belong together (a render's EXR and PNG) are written with [`stage`]: each
//! to its temporary file first, then renamed into place ([`Staged::commit`]) only once all of
//! them were written, so a failure in the last one leaves every old file as it was.
//!
//! Temporary files are named `.NAME.furnace-tmp-PID.N` (`NAME` the target's file name, `PID`
//! the writing process): recognisable, so that a process that dies mid-write (SIGKILL, a lost
//! node) leaves something its next run can find and remove ([`remove_stale_temporaries`]). The
//! paths being written are kept in a process-wide registry so that an exit that skips the
//! destructors (a second Ctrl-C) can remove them first ([`remove_temporaries_in_flight`]).

use crate::PostError;
use std::fs::{self, File, OpenOptions};
use std::io;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::{Mutex, PoisonError};

/// Distinguishes concurrent writes from one process (the pid distinguishes processes).
static COUNTER: AtomicU64 = AtomicU64::new(0);

/// The temporary files this process is writing now (created, not yet renamed or removed).
static IN_FLIGHT: Mutex<Vec<PathBuf>> = Mutex::new(Vec::new());

/// What a temporary file's name holds between the target's name and the pid.
const TEMP_TAG: &str = ".furnace-tmp-";

/// The temporary path for `path`: `.<file name>.furnace-tmp-<pid>.<n>` in the same directory.
fn temp_path(path: &Path) -> PathBuf {
    let name = path.file_name().map(|n| n.to_string_lossy().into_owned()).unwrap_or_default();
    let n = COUNTER.fetch_add(1, Ordering::Relaxed);
    path.with_file_name(format!(".{name}{TEMP_TAG}{}.{n}", std::process::id()))
}

fn in_flight() -> std::sync::MutexGuard<'static, Vec<PathBuf>> {
    // A panic while the lock was held cannot leave the list inconsistent (push and retain).
    IN_FLIGHT.lock().unwrap_or_else(PoisonError::into_inner)
}

/// Removes the temporary files this process is writing now, and returns how many it removed:
/// for an exit that skips destructors (the CLI's `_exit` on a second Ctrl-C), so that no
/// temporary file outlives the process. A write still in progress then fails at its rename.
pub fn remove_temporaries_in_flight() -> usize {
    let paths = std::mem::take(&mut *in_flight());
    paths.iter().filter(|p| fs::remove_file(p).is_ok()).count()
}

/// Removes the temporary files that an earlier furnace process left beside `path` when it died
/// while writing it (`.NAME.furnace-tmp-PID.N`, and `.NAME.PID.N.tmp` of earlier versions), if
/// that process is no longer running; returns the files removed. Files of this process and of
/// running processes are left alone: they may be in the middle of a write. Where it cannot be
/// told whether a process runs (no `/proc`), every other process's file counts as stale.
///
/// # Errors
/// [`PostError::Io`] naming a file that could not be removed. A directory that cannot be listed
/// (it does not exist yet) has nothing to remove: `Ok` with no files.
pub fn remove_stale_temporaries(path: &Path) -> Result<Vec<PathBuf>, PostError> {
    let Some(name) = path.file_name().map(|n| n.to_string_lossy().into_owned()) else {
        return Ok(Vec::new());
    };
    let dir = match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d,
        _ => Path::new("."),
    };
    let Ok(entries) = fs::read_dir(dir) else { return Ok(Vec::new()) };
    let mut removed = Vec::new();
    for entry in entries.flatten() {
        let file_name = entry.file_name();
        let Some(pid) = file_name.to_str().and_then(|n| temp_owner(n, &name)) else { continue };
        if pid == std::process::id() || process_runs(pid) {
            continue;
        }
        let stale = entry.path();
        if entry.file_type().is_ok_and(|t| t.is_file()) {
            fs::remove_file(&stale).map_err(|source| PostError::Io { path: stale.clone(), source })?;
            removed.push(stale);
        }
    }
    removed.sort();
    Ok(removed)
}

/// The pid in `entry` if it is the name of a temporary file of target `name`.
fn temp_owner(entry: &str, name: &str) -> Option<u32> {
    let rest = entry.strip_prefix('.')?.strip_prefix(name)?;
    let digits = |s: &str| !s.is_empty() && s.bytes().all(|b| b.is_ascii_digit());
    let (pid, n) = if let Some(rest) = rest.strip_prefix(TEMP_TAG) {
        rest.split_once('.')?
    } else {
        // `.NAME.PID.N.tmp`, the name of earlier versions.
        rest.strip_prefix('.')?.strip_suffix(".tmp")?.split_once('.')?
    };
    if !digits(n) {
        return None;
    }
    if digits(pid) { pid.parse().ok() } else { None }
}

/// Whether process `pid` runs (by `/proc`); `false` where that cannot be told.
fn process_runs(pid: u32) -> bool {
    Path::new("/proc/self").exists() && Path::new("/proc").join(pid.to_string()).exists()
}

/// A temporary file registered in [`IN_FLIGHT`]; removed (and unregistered) on drop unless it
/// was renamed into place.
struct TempGuard {
    path: PathBuf,
    armed: bool,
}

impl TempGuard {
    /// Registers `path`, then creates it (registered first, so that no moment exists where the
    /// file is there but unknown to [`remove_temporaries_in_flight`]).
    fn create(path: PathBuf) -> io::Result<(Self, File)> {
        in_flight().push(path.clone());
        let guard = Self { path, armed: true };
        let file = OpenOptions::new().write(true).create_new(true).open(&guard.path)?;
        Ok((guard, file))
    }

    /// Renames the file to `target`.
    fn rename_to(&mut self, target: &Path) -> io::Result<()> {
        fs::rename(&self.path, target)?;
        self.armed = false;
        in_flight().retain(|p| p != &self.path);
        Ok(())
    }
}

impl Drop for TempGuard {
    fn drop(&mut self) {
        if self.armed {
            // Best effort: the write already failed; a failure to clean up must not mask it.
            let _ = fs::remove_file(&self.path);
            in_flight().retain(|p| p != &self.path);
        }
    }
}

/// A file written to its temporary name by [`stage`], waiting to be renamed into place by
/// [`Staged::commit`]; dropped without a commit, the temporary file is removed and the target
/// left as it was.
#[must_use = "a staged file is removed unless committed"]
pub struct Staged {
    target: PathBuf,
    guard: TempGuard,
}

impl Staged {
    /// The file it will replace.
    pub fn target(&self) -> &Path {
        &self.target
    }

    /// Renames the temporary file to the target (atomically replacing any old file).
    ///
    /// # Errors
    /// [`PostError::Io`] naming the target; the temporary file is then removed.
    pub fn commit(mut self) -> Result<(), PostError> {
        let target = std::mem::take(&mut self.target);
        self.guard.rename_to(&target).map_err(|source| PostError::Io { path: target, source })
    }
}

impl std::fmt::Debug for Staged {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Staged").field("target", &self.target).field("temporary", &self.guard.path).finish()
    }
}

/// Writes `path`'s new content to a fresh temporary file in the same directory and syncs it,
/// without touching `path`: [`Staged::commit`] then renames it into place. On any error
/// (including a panic inside `write`) the temporary file is removed.
///
/// # Errors
/// [`PostError::Io`] naming `path`, or what `write` returns.
pub fn stage(
    path: &Path,
    write: impl FnOnce(&mut File) -> Result<(), PostError>,
) -> Result<Staged, PostError> {
    let io_err = |source: io::Error| PostError::Io { path: path.to_path_buf(), source };
    if path.file_name().is_none() {
        return Err(io_err(io::Error::new(io::ErrorKind::InvalidInput, "not a file path")));
    }
    let (guard, mut file) = TempGuard::create(temp_path(path)).map_err(io_err)?;
    write(&mut file)?;
    file.sync_all().map_err(io_err)?;
    drop(file);
    Ok(Staged { target: path.to_path_buf(), guard })
}

/// Writes `path` atomically: `write` fills a fresh temporary file in the same directory, which
/// is then synced and renamed to `path` ([`stage`], then [`Staged::commit`]). On any error
/// (including a panic inside `write`) the temporary file is removed and `path` is left as it
/// was.
///
/// # Errors
/// [`PostError::Io`] naming `path`, or what `write` returns.
pub fn write_atomic(
    path: &Path,
    write: impl FnOnce(&mut File) -> Result<(), PostError>,
) -> Result<(), PostError> {
    stage(path, write)?.commit()
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
    fn staged_files_appear_only_on_commit() {
        let dir = scratch("staged");
        let (a, b) = (dir.join("a.exr"), dir.join("b.png"));
        fs::write(&a, b"old a").unwrap();
        let sa =
            stage(&a, |f| f.write_all(b"new a").map_err(|e| PostError::Io { path: a.clone(), source: e }))
                .unwrap();
        // The second file fails: the first, staged, is dropped uncommitted.
        let failed = stage(&b, |_| Err(PostError::Io { path: b.clone(), source: io::Error::other("full") }));
        assert!(failed.is_err());
        drop(sa);
        assert_eq!(fs::read(&a).unwrap(), b"old a");
        assert_eq!(entries(&dir), vec!["a.exr".to_string()]);
        let sa =
            stage(&a, |f| f.write_all(b"new a").map_err(|e| PostError::Io { path: a.clone(), source: e }))
                .unwrap();
        assert_eq!(sa.target(), a);
        sa.commit().unwrap();
        assert_eq!(fs::read(&a).unwrap(), b"new a");
        assert_eq!(entries(&dir), vec!["a.exr".to_string()]);
        fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn temporaries_in_flight_are_removed_on_request() {
        let dir = scratch("in_flight");
        let path = dir.join("r.exr");
        let staged = stage(&path, |_| Ok(())).unwrap();
        let temp = staged.guard.path.clone();
        let name = temp.file_name().unwrap().to_string_lossy().into_owned();
        assert!(name.starts_with(".r.exr.furnace-tmp-"), "{name}");
        assert!(temp.exists());
        // Other tests may have files in flight too: at least this one is removed.
        assert!(remove_temporaries_in_flight() >= 1);
        assert!(!temp.exists());
        // Its commit then fails, naming the target, and leaves nothing behind.
        let e = staged.commit().unwrap_err();
        assert!(e.to_string().contains("r.exr"), "{e}");
        assert!(entries(&dir).is_empty(), "{:?}", entries(&dir));
        fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn stale_temporaries_of_dead_processes_are_removed() {
        let dir = scratch("stale");
        let path = dir.join("r.exr");
        // No process has the largest pid (Linux's limit is 2^22); pid 1 always runs.
        let dead = format!(".r.exr{TEMP_TAG}{}.0", u32::MAX);
        let old_style = format!(".r.exr.{}.3.tmp", u32::MAX);
        let mine = format!(".r.exr{TEMP_TAG}{}.7", std::process::id());
        let other = format!(".other.exr{TEMP_TAG}{}.0", u32::MAX);
        let mut names = vec![dead.clone(), old_style.clone(), mine.clone(), other.clone(), "r.exr".into()];
        if process_runs(1) {
            names.push(format!(".r.exr{TEMP_TAG}1.0"));
        }
        for n in &names {
            fs::write(dir.join(n), b"x").unwrap();
        }
        let removed = remove_stale_temporaries(&path).unwrap();
        let mut expected = vec![dir.join(&dead), dir.join(&old_style)];
        expected.sort();
        assert_eq!(removed, expected);
        names.retain(|n| n != &dead && n != &old_style);
        names.sort();
        assert_eq!(entries(&dir), names);
        assert!(remove_stale_temporaries(&dir.join("none").join("x.exr")).unwrap().is_empty());
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
