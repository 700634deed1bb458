//! Deterministic mutation fuzzing of the loaders: [`Scene::from_slice`] over small real glTF and
//! GLB files (Khronos samples, the glTF-Validator and edge-case corpora) and the hostile ones,
//! [`EnvironmentMap::from_bytes`] over tiny `.hdr` and `.exr` maps. Each mutant is one to three mutations (bit flips, bytes set to 0, 0xFF or a random
//! value, truncation, a span duplicated or deleted, and on glTF JSON — a GLB's JSON chunk
//! included, its lengths rewritten — numbers replaced by extremes or by other types, keys
//! deleted, strings replaced); each must load or fail with an error, never panic, and finish in
//! bounded time. Mutant `i` of a file depends only on [`SEED`], the file and `i`, so a failure
//! is reproduced by its name (`FILE.mutant-i`); its bytes are also written to
//! `target/test-output/scene/fuzz/`.
//!
//! No coverage guidance (cargo-fuzz needs nightly): a fixed number of mutants per seed file,
//! enough to reach past the parsers into validation, accessors, images and cameras.

use furnace_scene::{EnvironmentMap, Scene};
use furnace_tests::Rng;
use std::panic::{AssertUnwindSafe, catch_unwind};
use std::path::PathBuf;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

/// The seed of every mutant.
const SEED: u64 = 0x5cee_f022;

/// Mutants per seed file: with the 24 files of [`seeds`], 4.8·10⁵ loads; every mutation kind
/// hits every seed thousands of times.
const MUTANTS_PER_FILE: usize = 20_000;

/// Mutants per file of the corpora ([`corpus_seeds`], about 250 files): 10⁵ loads more. With
/// the others, a few seconds in the test profile on 2 cores.
const MUTANTS_PER_CORPUS_FILE: usize = 400;

/// The longest one load may take. The slowest seed (a GLB with a 256² PNG texture) loads in
/// milliseconds in the debug profile; a mutant taking 10 s is a hang, not a slow machine.
const MAX_LOAD: Duration = Duration::from_secs(10);

/// How many panicking mutants are listed and written out.
const MAX_REPORTED: usize = 20;

/// What a seed file is loaded as.
#[derive(Clone, Copy, PartialEq, Debug)]
enum Kind {
    /// glTF JSON, through `Scene::from_slice`.
    Json,
    /// GLB, through `Scene::from_slice`.
    Glb,
    /// An environment map, through `EnvironmentMap::from_bytes`.
    Environment,
}

/// The seed files: name, kind, bytes and how many mutants of each.
fn seeds() -> Vec<(String, Kind, Vec<u8>, usize)> {
    let scene = |p: &str| furnace_tests::data::scene(p);
    let hostile = |p: &str| furnace_tests::data::data_dir().join("hostile/scene").join(p);
    let mut files: Vec<(PathBuf, Kind)> = vec![
        (scene("Box/glTF-Embedded/Box.gltf"), Kind::Json),
        (scene("Box/glTF-Binary/Box.glb"), Kind::Glb),
        (scene("BoxTextured/glTF-Binary/BoxTextured.glb"), Kind::Glb),
        (scene("gltf-transform/BoxMeshopt.glb"), Kind::Glb),
        (scene("Cameras/glTF-Embedded/Cameras.gltf"), Kind::Json),
        (hostile("tiny_4x2.hdr"), Kind::Environment),
        (hostile("tiny_4x2.exr"), Kind::Environment),
        (hostile("huge_header.hdr"), Kind::Environment),
        (hostile("huge_windows.exr"), Kind::Environment),
    ];
    let mut hostile_files: Vec<PathBuf> = std::fs::read_dir(hostile(""))
        .expect("tests/data/hostile/scene")
        .map(|e| e.expect("a directory entry").path())
        .filter(|p| p.extension().is_some_and(|x| x == "gltf"))
        .collect();
    hostile_files.sort();
    files.extend(hostile_files.into_iter().map(|p| (p, Kind::Json)));
    files
        .into_iter()
        .map(|(p, k)| {
            let bytes = std::fs::read(&p).unwrap_or_else(|e| panic!("{}: {e}", p.display()));
            (p.file_name().unwrap().to_string_lossy().into_owned(), k, bytes, MUTANTS_PER_FILE)
        })
        .chain(corpus_seeds())
        .collect()
}

