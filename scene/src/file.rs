//! Reading the files a scene names (the scene itself, its buffers and images, environment maps)
//! with bounded time and memory: only regular files are opened (a FIFO would block in `open`
//! itself, `/dev/zero` or `/dev/urandom` never end), and no read goes beyond a stated number of
//! bytes, so a file cannot make the loader hang or exhaust memory.

use std::fs::File;
use std::io::{self, Read};
use std::path::Path;

/// What a path names when it is not a regular file, for messages.
fn kind_of(meta: &std::fs::Metadata) -> &'static str {
    let t = meta.file_type();
    if t.is_dir() {
        return "a directory";
    }
    #[cfg(unix)]
    {
        use std::os::unix::fs::FileTypeExt;
        if t.is_fifo() {
            return "a FIFO";
        }
        if t.is_char_device() || t.is_block_device() {
            return "a device";
        }
        if t.is_socket() {
            return "a socket";
        }
    }
    "not a regular file"
}

fn not_regular(meta: &std::fs::Metadata) -> io::Error {
    io::Error::new(io::ErrorKind::InvalidInput, format!("{}: only regular files are read", kind_of(meta)))
}

/// Opens `path` for reading if it names a regular file (symbolic links followed), with its
/// length. The path is examined before it is opened, because opening a FIFO blocks until a
/// writer comes; the open handle is examined again, so that a path swapped for something else
/// between the two is still refused (a FIFO swapped in at that instant can still block `open`:
/// Rust's standard library offers no portable non-blocking open).
pub(crate) fn open_regular(path: &Path) -> io::Result<(File, u64)> {
    let meta = std::fs::metadata(path)?;
    if !meta.is_file() {
        return Err(not_regular(&meta));
    }
    let file = File::open(path)?;
    let meta = file.metadata()?;
    if !meta.is_file() {
        return Err(not_regular(&meta));
    }
    Ok((file, meta.len()))
}

/// The bytes of the regular file `path`; an error, before anything is read, when it is longer
/// than `max` bytes (`what` names the limit in the message). At most `max` bytes are read even
/// if the file grows meanwhile.
pub(crate) fn read_regular(path: &Path, max: u64, what: &str) -> io::Result<Vec<u8>> {
    let (file, len) = open_regular(path)?;
    if len > max {
        return Err(too_large(len, max, what));
    }
    let mut bytes = Vec::with_capacity(len as usize);
    file.take(max).read_to_end(&mut bytes)?;
    Ok(bytes)
}

/// The first `len` bytes of the regular file `path` (a buffer reads its `byteLength`, no
/// more): an error naming both lengths when the file is shorter.
pub(crate) fn read_prefix(path: &Path, len: u64) -> io::Result<Vec<u8>> {
    let (file, file_len) = open_regular(path)?;
    if file_len < len {
        return Err(io::Error::new(
            io::ErrorKind::UnexpectedEof,
            format!("the file has {file_len} bytes, fewer than the byteLength {len}"),
        ));
    }
    let mut bytes = Vec::with_capacity(len as usize);
    file.take(len).read_to_end(&mut bytes)?;
    if (bytes.len() as u64) < len {
        return Err(io::Error::new(
            io::ErrorKind::UnexpectedEof,
            format!("only {} bytes could be read, fewer than the byteLength {len}", bytes.len()),
        ));
    }
    Ok(bytes)
}

fn too_large(len: u64, max: u64, what: &str) -> io::Error {
    io::Error::new(
        io::ErrorKind::InvalidData,
        format!("{len} bytes is more than the {max} bytes {what} may have"),
    )
}

/// Whether the percent-decoded URI `rel` is an absolute path (`/etc/x`, `\\server\x`, `C:\x`,
/// `C:/x`, and `c:x`, which RFC 3986 would read as a scheme). `Path::join` would let it replace
/// the scene's folder, so the loader refuses it: a glTF URI that is not a data URI is a
/// reference relative to the glTF file (glTF 2.0 §3.9.1 with RFC 3986), and an asset that names
/// a place outside its own folder by an absolute path is not portable.
pub(crate) fn is_absolute_uri_path(rel: &str) -> bool {
    let b = rel.as_bytes();
    let drive = b.len() >= 2 && b[0].is_ascii_alphabetic() && b[1] == b':';
    rel.starts_with('/') || rel.starts_with('\\') || drive || Path::new(rel).is_absolute()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn absolute_paths_are_recognised() {
        for p in ["/etc/passwd", "\\\\server\\share\\x.bin", "C:\\x.bin", "c:/x.bin", "/", "a:b.bin"] {
            assert!(is_absolute_uri_path(p), "{p}");
        }
        for p in ["x.bin", "sub/x.bin", "../shared/x.png", "./x.bin"] {
            assert!(!is_absolute_uri_path(p), "{p}");
        }
    }
}
