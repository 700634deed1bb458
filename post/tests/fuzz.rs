//! Deterministic mutation fuzzing of the EXR readers that resume, merge and compare go
//! through: [`read_exr_with_state`], [`read_exr`] and [`read_exr_metadata`] on mutants of a
//! small real resumable EXR written by [`write_exr_with_state`] (a film with AOVs and
//! adaptive-sampling state, every metadata field). Each mutant is one to three mutations: bit
//! flips, bytes set to 0, 0xFF or a random value, truncation, a span duplicated or deleted, and
//! header attribute values (`dataWindow`, `channels`, `compression`, the furnace records …)
//! replaced by extremes. Each read must return (`Ok` or an error) without a panic and within
//! [`MAX_READ`]. Mutant `i` depends only on [`SEED`] and `i`, so a failure is reproduced by its
//! index; its bytes are also written to `target/test-output/post/fuzz/`.
//!
//! No coverage guidance (cargo-fuzz needs nightly): a fixed number of mutants, enough for every
//! mutation kind to reach the header parser, the offset tables, the decompressors and furnace's
//! own checks of the state many times over.

use furnace_post::{
    Metadata, PostError, read_exr, read_exr_metadata, read_exr_with_state, write_exr_with_state,
};
use furnace_render::{AdaptiveSampling, AovSample, Film};
use furnace_tests::Rng;
use glam::Vec3;
use std::panic::{AssertUnwindSafe, catch_unwind};
use std::path::{Path, PathBuf};
use std::sync::mpsc;
use std::time::{Duration, Instant};

/// The seed of every mutant.
const SEED: u64 = 0x0ec5_f022;

/// Mutants: about 12 s in the test profile on one core (850 mutants/s), under the minute on 2
/// shared cores; every mutation kind about 2500 times, every attribute's value about 400.
const MUTANTS: usize = 10_000;

/// The longest the three reads of one mutant may take. The seed file reads in well under a
/// millisecond; a mutant taking 10 s is a hang (or memory thrashing), not a slow machine.
const MAX_READ: Duration = Duration::from_secs(10);

/// Header attributes whose values the attribute mutation replaces.
const ATTRIBUTES: [&str; 11] = [
    "dataWindow",
    "displayWindow",
    "channels",
    "compression",
    "lineOrder",
    "furnace.spp",
    "furnace.bounces",
    "furnace.rejectedSamples",
    "furnace.renderTimeS",
    "furnace.resume.size",
    "furnace.target_spp",
];

/// Values an `i32` field of a header is set to.
const EXTREME_I32: [i32; 10] = [0, -1, 1, i32::MIN, i32::MAX, 16_383, 16_384, 100_000, -100_000, 1 << 30];

/// Texts a furnace attribute's value is replaced by (truncated or padded with spaces to the
/// value's length, so the header stays parseable).
const EXTREME_TEXT: [&[u8]; 6] =
    [b"4294967295", b"18446744073709551615", b"-1", b"NaN", b"99999x99999", b"\xff\xfe\x00\x1b[2J"];

/// The seed file: a 6 × 4 film with AOVs and adaptive state, a rejected sample, all metadata.
fn seed_file(dir: &Path) -> Vec<u8> {
    let mut film = Film::with_aovs(6, 4).with_adaptive();
    let hit = AovSample { albedo: Vec3::new(0.8, 0.5, 0.2), normal: Vec3::Z, depth: Some(3.5) };
    for (i, (x, y)) in (0..4).flat_map(|y| (0..6).map(move |x| (x, y))).enumerate() {
        for s in 0..3 {
            let v = Vec3::new(i as f32 * 0.1, s as f32, 0.25);
            film.add_sample_with_aovs(x, y, v, if s == 1 { &AovSample::MISS } else { &hit });
        }
    }
    film.add_sample_with_aovs(0, 0, Vec3::NAN, &hit);
    film.test_convergence(&AdaptiveSampling { threshold: 0.5, min_samples: 2 });
    let mut meta = Metadata {
        spp: Some(3),
        sampler: Some("sobol".into()),
        bounces: Some(4),
        seed: Some(7),
        scene: Some("<built-in cbox>".into()),
        render_time_s: Some(0.125),
        rejected_samples: Some(film.rejected()),
        ..Metadata::default()
    };
    meta.extra.insert("furnace.target_spp".into(), "64".into());
    let path = dir.join("seed.exr");
    write_exr_with_state(&path, &film, &meta).unwrap();
    let bytes = std::fs::read(&path).unwrap();
    // The seed reads back whole: the mutants start from a valid file.
    let back = read_exr_with_state(&path).unwrap();
    assert!(back.state.is_some_and(|f| f.has_aovs() && f.converged().is_some()));
    bytes
}

