//! What a furnace EXR records about its render, and resuming from it.
//!
//! Every EXR `furnace render` writes carries (besides R, G, B) the film's exact state — the
//! `f64` sums and the counts of every pixel, in the `furnace.resume.*` channels
//! (`furnace_post::write_exr_with_state`) — and, as `furnace.*` text attributes, every setting
//! that decides the film: scene identity (name and a hash of its loaded content), camera, the
//! environment options given (`--env`, `--env-intensity`, `--env-rotation`, `--env-visible`),
//! and the render settings as their one description records them (`furnace_render::fields`:
//! bounces, sampler, seed, material model, light sampling, clamp, adaptive sampling; the size
//! and, for the fixed-N samplers, N are in `furnace_render::resume::identity`). The scene hash covers the environment itself (its texels, intensity,
//! rotation and visibility), so the same options rebuild the same scene, the default light
//! included (its decision is recorded, [`DEFAULT_LIGHT`], and followed on resume).
//! `--resume` restores the film from the sums and continues at sample index `furnace.spp`: each
//! pixel's sum keeps adding samples in index order, so the result is bit-identical to an
//! uninterrupted render on the same backend and adapter (on a GPU without `f64` shaders, whose
//! film sums each pass in `f32`, only where the pass boundaries agree, as after Ctrl-C or
//! `--time-limit`).
//!
//! The backend is recorded (`furnace.backend`, `furnace_render::resume::backend_record`) but does not decide the
//! film: a render started on the CPU may be continued on a GPU, or the reverse. Both integrators
//! trace the same sample indices, so the continuation adds exactly the missing samples, computed
//! by the other backend: an unbiased estimate of the same image, equal to an uninterrupted
//! render to the float rounding of each path, not bit for bit (`tests/gpu.rs` checks it). The
//! record keeps every backend that added samples, and `--resume` says when it changes.

use crate::args::{EnvArgs, LookAt, RenderArgs};
use clap::ValueEnum;
use furnace_post::{Metadata, printable_excerpt};
use furnace_render::resume::{self, Attributes, Identity, LayoutUse, RecordError};
use furnace_render::{MAX_BOUNCES, SampleRange};
use std::path::{Path, PathBuf};

pub use furnace_render::resume::TARGET_SPP;

/// The name `furnace_scene::builtin::cornell_box` gives its scene (the scene of `furnace
/// render` without a file).
pub const BUILTIN_CBOX: &str = "<built-in cbox>";

/// Hex hash of the scene's loaded content (`Scene::content_hash`).
pub const SCENE_HASH: &str = "furnace.scene_hash";
/// The sampler-dimension layout version the paths were traced with
/// (`furnace_render::SAMPLER_LAYOUT_VERSION`; absent in files of layout 1 written before it was
/// recorded).
pub const SAMPLER_LAYOUT: &str = "furnace.sampler_layout";
/// The camera: `--camera`'s index (`0` by default), [`FRAMED`] for a scene without cameras, or
/// for `--look-at` its [`look_at_record`].
pub const CAMERA: &str = "furnace.camera";
/// The `--sun-angle` given (absent: the scene's own).
pub const SUN_ANGLE: &str = "furnace.sun_angle_deg";
/// The `--env` given, as given: the map's path, `studio` or `none` (absent: the scene's own, or
/// the default studio for a scene without a light of its own).
pub const ENV: &str = "furnace.env";
/// The `--env-intensity` given (absent: the scene's own, else 1).
pub const ENV_INTENSITY: &str = "furnace.env_intensity";
/// The `--env-rotation` given, in degrees (absent: the scene's own, else 0).
pub const ENV_ROTATION: &str = "furnace.env_rotation_deg";
/// The `--env-visible` given, `on` or `off` (absent: the scene's own, else on).
pub const ENV_VISIBLE: &str = "furnace.env_visible";
/// The default light's decision, `studio` or `none`, where it decided (no `--env` given and no
/// environment of the scene's own; `crate::default_light`). `--resume` follows it rather than
/// measuring again (absent in a file from before the rule: that rule, the studio only for a
/// scene without a light of its own).
pub const DEFAULT_LIGHT: &str = "furnace.default_light";
/// The `--variant` given (absent: each primitive's own material). It decides the scene's
/// content, so a resumed render needs the same.
pub const VARIANT: &str = "furnace.variant";
/// A part of a split render: the `--samples A..B` it renders (absent: the whole render,
/// `0..furnace.target_spp`). Its film holds samples `A..A+furnace.spp`.
pub const SAMPLE_RANGE: &str = "furnace.sample_range";
/// The sample indices a merge with gaps holds, `A..B,C..D` (`furnace_render::split::format_ranges`;
/// absent: those that [`SAMPLE_RANGE`] and `furnace.spp` say). Such a file is not resumable.
pub const SAMPLES: &str = "furnace.samples";
/// `--tonemap` (PNG only; free to change on resume).
pub const TONEMAP: &str = "furnace.tonemap";
/// `--exposure` (PNG only; free to change on resume).
pub const EXPOSURE: &str = "furnace.exposure_ev";

