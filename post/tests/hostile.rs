//! Hostile EXR inputs: headers claiming huge images, files that are not regular files, resume
//! state cropped after it was written, and the regression files of the fuzzer
//! (`tests/data/hostile/cli/`). Each must end in one error naming the file (and the attribute),
//! in bounded time and memory; never a panic, an abort or a hang.

use furnace_post::{
    MAX_COMPRESSION_RATIO, MAX_IMAGE_SIDE, Metadata, PostError, read_exr, read_exr_metadata,
    read_exr_with_state, write_exr, write_exr_with_state,
};
use furnace_render::Film;
use glam::{DVec3, Vec3};
use std::fs;
use std::path::{Path, PathBuf};
use std::sync::mpsc;
use std::time::Duration;

/// A fresh, empty scratch directory under `target/test-output/post/`.
fn scratch(name: &str) -> PathBuf {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../target/test-output/post/hostile").join(name);
    let _ = fs::remove_dir_all(&dir);
    fs::create_dir_all(&dir).unwrap();
    dir
}

/// The three readers' errors for `path`, each in a thread given `limit` to answer: a reader
/// that blocks (on a FIFO) fails the test instead of hanging it.
fn read_all(path: &Path, limit: Duration) -> [Result<(), PostError>; 3] {
    let (tx, rx) = mpsc::channel();
    let p = path.to_path_buf();
    std::thread::spawn(move || {
        let results =
            [read_exr(&p).map(drop), read_exr_metadata(&p).map(drop), read_exr_with_state(&p).map(drop)];
        let _ = tx.send(results);
    });
    rx.recv_timeout(limit)
        .unwrap_or_else(|_| panic!("{}: a reader did not return in {limit:?}", path.display()))
}

/// The byte offset of the value of header attribute `name` (after its name, type and size).
fn attribute_value(bytes: &[u8], name: &str) -> usize {
    let key: Vec<u8> = [name.as_bytes(), b"\0"].concat();
    let at = bytes.windows(key.len()).position(|w| w == key).unwrap_or_else(|| panic!("no {name}"));
    let type_end = at + key.len() + bytes[at + key.len()..].iter().position(|&b| b == 0).unwrap();
    type_end + 1 + 4
}

/// A small valid EXR (8 × 4, RGB) whose `dataWindow` is patched to `width` × `height`.
fn with_data_window(dir: &Path, width: i32, height: i32) -> PathBuf {
    let path = dir.join(format!("window_{width}x{height}.exr"));
    write_exr(&path, 8, 4, &[Vec3::splat(0.5); 32], &Metadata::default()).unwrap();
    let mut bytes = fs::read(&path).unwrap();
    // box2i: xMin, yMin, xMax, yMax.
    let v = attribute_value(&bytes, "dataWindow");
    bytes[v + 8..v + 12].copy_from_slice(&(width - 1).to_le_bytes());
    bytes[v + 12..v + 16].copy_from_slice(&(height - 1).to_le_bytes());
    fs::write(&path, bytes).unwrap();
    path
}

/// A read of a file of a few hundred bytes has no reason to take longer than this, even in the
/// debug profile on a loaded machine; a blocked or looping reader takes forever.
const QUICK: Duration = Duration::from_secs(20);

#[test]
fn a_data_window_of_100000_squared_is_refused_from_the_header() {
    let dir = scratch("huge");
    let path = with_data_window(&dir, 100_000, 100_000);
    for e in read_all(&path, QUICK) {
        let e = e.unwrap_err();
        assert!(matches!(e, PostError::TooLarge { width: 100_000, height: 100_000, .. }), "{e}");
        let text = e.to_string();
        assert!(text.contains("window_100000x100000.exr") && text.contains("'dataWindow'"), "{text}");
        assert!(text.contains(&MAX_IMAGE_SIDE.to_string()), "{text}");
    }
}

