//! Every `.gltf`/`.glb` of the Khronos glTF-Validator test corpus and of atteneder's edge cases
//! (the workspace's `tests/data/scenes/`, with their licences): none may panic; files the validator finds valid
//! (`X.report.json`: `issues.numErrors == 0`) must load, or fail only with an error that states
//! why furnace cannot render them (no triangles at all, or a required extension furnace does
//! not implement); invalid ones must return an error or load with warnings.

use furnace_scene::{Scene, SceneError};
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

fn collect(dir: &Path, out: &mut Vec<PathBuf>) {
    let Ok(entries) = std::fs::read_dir(dir) else {
        return;
    };
    for e in entries.flatten() {
        let p = e.path();
        if p.is_dir() {
            collect(&p, out);
        } else if matches!(p.extension().and_then(|e| e.to_str()), Some("gltf" | "glb")) {
            out.push(p);
        }
    }
}

/// Valid files that the `gltf` 1.4 parser itself rejects (its serde model is stricter than the
/// specification); furnace reports them as parse/validation errors naming the place. Each needs
/// a fix upstream or a parser of our own.
const KNOWN_PARSER_LIMITS: &[(&str, &str)] = &[
    ("base/data/accessor/unknown_type.gltf", "unknown enum values are rejected, not ignored"),
    ("ext/KHR_lights_punctual/data/light/unknown_type.gltf", "unknown light type rejected"),
    ("base/data/glb/extra_data.glb", "GLB with bytes after the declared length"),
    ("base/data/json/integer_written_as_float.gltf", "`1.0` where an integer is expected"),
    ("base/data/root/named_objects.gltf", "animation channel target without `node`"),
    ("base/data/root/unused_objects.gltf", "animation channel target without `node`"),
    ("channel/target/custom_property.gltf", "KHR_animation_pointer: target without `node`"),
    ("channel/target/missing_extension_declaration.gltf", "target without `node`"),
    ("KHR_animation_pointer/data/animation/channel/target/valid.gltf", "target without `node`"),
];

/// `Some(numErrors)` from `X.gltf.report.json`, `None` without a report.
fn validator_errors(p: &Path) -> Option<u64> {
    let mut report = p.as_os_str().to_owned();
    report.push(".report.json");
    let text = std::fs::read_to_string(report).ok()?;
    let v: gltf::json::Value = gltf::json::deserialize::from_str(&text).ok()?;
    v.get("issues")?.get("numErrors")?.as_u64()
}

/// Whether an error on a validator-valid file is acceptable: the file is valid but furnace
/// cannot render it for a stated reason.
fn acceptable_on_valid(e: &SceneError) -> bool {
    matches!(e, SceneError::NothingToRender { .. } | SceneError::UnsupportedExtension { .. })
}

#[test]
fn corpus_never_panics_and_valid_files_load() {
    let data = furnace_tests::data::scene("");
    let mut files = Vec::new();
    collect(&data.join("gltf-validator-tests"), &mut files);
    collect(&data.join("atteneder-edge-cases"), &mut files);
    files.sort();
    assert!(files.len() > 200, "corpus missing: {} files", files.len());

    // Silence the default hook's backtraces for the duration; panics are reported below.
    let hook = std::panic::take_hook();
    std::panic::set_hook(Box::new(|_| {}));
    let mut panicked = Vec::new();
    let mut bad = Vec::new();
    // (category, outcome) → count.
    let mut table: BTreeMap<(&str, String), usize> = BTreeMap::new();
    let (mut with_warnings, mut warnings_total) = (0, 0);
    for f in &files {
        let verdict = validator_errors(f);
        let category = match verdict {
            Some(0) => "valid",
            Some(_) => "invalid",
            None => "no report",
        };
        let result = std::panic::catch_unwind(|| Scene::load(f));
        let rel = f.strip_prefix(&data).unwrap_or(f).display().to_string();
        let outcome = match result {
            Err(_) => {
                panicked.push(rel.clone());
                "PANIC".to_string()
            }
            Ok(Ok(scene)) => {
                if !scene.warnings.is_empty() {
                    with_warnings += 1;
                    warnings_total += scene.warnings.len();
                }
                "loaded".to_string()
            }
            Ok(Err(e)) => {
                let known = KNOWN_PARSER_LIMITS.iter().any(|(k, _)| rel.ends_with(k));
                if verdict == Some(0) && !acceptable_on_valid(&e) && !known {
                    bad.push(format!("{rel}: {e}"));
                }
                // Every error names the file.
                assert!(e.to_string().contains(&f.display().to_string()), "{e}");
                format!("error: {}", e.kind())
            }
        };
        *table.entry((category, outcome)).or_default() += 1;
    }
    std::panic::set_hook(hook);

    println!("\n| validator verdict | outcome | files |\n|---|---|---|");
    for ((c, o), n) in &table {
        println!("| {c} | {o} | {n} |");
    }
    println!(
        "\n{} files; {with_warnings} loaded with warnings ({warnings_total} warnings); {} panics",
        files.len(),
        panicked.len()
    );
    for p in &panicked {
        println!("PANIC: {p}");
    }
    for b in &bad {
        println!("VALID BUT FAILED: {b}");
    }
    assert!(panicked.is_empty(), "{} files panicked (listed above)", panicked.len());
    assert!(bad.is_empty(), "{} valid files failed (listed above)", bad.len());
}