/// Every backend that added samples, in order, separated by
/// `furnace_render::resume::BACKEND_SEPARATOR`: `cpu: ` and the target (`x86_64-linux`), or
/// `gpu: ` and the adapter (name, type, API, driver). Provenance only: not part of the identity.
pub const BACKEND: &str = "furnace.backend";

/// The `--camera` value recorded for a scene without cameras.
pub const FRAMED: &str = "framed";

/// How a [`look_at_record`] starts.
pub const LOOK_AT: &str = "look-at:";

/// The [`CAMERA`] record of a `--look-at` camera with a vertical field of view of `yfov_deg`
/// degrees: `look-at:EX,EY,EZ,TX,TY,TZ,UX,UY,UZ;yfov:DEG`, every number in the shortest form
/// that parses back to the same `f32`, so that a resumed render rebuilds the same camera bit for
/// bit (and the identity check, which compares records, accepts it).
pub fn look_at_record(look: &LookAt, yfov_deg: f32) -> String {
    format!("{LOOK_AT}{look};yfov:{yfov_deg}")
}

/// The pose and the field of view (degrees) of a [`look_at_record`]; `None` if `record` is not
/// one, or not a valid one.
pub fn parse_look_at_record(record: &str) -> Option<(LookAt, f32)> {
    let (look, yfov) = record.strip_prefix(LOOK_AT)?.split_once(";yfov:")?;
    Some((look.parse().ok()?, crate::args::parse_yfov(yfov).ok()?))
}

/// The options that give the camera of a [`CAMERA`] record: `--look-at … --yfov …`, or
/// `--camera INDEX` (for messages).
pub fn camera_options(record: &str) -> String {
    match parse_look_at_record(record) {
        Some((look, yfov)) => format!("--look-at {look} --yfov {yfov}"),
        None => format!("--camera {record}"),
    }
}

/// A clap value's command-line spelling (`height-correlated`).
pub fn cli_name(v: &impl ValueEnum) -> String {
    v.to_possible_value().map(|p| p.get_name().to_string()).unwrap_or_default()
}

/// The EXR attribute of the render setting of flag `flag` (`furnace_render::fields`).
pub fn key(flag: &str) -> &'static str {
    furnace_render::fields::field(flag)
        .map_or_else(|| unreachable!("the settings have a field {flag}"), |f| f.key)
}

/// Whether `key` is one of the settings' attributes that [`Metadata`] keeps in a field of its own.
fn typed(key: &str) -> bool {
    ["bounces", "sampler", "seed"].iter().any(|&flag| self::key(flag) == key)
}

/// Every text attribute of `meta` by name, its own fields' included.
pub fn attributes(meta: &Metadata) -> Attributes {
    let mut attributes = meta.extra.clone();
    let own = [
        ("bounces", meta.bounces.map(|b| b.to_string())),
        ("sampler", meta.sampler.clone()),
        ("seed", meta.seed.map(|s| s.to_string())),
    ];
    for (flag, value) in own {
        if let Some(v) = value {
            attributes.insert(key(flag).to_string(), v);
        }
    }
    attributes
}