#[test]
fn a_large_image_in_a_small_file_is_refused_before_its_pixels_are_allocated() {
    // Within the largest side, but 16384² × 12 bytes of pixel data cannot be in a file of a few
    // hundred bytes: the exr crate would allocate 3 GiB before it found the blocks missing.
    let dir = scratch("small_file");
    let side = MAX_IMAGE_SIDE as i32;
    let path = with_data_window(&dir, side, side);
    let file_bytes = fs::metadata(&path).unwrap().len();
    assert!(u64::from(MAX_IMAGE_SIDE).pow(2) * 12 > file_bytes * MAX_COMPRESSION_RATIO);
    for e in read_all(&path, QUICK) {
        let e = e.unwrap_err();
        assert!(matches!(e, PostError::TooLittleData { .. }), "{e}");
        assert!(e.to_string().contains("truncated or damaged"), "{e}");
    }
}

#[test]
fn constant_images_compress_below_the_bound() {
    // The most compressible image, one colour, with every codec the exr crate writes: its ratio
    // of pixel bytes to file bytes must stay well below MAX_COMPRESSION_RATIO. A factor 8: the
    // ratio grows with the image towards the codec's limit (zlib's 1032:1, 3× over 330:1).
    use exr::prelude::*;
    let dir = scratch("ratios");
    let (w, h) = (1024usize, 1024usize);
    let mut worst = 0.0f64;
    for (name, compression) in [
        ("none", Compression::Uncompressed),
        ("rle", Compression::RLE),
        ("zip1", Compression::ZIP1),
        ("zip16", Compression::ZIP16),
        ("piz", Compression::PIZ),
        ("pxr24", Compression::PXR24),
        ("b44", Compression::B44),
        ("b44a", Compression::B44A),
    ] {
        let path = dir.join(format!("{name}.exr"));
        let channels = SpecificChannels::rgb(|_: Vec2<usize>| (f16::ZERO, f16::ZERO, f16::ZERO));
        let encoding = Encoding { compression, ..Encoding::default() };
        let layer = Layer::new((w, h), LayerAttributes::default(), encoding, channels);
        Image::from_layer(layer).write().to_file(&path).unwrap();
        let ratio = (w * h * 6) as f64 / fs::metadata(&path).unwrap().len() as f64;
        println!("{name:>6}: {ratio:8.1}:1");
        worst = worst.max(ratio);
        // The image reads back: the bound refuses no real file.
        read_exr(&path).unwrap();
    }
    assert!(worst * 8.0 < MAX_COMPRESSION_RATIO as f64, "best compression {worst}:1");
}

#[test]
#[cfg(unix)]
fn a_fifo_or_a_directory_is_refused_without_blocking() {
    let dir = scratch("fifo");
    let fifo = dir.join("pipe.exr");
    let made = std::process::Command::new("mkfifo").arg(&fifo).status().unwrap();
    assert!(made.success());
    for e in read_all(&fifo, QUICK) {
        let e = e.unwrap_err();
        assert!(matches!(e, PostError::NotAFile { kind: "a FIFO", .. }), "{e}");
        assert!(e.to_string().contains("pipe.exr: a FIFO, not a regular file"), "{e}");
    }
    for e in read_all(&dir, QUICK) {
        assert!(e.unwrap_err().to_string().contains("a directory, not a regular file"));
    }
    for e in read_all(Path::new("/dev/zero"), QUICK) {
        assert!(e.unwrap_err().to_string().contains("/dev/zero: a device, not a regular file"));
    }
}

/// A 64 × 32 film with some samples in every pixel, and its metadata.
fn film_64x32() -> (Film, Metadata) {
    let (w, h) = (64u32, 32u32);
    let n = (w * h) as usize;
    let sums = (0..n).map(|i| DVec3::splat(i as f64 * 0.25)).collect();
    let film = Film::from_parts(w, h, sums, vec![4; n], 0).unwrap();
    (film, Metadata { spp: Some(4), rejected_samples: Some(0), ..Metadata::default() })
}