/// About where the header ends: past the last value of the [`ATTRIBUTES`] found (enough to
/// aim mutations at the header).
fn header_end(bytes: &[u8]) -> usize {
    let mut end = 8;
    for name in ATTRIBUTES {
        if let Some((_, value_end)) = attribute(bytes, name) {
            end = end.max(value_end);
        }
    }
    (end + 1).min(bytes.len())
}

/// The byte range of header attribute `name`'s value (after its name, type and size).
fn attribute(bytes: &[u8], name: &str) -> Option<(usize, usize)> {
    let key: Vec<u8> = [name.as_bytes(), b"\0"].concat();
    let at = bytes.windows(key.len()).position(|w| w == key)?;
    let type_start = at + key.len();
    let type_end = type_start + bytes.get(type_start..)?.iter().position(|&b| b == 0)?;
    let size_at = type_end + 1;
    let size = i32::from_le_bytes(bytes.get(size_at..size_at + 4)?.try_into().ok()?);
    let start = size_at + 4;
    let end = start + usize::try_from(size).ok()?;
    (end <= bytes.len()).then_some((start, end))
}

/// Applies one random mutation to `bytes`.
fn mutate(bytes: &mut Vec<u8>, rng: &mut Rng) {
    let len = bytes.len().max(1);
    let at = |rng: &mut Rng, n: usize| (rng.next_u64() % n.max(1) as u64) as usize;
    match rng.next_u64() % 8 {
        0 => {
            let i = at(rng, len);
            if let Some(b) = bytes.get_mut(i) {
                *b ^= 1 << (rng.next_u64() % 8);
            }
        }
        1 => {
            // Most of what decides allocation and structure is in the header: aim half there.
            let span = if rng.next_u64() & 1 == 0 { header_end(bytes) } else { len };
            let i = at(rng, span);
            let value = [0u8, 0xff, rng.u32() as u8][at(rng, 3)];
            if let Some(b) = bytes.get_mut(i) {
                *b = value;
            }
        }
        2 => {
            let keep = at(rng, len);
            bytes.truncate(keep);
        }
        3 => {
            // A span duplicated in place or deleted.
            let start = at(rng, len);
            let end = (start + 1 + at(rng, 64)).min(bytes.len());
            if start < end {
                if rng.next_u64() & 1 == 0 {
                    let copy = bytes[start..end].to_vec();
                    bytes.splice(end..end, copy);
                } else {
                    bytes.drain(start..end);
                }
            }
        }
        4 => {
            // An i32 of the header (or offset table) set to an extreme.
            let i = at(rng, header_end(bytes) + 64);
            let v = EXTREME_I32[at(rng, EXTREME_I32.len())].to_le_bytes();
            if i + 4 <= bytes.len() {
                bytes[i..i + 4].copy_from_slice(&v);
            }
        }
        _ => {
            // An attribute's value: an i32 in it set to an extreme, or its text replaced.
            let name = ATTRIBUTES[at(rng, ATTRIBUTES.len())];
            let Some((start, end)) = attribute(bytes, name) else { return };
            if name.starts_with("furnace.") {
                let text = EXTREME_TEXT[at(rng, EXTREME_TEXT.len())];
                for (k, b) in bytes[start..end].iter_mut().enumerate() {
                    *b = text.get(k).copied().unwrap_or(b' ');
                }
            } else if end - start >= 4 {
                let i = start + 4 * at(rng, (end - start) / 4);
                let v = EXTREME_I32[at(rng, EXTREME_I32.len())].to_le_bytes();
                bytes[i..i + 4].copy_from_slice(&v);
            } else {
                bytes[start] = rng.u32() as u8;
            }
        }
    }
}