/// The small files (under 6 KiB) of the glTF-Validator and edge-case corpora
/// (`tests/data/scenes/`): every part of the format in a few hundred files, fewer mutants each.
fn corpus_seeds() -> Vec<(String, Kind, Vec<u8>, usize)> {
    let mut found = Vec::new();
    let mut stack = vec![
        furnace_tests::data::scene("gltf-validator-tests"),
        furnace_tests::data::scene("atteneder-edge-cases"),
    ];
    while let Some(dir) = stack.pop() {
        for entry in std::fs::read_dir(&dir).unwrap_or_else(|e| panic!("{}: {e}", dir.display())) {
            let path = entry.expect("a directory entry").path();
            let kind = match path.extension().and_then(|x| x.to_str()) {
                _ if path.is_dir() => {
                    stack.push(path);
                    continue;
                }
                Some("gltf") => Kind::Json,
                Some("glb") => Kind::Glb,
                _ => continue,
            };
            let bytes = std::fs::read(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
            if bytes.len() < 6 << 10 {
                let name = path.strip_prefix(furnace_tests::data::scene("")).unwrap_or(&path);
                found.push((
                    name.display().to_string().replace('/', "_"),
                    kind,
                    bytes,
                    MUTANTS_PER_CORPUS_FILE,
                ));
            }
        }
    }
    found.sort_by(|a, b| a.0.cmp(&b.0));
    found
}

/// Loads `bytes` as `kind`; the result does not matter, only that it returns.
fn load(kind: Kind, bytes: &[u8]) {
    match kind {
        Kind::Json | Kind::Glb => {
            let _ = Scene::from_slice(bytes, "mutant");
        }
        Kind::Environment => {
            let _ = EnvironmentMap::from_bytes(bytes, "mutant");
        }
    }
}

/// Replacement values for a JSON number: zero and the extremes of each type the glTF schema
/// reads (u32, usize, f32), past them, and values of other JSON types.
const JSON_VALUES: &[&str] = &[
    "0",
    "-1",
    "1",
    "3",
    "0.5",
    "1e38",
    "-1e38",
    "1e39",
    "1e-45",
    "4294967295",
    "4294967296",
    "2147483648",
    "18446744073709551615",
    "18446744073709551616",
    "99999999999999999999999999",
    "\"NaN\"",
    "\"\"",
    "null",
    "true",
    "[]",
    "{}",
    "[0, 0, 0]",
];

/// The spans of `json` (byte ranges) that are numbers, strings, and keys with their value.
#[derive(Default)]
struct Spans {
    numbers: Vec<(usize, usize)>,
    strings: Vec<(usize, usize)>,
    /// From a key's opening quote to the end of its value, with the comma after it if any.
    members: Vec<(usize, usize)>,
}

/// Where the numbers, strings and object members of `json` are (a scan that tracks strings and
/// nesting; on malformed JSON it finds what it can).
fn scan(json: &[u8]) -> Spans {
    let mut spans = Spans::default();
    let mut i = 0;
    // Open keys per nesting level: (key start, depth).
    let mut open_key: Vec<(usize, usize)> = Vec::new();
    let mut depth = 0usize;
    let close_member = |spans: &mut Spans, open_key: &mut Vec<(usize, usize)>, depth: usize, end: usize| {
        if let Some(&(start, d)) = open_key.last()
            && d == depth
        {
            open_key.pop();
            spans.members.push((start, end));
        }
    };
    while i < json.len() {
        match json[i] {
            b'"' => {
                let start = i;
                i += 1;
                while i < json.len() && json[i] != b'"' {
                    i += if json[i] == b'\\' { 2 } else { 1 };
                }
                let end = (i + 1).min(json.len());
                let mut k = end;
                while k < json.len() && json[k].is_ascii_whitespace() {
                    k += 1;
                }
                if json.get(k) == Some(&b':') {
                    open_key.push((start, depth));
                } else {
                    spans.strings.push((start, end));
                }
                i = end;
                continue;
            }
            b'-' | b'0'..=b'9' => {
                let start = i;
                while i < json.len() && matches!(json[i], b'-' | b'+' | b'.' | b'e' | b'E' | b'0'..=b'9') {
                    i += 1;
                }
                spans.numbers.push((start, i));
                continue;
            }
            b'{' | b'[' => depth += 1,
            b'}' | b']' => {
                close_member(&mut spans, &mut open_key, depth, i);
                depth = depth.saturating_sub(1);
            }
            b',' => close_member(&mut spans, &mut open_key, depth, i + 1),
            _ => {}
        }
        i += 1;
    }
    spans
}

fn pick<T: Copy>(rng: &mut Rng, v: &[T]) -> Option<T> {
    (!v.is_empty()).then(|| v[(rng.next_u64() % v.len() as u64) as usize])
}

fn below(rng: &mut Rng, n: usize) -> usize {
    (rng.next_u64() % n.max(1) as u64) as usize
}

/// One JSON-aware mutation: a number replaced by an extreme or by another type, a string
/// replaced by another type or by another string of the file, a member deleted; a byte-level
/// one when the JSON has nothing of the kind chosen.
fn mutate_json(rng: &mut Rng, json: &mut Vec<u8>) {
    let spans = scan(json);
    let (span, with): (Option<(usize, usize)>, &str) = match below(rng, 5) {
        0 | 1 => (pick(rng, &spans.numbers), pick(rng, JSON_VALUES).unwrap_or("0")),
        2 => (
            pick(rng, &spans.strings),
            pick(rng, &["0", "-1", "\"\"", "\"/dev/zero\"", "\"data:,\"", "{}", "null"]).unwrap_or("0"),
        ),
        3 => {
            // Another string of the same file: an enum's value swapped for another
            // ("perspective" for "orthographic", "SCALAR" for "VEC3"), a URI for a name.
            let other =
                pick(rng, &spans.strings).map(|(a, b)| String::from_utf8_lossy(&json[a..b]).into_owned());
            if let (Some(span), Some(other)) = (pick(rng, &spans.strings), other) {
                json.splice(span.0..span.1, other.into_bytes());
                return;
            }
            (None, "")
        }
        _ => (pick(rng, &spans.members), ""),
    };
    match span {
        Some((a, b)) => {
            json.splice(a..b, with.bytes());
        }
        None => mutate_bytes(rng, json),
    }
}

/// One byte-level mutation.
fn mutate_bytes(rng: &mut Rng, b: &mut Vec<u8>) {
    if b.is_empty() {
        b.push(rng.u32() as u8);
        return;
    }
    match below(rng, 6) {
        0 => {
            for _ in 0..1 + below(rng, 8) {
                let i = below(rng, b.len() * 8);
                b[i / 8] ^= 1 << (i % 8);
            }
        }
        1 => {
            for _ in 0..1 + below(rng, 4) {
                let i = below(rng, b.len());
                b[i] = pick(rng, &[0u8, 0xFF, 0x7F, 0x80]).unwrap_or(0);
            }
        }
        2 => {
            let i = below(rng, b.len());
            b[i] = rng.u32() as u8;
        }
        3 => b.truncate(below(rng, b.len())),
        4 => {
            let a = below(rng, b.len());
            let len = 1 + below(rng, (b.len() - a).min(64));
            let at = below(rng, b.len());
            let span: Vec<u8> = b[a..a + len].to_vec();
            b.splice(at..at, span);
        }
        _ => {
            let a = below(rng, b.len());
            let len = 1 + below(rng, (b.len() - a).min(64));
            b.drain(a..a + len);
        }
    }
}

/// A GLB's JSON chunk (if the header and chunk are intact): its range in `glb`.
fn glb_json(glb: &[u8]) -> Option<(usize, usize)> {
    let len = u32::from_le_bytes(glb.get(12..16)?.try_into().ok()?) as usize;
    (glb.get(16..20)? == b"JSON" && 20 + len <= glb.len()).then_some((20, 20 + len))
}

/// `glb` with its JSON chunk replaced by `json` (padded with spaces to 4 bytes) and the
/// container's and the chunk's lengths rewritten to match.
fn glb_with_json(glb: &[u8], json_end: usize, json: &[u8]) -> Vec<u8> {
    let mut json = json.to_vec();
    while !json.len().is_multiple_of(4) {
        json.push(b' ');
    }
    let mut out = glb[..12].to_vec();
    out.extend((json.len() as u32).to_le_bytes());
    out.extend(b"JSON");
    out.extend(&json);
    out.extend(&glb[json_end..]);
    let total = out.len() as u32;
    out[8..12].copy_from_slice(&total.to_le_bytes());
    out
}

/// Mutant `index` of `seed` (the bytes of `file`, of kind `kind`): one to three mutations, JSON-aware ones
/// with probability ½ on glTF JSON and GLB.
fn mutant(file: &str, seed: &[u8], kind: Kind, index: usize) -> Vec<u8> {
    // FNV-1a of the file's name: each file its own sequence of mutants.
    let name_hash =
        file.bytes().fold(0xcbf2_9ce4_8422_2325u64, |h, b| (h ^ u64::from(b)).wrapping_mul(0x100_0000_01b3));
    let mut rng = Rng(SEED ^ name_hash ^ (index as u64).wrapping_mul(0x9e37_79b9_7f4a_7c15));
    let mut b = seed.to_vec();
    for _ in 0..1 + below(&mut rng, 3) {
        let json_aware = kind != Kind::Environment && rng.next_u64() & 1 == 0;
        match (json_aware, kind) {
            (true, Kind::Json) => mutate_json(&mut rng, &mut b),
            (true, Kind::Glb) => {
                if let Some(span) = glb_json(&b) {
                    let mut json = b[span.0..span.1].to_vec();
                    mutate_json(&mut rng, &mut json);
                    b = glb_with_json(&b, span.1, &json);
                } else {
                    mutate_bytes(&mut rng, &mut b);
                }
            }
            _ => mutate_bytes(&mut rng, &mut b),
        }
    }
    b
}

/// The mutant being loaded, for the watchdog: its name, its bytes and when its load began.
type Loading = (String, Vec<u8>, Instant);

/// Every mutant of every seed file loads or fails without a panic, each within [`MAX_LOAD`].
/// A watchdog thread fails the test when a load runs past the limit (a hang never returns to
/// the loop). Crashing and hanging inputs are written to `target/test-output/scene/fuzz/`.
#[test]
fn mutants_load_or_fail_cleanly() {
    let dir = furnace_tests::data::output_dir("scene/fuzz");
    let seeds = seeds();
    // The mutant being loaded and when it started, for the watchdog.
    let current: Arc<Mutex<Option<Loading>>> = Arc::new(Mutex::new(None));
    let done = Arc::new(AtomicBool::new(false));
    let watchdog = {
        let (current, done, dir) = (Arc::clone(&current), Arc::clone(&done), dir.clone());
        std::thread::spawn(move || {
            while !done.load(Ordering::Relaxed) {
                std::thread::sleep(Duration::from_millis(200));
                let guard = current.lock().unwrap_or_else(|e| e.into_inner());
                if let Some((name, bytes, start)) = guard.as_ref()
                    && start.elapsed() > MAX_LOAD
                {
                    let path = dir.join(name);
                    let _ = std::fs::write(&path, bytes);
                    eprintln!("{name}: still loading after {MAX_LOAD:?}; written to {}", path.display());
                    std::process::exit(1);
                }
            }
        })
    };

    let start = Instant::now();
    let mut executions = 0usize;
    let mut failures = Vec::new();
    let mut panics = 0usize;
    let mut slowest = (Duration::ZERO, String::new(), Vec::new());
    for (file, kind, seed, mutants) in &seeds {
        for i in 0..*mutants {
            let bytes = mutant(file, seed, *kind, i);
            let name = format!("{file}.mutant-{i}");
            *current.lock().unwrap_or_else(|e| e.into_inner()) =
                Some((name.clone(), bytes.clone(), Instant::now()));
            let t = Instant::now();
            let result = catch_unwind(AssertUnwindSafe(|| load(*kind, &bytes)));
            let took = t.elapsed();
            executions += 1;
            if took > slowest.0 {
                slowest = (took, name.clone(), bytes.clone());
            }
            if let Err(panic) = result {
                let message = panic
                    .downcast_ref::<String>()
                    .cloned()
                    .or_else(|| panic.downcast_ref::<&str>().map(|s| (*s).to_string()))
                    .unwrap_or_default();
                // The first inputs are enough to reproduce; one bug can make thousands.
                if failures.len() < MAX_REPORTED {
                    let path = dir.join(&name);
                    std::fs::write(&path, &bytes).unwrap();
                    failures.push(format!("{name} ({}): panicked: {message}", path.display()));
                }
                panics += 1;
            }
        }
    }
    done.store(true, Ordering::Relaxed);
    *current.lock().unwrap_or_else(|e| e.into_inner()) = None;
    watchdog.join().unwrap();
    let elapsed = start.elapsed();
    // The slowest input, for a human to look at.
    std::fs::write(dir.join("slowest"), &slowest.2).unwrap();
    println!(
        "fuzz: {executions} executions over {} seed files in {elapsed:.2?} ({:.0}/s); slowest {:.2?} ({})",
        seeds.len(),
        executions as f64 / elapsed.as_secs_f64(),
        slowest.0,
        slowest.1
    );
    assert!(
        panics == 0,
        "{panics} of {executions} mutants panicked; the first {}:\n{}",
        failures.len(),
        failures.join("\n")
    );
}

/// The mutators change their input and the JSON scan finds what it should: a fuzzer whose
/// mutants were all the seed would pass while testing nothing.
#[test]
fn mutants_differ_from_their_seed() {
    let spans = scan(br#"{"a": 1, "b": {"c": "x", "d": [2, -3.5e4]}, "e": "y"}"#);
    assert_eq!(spans.numbers.len(), 3);
    assert_eq!(spans.strings.len(), 2);
    assert_eq!(spans.members.len(), 5);
    for (file, kind, seed, _) in seeds() {
        if seed.len() < 16 {
            // An empty or near-empty file: a byte added and truncated away again is the seed.
            continue;
        }
        let changed = (0..100).filter(|&i| mutant(&file, &seed, kind, i) != seed).count();
        // A JSON mutation can miss (no member to delete, a number replaced by itself, a span
        // duplicated onto its own copy): about one mutant in ten of the tiniest files.
        assert!(changed >= 80, "{file}: only {changed} of 100 mutants differ from the seed");
    }
}