/// `meta` with the record of `settings` (`furnace_render::fields::record`) added.
pub fn with_settings(mut meta: Metadata, settings: &furnace_render::RenderSettings) -> Metadata {
    meta.sampler = Some(settings.sampler.to_string());
    meta.bounces = Some(settings.bounces);
    meta.seed = Some(u64::from(settings.seed));
    let record = furnace_render::fields::record(settings).into_iter().filter(|(k, _)| !typed(k));
    meta.extra.extend(record.map(|(k, v)| (k.to_string(), v)));
    meta
}

/// The settings that decide the film, as `(setting, value)` pairs read from `meta` and the
/// image size: two renders continue each other exactly when their lists are equal. A value the
/// file lacks is `None`. The scene's part (its name, content, camera and options) is here; the
/// settings' part is `furnace_render::resume::identity`'s.
pub fn identity(meta: &Metadata, width: u32, height: u32) -> Identity {
    let extra = |k: &str| meta.extra.get(k).cloned();
    let scene_name = meta.scene.as_deref().map(|s| {
        // The file name only: the same file given by another relative path is the same scene
        // (the hash checks the content).
        Path::new(s).file_name().map_or_else(|| s.to_string(), |n| n.to_string_lossy().into_owned())
    });
    let scene = vec![
        ("scene", scene_name),
        ("scene content hash", extra(SCENE_HASH)),
        ("camera", extra(CAMERA)),
        ("sun angle", extra(SUN_ANGLE)),
        ("environment", extra(ENV)),
        ("environment intensity", extra(ENV_INTENSITY)),
        ("environment rotation (degrees)", extra(ENV_ROTATION)),
        ("environment visible", extra(ENV_VISIBLE)),
    ];
    resume::identity(scene, &attributes(meta), width, height)
}

/// The error of a file whose `furnace.bounces` is more than furnace renders (`None` if it is not).
pub fn modified_bounces(file: &Path, meta: &Metadata) -> Option<String> {
    meta.bounces.filter(|&b| b > MAX_BOUNCES).map(|b| {
        format!(
            "{}: attribute 'furnace.bounces' = {b} is more than furnace renders (at most {MAX_BOUNCES}); it \
             was modified",
            file.display()
        )
    })
}

/// The EXR records of the environment options given (none for those not given).
pub fn env_records(e: &EnvArgs) -> impl Iterator<Item = (&'static str, String)> + use<> {
    [
        e.env.as_ref().map(|v| (ENV, v.to_string())),
        e.env_intensity.map(|x| (ENV_INTENSITY, x.to_string())),
        e.env_rotation.map(|d| (ENV_ROTATION, d.to_string())),
        e.env_visible.map(|v| (ENV_VISIBLE, cli_name(&v))),
    ]
    .into_iter()
    .flatten()
}