/// Mutant `index` of `seed`: one to three mutations, from a generator seeded by [`SEED`] and
/// the index alone.
fn mutant(seed: &[u8], index: usize) -> Vec<u8> {
    let mut rng = Rng::new(SEED ^ (index as u64).wrapping_mul(0x9e37_79b9_7f4a_7c15));
    let mut bytes = seed.to_vec();
    for _ in 0..1 + rng.next_u64() % 3 {
        mutate(&mut bytes, &mut rng);
    }
    bytes
}

/// What went wrong with a mutant.
enum Failure {
    Panic(String),
    Hang,
}

/// The kind of `read_exr_with_state`'s answer, for the tally.
fn outcome(r: &Result<furnace_post::ExrWithState, PostError>) -> &'static str {
    match r {
        Ok(_) => "read",
        Err(PostError::Exr { .. }) => "Exr",
        Err(PostError::FilmState { .. }) => "FilmState",
        Err(PostError::InvalidMetadataValue { .. }) => "InvalidMetadataValue",
        Err(PostError::TooLarge { .. }) => "TooLarge",
        Err(PostError::TooLittleData { .. }) => "TooLittleData",
        Err(_) => "other",
    }
}

/// The three readers on `path`, each under `catch_unwind`, in a thread given [`MAX_READ`];
/// `Ok` with the kind of `read_exr_with_state`'s answer.
fn read_mutant(path: &Path) -> Result<&'static str, Failure> {
    let (tx, rx) = mpsc::channel();
    let p = path.to_path_buf();
    std::thread::spawn(move || {
        let outcome = catch_unwind(AssertUnwindSafe(|| {
            let kind = outcome(&read_exr_with_state(&p));
            let _ = read_exr(&p);
            let _ = read_exr_metadata(&p);
            kind
        }));
        let _ = tx.send(outcome.map_err(|payload| {
            payload
                .downcast_ref::<String>()
                .cloned()
                .or_else(|| payload.downcast_ref::<&str>().map(|s| s.to_string()))
                .unwrap_or_default()
        }));
    });
    match rx.recv_timeout(MAX_READ) {
        Ok(Ok(kind)) => Ok(kind),
        Ok(Err(message)) => Err(Failure::Panic(message)),
        Err(_) => Err(Failure::Hang),
    }
}

#[test]
fn exr_readers_survive_mutants() {
    let out = Path::new(env!("CARGO_MANIFEST_DIR")).join("../target/test-output/post/fuzz");
    let _ = std::fs::remove_dir_all(&out);
    std::fs::create_dir_all(&out).unwrap();
    let seed = seed_file(&out);
    let start = Instant::now();
    let mut failures: Vec<(usize, String, PathBuf)> = Vec::new();
    let mut tally = std::collections::BTreeMap::new();
    for i in 0..MUTANTS {
        let bytes = mutant(&seed, i);
        let path = out.join("mutant.exr");
        std::fs::write(&path, &bytes).unwrap();
        let failure = match read_mutant(&path) {
            Ok(kind) => {
                *tally.entry(kind).or_insert(0usize) += 1;
                continue;
            }
            Err(Failure::Panic(m)) => format!("panicked: {m}"),
            Err(Failure::Hang) => format!("did not return within {MAX_READ:?}"),
        };
        let kept = out.join(format!("crash_{i}.exr"));
        std::fs::write(&kept, &bytes).unwrap();
        let hang = failure.starts_with("did not");
        failures.push((i, failure, kept));
        if hang {
            // The stuck thread cannot be stopped: report what there is.
            break;
        }
    }
    let seconds = start.elapsed().as_secs_f64();
    println!(
        "EXR fuzz: {} mutants × 3 readers of a {}-byte seed in {seconds:.1} s ({:.0} mutants/s), {} failures",
        MUTANTS,
        seed.len(),
        MUTANTS as f64 / seconds,
        failures.len()
    );
    println!("read_exr_with_state's answers: {tally:?}");
    let _ = std::fs::remove_file(out.join("mutant.exr"));
    assert!(
        failures.is_empty(),
        "{} mutants failed:\n{}",
        failures.len(),
        failures
            .iter()
            .map(|(i, f, p)| format!("mutant {i} {f} (input: {})", p.display()))
            .collect::<Vec<_>>()
            .join("\n")
    );
}