#[test]
fn resume_state_cropped_after_writing_is_refused() {
    // What an image tool's crop does to a furnace EXR: every channel cut to 32 × 16 (the state
    // stays consistent with the RGB), every attribute kept.
    use exr::prelude::*;
    let dir = scratch("cropped");
    let path = dir.join("full.exr");
    let (film, meta) = film_64x32();
    write_exr_with_state(&path, &film, &meta).unwrap();
    let image = read()
        .no_deep_data()
        .largest_resolution_level()
        .all_channels()
        .first_valid_layer()
        .all_attributes()
        .from_file(&path)
        .unwrap();
    let (cw, ch) = (32usize, 16usize);
    let crop = |samples: &FlatSamples| -> FlatSamples {
        let keep = |i: usize| i % 64 < cw && i / 64 < ch;
        match samples {
            FlatSamples::F32(v) => {
                FlatSamples::F32(v.iter().enumerate().filter(|(i, _)| keep(*i)).map(|(_, x)| *x).collect())
            }
            FlatSamples::U32(v) => {
                FlatSamples::U32(v.iter().enumerate().filter(|(i, _)| keep(*i)).map(|(_, x)| *x).collect())
            }
            FlatSamples::F16(v) => {
                FlatSamples::F16(v.iter().enumerate().filter(|(i, _)| keep(*i)).map(|(_, x)| *x).collect())
            }
        }
    };
    let list: SmallVec<[AnyChannel<FlatSamples>; 4]> = image
        .layer_data
        .channel_data
        .list
        .iter()
        .map(|c| AnyChannel::new(c.name.clone(), crop(&c.sample_data)))
        .collect();
    let layer = Layer::new(
        (cw, ch),
        image.layer_data.attributes.clone(),
        Encoding::SMALL_LOSSLESS,
        AnyChannels::sort(list),
    );
    let cropped = dir.join("cropped.exr");
    Image::from_layer(layer).write().to_file(&cropped).unwrap();

    let e = read_exr_with_state(&cropped).unwrap_err();
    assert!(matches!(e, PostError::FilmState { .. }), "{e}");
    let text = e.to_string();
    assert!(
        text.contains("cropped.exr")
            && text.contains("'furnace.resume.size' records a 64×32 film but the data window is 32×16"),
        "{text}"
    );
    // The image alone still reads (compare needs no state).
    assert_eq!(read_exr(&cropped).unwrap().0, 32);
    // The size record is the file's own: it does not appear among the metadata.
    assert_eq!(read_exr_with_state(&path).unwrap().metadata, meta);
}

#[test]
fn attribute_values_are_not_echoed_when_they_are_not_short_text() {
    let dir = scratch("echo");
    let path = dir.join("e.exr");
    let m = Metadata { spp: Some(1_234_567_890), ..Metadata::default() };
    write_exr(&path, 1, 1, &[Vec3::ZERO], &m).unwrap();
    let mut bytes = fs::read(&path).unwrap();
    let at = bytes.windows(10).position(|w| w == b"1234567890").unwrap();
    // An escape sequence in place of the number: never printed raw.
    bytes[at..at + 10].copy_from_slice(b"\x1b[2J\x1b[31ma");
    fs::write(&path, bytes).unwrap();
    let e = read_exr(&path).unwrap_err().to_string();
    assert!(e.contains("'furnace.spp' = (a text of 10 bytes) is not a valid u32"), "{e}");
    assert!(!e.contains('\x1b'), "{e:?}");
}

#[test]
fn the_hostile_files_fail_cleanly_naming_the_file() {
    // The crafted files of `tests/data/hostile/cli/` (the fuzzer's findings would join them):
    // what each reader must answer, `None` for a file it reads.
    let dir = furnace_tests::data::data_dir().join("hostile/cli");
    let big = "'dataWindow' gives 100000×100000 pixels";
    let small = "16384×16384 pixels, 3221225472 bytes of pixel data";
    let cropped = "'furnace.resume.size' records a 64×32 film but the data window is 32×16";
    for (name, image, header, state) in [
        ("huge_data_window.exr", Some(big), Some(big), Some(big)),
        ("large_window_small_file.exr", Some(small), Some(small), Some(small)),
        ("cropped_resume_state.exr", None, None, Some(cropped)),
    ] {
        let path = dir.join(name);
        let [r_image, r_header, r_state] = read_all(&path, QUICK);
        for (result, want) in [(r_image, image), (r_header, header), (r_state, state)] {
            match (result, want) {
                (Ok(()), None) => {}
                (Err(e), Some(want)) => {
                    let e = e.to_string();
                    assert!(e.contains(name) && e.contains(want), "{name}: {e}");
                }
                (r, want) => panic!("{name}: {:?}, expected {want:?}", r.map_err(|e| e.to_string())),
            }
        }
    }
    // Every file of the folder is in the table above.
    assert_eq!(fs::read_dir(&dir).unwrap().count(), 3);
}