/// `Err` naming `file` and, for each setting that differs between its record and this
/// render's, both values; or, if the file's paths used another sampler-dimension layout, why it
/// cannot be continued.
pub fn check_same(
    file: &Path,
    meta: &Metadata,
    recorded: &[(&'static str, Option<String>)],
    now: &[(&'static str, Option<String>)],
    uses: LayoutUse,
) -> Result<(), String> {
    resume::check_layout(meta.extra.get(SAMPLER_LAYOUT).map(String::as_str), uses)
        .and_then(|()| resume::check_same(recorded, now))
        .map_err(|e| format!("{}: {e}", file.display()))
}

/// A refused resume's `message` with what the file says of `--variant`, where the scene's content
/// differs (a variant changes it): the variant it records if another is given now (`now`), or,
/// for a file without the record of a scene that has variants (`has_variants`), that it may
/// have been rendered with one from before furnace recorded it.
pub fn variant_hint(message: String, meta: &Metadata, now: Option<&str>, has_variants: bool) -> String {
    if !message.contains("scene content hash") {
        return message;
    }
    match (meta.extra.get(VARIANT), now) {
        (Some(file), Some(now)) if file != now => {
            let (file, now) = (printable_excerpt(file), printable_excerpt(now));
            format!("{message}; it was rendered with --variant {file}, not --variant {now}")
        }
        (None, Some(now)) => format!(
            "{message}; the file records no --variant (rendered without one, or by a furnace that did not \
             record it): try without --variant {}",
            printable_excerpt(now)
        ),
        (None, None) if has_variants => format!(
            "{message}; the file records no --variant (it was written by a furnace that did not record \
             it): if it was rendered with one, give the same --variant"
        ),
        _ => message,
    }
}

/// Fills every film-deciding argument that was not given on the command line from the file's
/// record (`given` ones stay, to be checked by [`check_same`]); `--out` defaults to the file
/// itself, `--spp` to the recorded target.
pub fn apply_recorded(
    a: &mut RenderArgs,
    file: &Path,
    meta: &Metadata,
    width: u32,
    height: u32,
) -> Result<(), String> {
    let missing =
        |key: &str| format!("{}: no '{key}' attribute; this file's render cannot be resumed", file.display());
    let invalid = |key: &str, v: &str| {
        format!("{}: attribute '{key}' = {} is not a valid value", file.display(), printable_excerpt(v))
    };
    let extra = |key: &'static str| meta.extra.get(key).map(String::as_str).ok_or_else(|| missing(key));
    if !a.given("scene") {
        let name = meta.scene.as_deref().ok_or_else(|| missing("furnace.scene"))?;
        a.scene = (name != BUILTIN_CBOX).then(|| PathBuf::from(name));
    }
    if !a.given("width") {
        a.width = Some(width);
    }
    if !a.given("height") {
        a.height = Some(height);
    }
    if !a.given("bounces")
        && let Some(e) = modified_bounces(file, meta)
    {
        return Err(e);
    }
    let given = a.given.clone();
    resume::restore(&mut a.settings.settings, &attributes(meta), |flag| given.contains(flag)).map_err(
        |e| match e {
            RecordError::Invalid { key, value } => invalid(key, &value),
            e => format!("{}: {e}", file.display()),
        },
    )?;
    if !a.given("camera") && !a.given("look_at") {
        let v = extra(CAMERA)?;
        (a.camera, a.look_at, a.yfov) = match v {
            FRAMED => (None, None, None),
            _ if v.starts_with(LOOK_AT) => {
                let (look, yfov) = parse_look_at_record(v).ok_or_else(|| invalid(CAMERA, v))?;
                (None, Some(look), Some(yfov))
            }
            _ => (Some(v.parse().map_err(|_| invalid(CAMERA, v))?), None, None),
        };
    } else if a.given("look_at")
        && !a.given("yfov")
        && let Some((_, yfov)) = meta.extra.get(CAMERA).and_then(|v| parse_look_at_record(v))
    {
        // The same pose given again: the field of view is the file's unless given.
        a.yfov = Some(yfov);
    }
    if !a.given("variant")
        && let Some(v) = meta.extra.get(VARIANT)
    {
        a.load.variant = Some(v.clone());
    }
    if let Some(v) = meta.extra.get(DEFAULT_LIGHT)
        && v != "studio"
        && v != "none"
    {
        return Err(invalid(DEFAULT_LIGHT, v));
    }
    if !a.given("sun_angle")
        && let Some(v) = meta.extra.get(SUN_ANGLE)
    {
        a.sun_angle = Some(v.parse().map_err(|_| invalid(SUN_ANGLE, v))?);
    }
    let e = &mut a.environment;
    if !a.given.contains("env")
        && let Some(v) = meta.extra.get(ENV)
    {
        e.env = Some(crate::args::parse_env(v).map_err(|_| invalid(ENV, v))?);
    }
    if !a.given.contains("env_intensity")
        && let Some(v) = meta.extra.get(ENV_INTENSITY)
    {
        e.env_intensity = Some(
            v.parse()
                .ok()
                .filter(|x: &f32| x.is_finite() && *x >= 0.0)
                .ok_or_else(|| invalid(ENV_INTENSITY, v))?,
        );
    }
    if !a.given.contains("env_rotation")
        && let Some(v) = meta.extra.get(ENV_ROTATION)
    {
        e.env_rotation =
            Some(v.parse().ok().filter(|x: &f32| x.is_finite()).ok_or_else(|| invalid(ENV_ROTATION, v))?);
    }
    if !a.given.contains("env_visible")
        && let Some(v) = meta.extra.get(ENV_VISIBLE)
    {
        e.env_visible = Some(crate::args::Switch::from_str(v, false).map_err(|_| invalid(ENV_VISIBLE, v))?);
    }
    if let Some(v) = meta.extra.get(SAMPLES) {
        return Err(format!(
            "{}: a merge of parts with samples missing (it holds samples {}): it cannot be continued; \
             render the missing ranges with --samples and merge them with it",
            file.display(),
            // Shown as parsed (what it says, not the file's bytes).
            furnace_render::split::parse_ranges(v)
                .map_or_else(|_| printable_excerpt(v), |r| furnace_render::split::format_ranges(&r))
        ));
    }
    if let Some(v) = meta.extra.get(SAMPLE_RANGE) {
        let recorded: SampleRange = v.parse().map_err(|_| invalid(SAMPLE_RANGE, v))?;
        match a.samples {
            Some(given) if given != recorded => {
                return Err(format!(
                    "{}: it renders samples {recorded} of a split render, not --samples {given}",
                    file.display()
                ));
            }
            _ => a.samples = Some(recorded),
        }
    } else if let Some(given) = a.samples {
        return Err(format!(
            "{}: a whole render, not a part: --samples {given} cannot continue it",
            file.display()
        ));
    }
    if !a.given("spp") {
        let v = extra(TARGET_SPP)?;
        a.spp = v.parse().ok().filter(|&n| n > 0).ok_or_else(|| invalid(TARGET_SPP, v))?;
    }
    // The PNG's look: the file's unless given (any value may be given).
    if !a.given("tonemap")
        && let Some(v) = meta.extra.get(TONEMAP)
    {
        a.tonemap = v.parse().map_err(|_| invalid(TONEMAP, v))?;
    }
    if !a.given("exposure")
        && let Some(v) = meta.extra.get(EXPOSURE)
    {
        a.exposure = v.parse().map_err(|_| invalid(EXPOSURE, v))?;
    }
    if !a.given("out") {
        a.out = file.to_path_buf();
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use furnace_scene::builtin;

    #[test]
    fn builtin_name_is_the_cornell_box() {
        assert_eq!(builtin::cornell_box().unwrap().name, BUILTIN_CBOX);
    }

    #[test]
    fn mismatches_name_the_setting_and_both_values() {
        let mut m = Metadata { bounces: Some(4), sampler: Some("sobol".into()), ..Metadata::default() };
        m.extra.insert(CAMERA.into(), "0".into());
        let mut n = m.clone();
        n.bounces = Some(2);
        n.extra.insert(CAMERA.into(), "1".into());
        let file = Path::new("dir/r.exr");
        assert!(check_same(file, &m, &identity(&m, 8, 8), &identity(&m, 8, 8), LayoutUse::default()).is_ok());
        let e =
            check_same(file, &m, &identity(&m, 8, 8), &identity(&n, 8, 6), LayoutUse::default()).unwrap_err();
        assert_eq!(
            e,
            "dir/r.exr: cannot resume with different settings: camera is 0 in the file but 1 now; \
             height is 8 in the file but 6 now; bounces is 4 in the file but 2 now"
        );
    }

    #[test]
    fn look_at_records_round_trip() {
        let look: LookAt = "0.1,-2,3e-7,4,5,6,0,0,1".parse().unwrap();
        let record = look_at_record(&look, 37.5);
        assert_eq!(record, "look-at:0.1,-2,0.0000003,4,5,6,0,0,1;yfov:37.5");
        assert_eq!(parse_look_at_record(&record), Some((look, 37.5)));
        assert_eq!(camera_options(&record), "--look-at 0.1,-2,0.0000003,4,5,6,0,0,1 --yfov 37.5");
        assert_eq!(camera_options("1"), "--camera 1");
        for bad in ["look-at:1,2,3;yfov:40", "look-at:0,0,1,0,0,0,0,1,0;yfov:180", "look-at:0,0,1,0,0,0", "0"]
        {
            assert_eq!(parse_look_at_record(bad), None, "{bad}");
        }
    }

    #[test]
    fn another_sampler_layout_is_refused() {
        let mut m = Metadata { bounces: Some(4), ..Metadata::default() };
        m.extra.insert(SAMPLER_LAYOUT.into(), "5".into());
        let e = check_same(
            Path::new("old.exr"),
            &m,
            &identity(&m, 8, 8),
            &identity(&m, 8, 8),
            LayoutUse::default(),
        )
        .unwrap_err();
        assert!(e.starts_with("old.exr: its samples were drawn with sampler dimension layout 5"), "{e}");
        // Layout 1 (or none recorded) continues a scene that samples no light, not one that does.
        m.extra.insert(SAMPLER_LAYOUT.into(), "1".into());
        let same = |m: &Metadata, samples_lights: bool, chooses_point_lights: bool| {
            let uses = LayoutUse { samples_lights, chooses_point_lights, samples_wavelengths: false };
            check_same(Path::new("v1.exr"), m, &identity(m, 8, 8), &identity(m, 8, 8), uses)
        };
        assert!(same(&m, false, false).is_ok());
        let e = same(&m, true, false).unwrap_err();
        assert!(e.contains("layout 1, this furnace traces layout 4"), "{e}");
        // Layout 2 continues any render that chooses no point light.
        m.extra.insert(SAMPLER_LAYOUT.into(), "2".into());
        assert!(same(&m, true, false).is_ok());
        let e = same(&m, false, true).unwrap_err();
        assert!(e.contains("layout 2, this furnace traces layout 4"), "{e}");
        // Layout 3 continues any render without a dispersive material.
        m.extra.insert(SAMPLER_LAYOUT.into(), "3".into());
        assert!(same(&m, true, true).is_ok());
        let dispersive = LayoutUse { samples_wavelengths: true, ..LayoutUse::default() };
        let e = check_same(Path::new("v3.exr"), &m, &identity(&m, 8, 8), &identity(&m, 8, 8), dispersive)
            .unwrap_err();
        assert!(e.contains("layout 3, this furnace traces layout 4"), "{e}");
    }

    #[test]
    fn fixed_n_samplers_record_n() {
        let mut m = Metadata { sampler: Some("hammersley".into()), ..Metadata::default() };
        m.extra.insert(TARGET_SPP.into(), "64".into());
        let mut n = m.clone();
        n.extra.insert(TARGET_SPP.into(), "128".into());
        let e = check_same(
            Path::new("h.exr"),
            &m,
            &identity(&m, 4, 4),
            &identity(&n, 4, 4),
            LayoutUse::default(),
        )
        .unwrap_err();
        assert!(
            e.contains("sample count N of the fixed-N sampler (--spp) is 64 in the file but 128 now"),
            "{e}"
        );
        // A progressive sampler's target may change.
        m.sampler = Some("sobol".into());
        n.sampler = Some("sobol".into());
        assert!(
            check_same(
                Path::new("s.exr"),
                &m,
                &identity(&m, 4, 4),
                &identity(&n, 4, 4),
                LayoutUse::default()
            )
            .is_ok()
        );
    }

    #[test]
    fn same_scene_by_another_path_is_the_same_scene() {
        let m = Metadata { scene: Some("scenes/a.glb".into()), ..Metadata::default() };
        let n = Metadata { scene: Some("./../x/scenes/a.glb".into()), ..Metadata::default() };
        assert_eq!(identity(&m, 1, 1), identity(&n, 1, 1));
    }

    #[test]
    fn a_file_without_light_selection_was_rendered_by_power() {
        // Files made before the light BVH record no light selection: they chose by power.
        let old = Metadata::default();
        let mut bvh = old.clone();
        bvh.extra.insert(key("light-selection").into(), "bvh".into());
        let mut power = old.clone();
        power.extra.insert(key("light-selection").into(), "power".into());
        let file = Path::new("old.exr");
        assert!(
            check_same(file, &old, &identity(&old, 2, 2), &identity(&power, 2, 2), LayoutUse::default())
                .is_ok()
        );
        let e = check_same(file, &old, &identity(&old, 2, 2), &identity(&bvh, 2, 2), LayoutUse::default())
            .unwrap_err();
        assert!(e.ends_with("light selection is power in the file but bvh now"), "{e}");
    }
}
