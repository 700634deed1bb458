//! What decides a film, and whether a saved render may be continued.
//!
//! A saved render records its *identity*: every setting that decides which samples its film
//! holds (scene and its content hash, size, bounces, sampler, seed, material model, camera,
//! Russian roulette, N of a fixed-N sampler) and the [`SAMPLER_LAYOUT_VERSION`] its paths drew
//! their dimensions with. Continuing it is exact — each pixel keeps adding samples in index
//! order — only when the identity now equals the recorded one ([`check_same`],
//! [`check_layout`]).
//!
//! The settings' part of the identity, and how a record fills the settings a continuation was
//! not given, come from the one description of the settings ([`crate::fields::FIELDS`]):
//! [`identity`], [`restore`].
//!
//! The backend is recorded too ([`backend_record`]) but is not part of the identity: both
//! integrators trace the same sample indices, so a render continued on another backend adds
//! exactly the missing samples, computed there — an unbiased estimate of the same image, equal
//! to an uninterrupted render to the rounding of each path, not bit for bit.

use crate::fields::{Absent, FIELDS};
use crate::{RenderSettings, SAMPLER_LAYOUT_VERSION};
use std::collections::BTreeMap;
use std::str::FromStr;

/// The settings that decide a film, as `(setting, value)` pairs in a fixed order; a value a
/// saved render lacks is `None`.
pub type Identity = Vec<(&'static str, Option<String>)>;

/// A saved render's record: its text attributes by name.
pub type Attributes = BTreeMap<String, String>;

/// The attribute of the render's target samples per pixel (for a fixed-N sampler, its N).
pub const TARGET_SPP: &str = "furnace.target_spp";

/// Why a record cannot fill the settings.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[non_exhaustive]
pub enum RecordError {
    /// A field recorded from the start is missing.
    #[error("no '{0}' attribute; this file's render cannot be resumed")]
    Missing(&'static str),
    /// A field's recorded value is not one of its values.
    #[error("attribute '{key}' = {value} is not a valid value")]
    Invalid {
        /// The attribute.
        key: &'static str,
        /// Its value, as recorded.
        value: String,
    },
}

/// The identity of a render of `width` × `height` pixels recorded by `attributes`: the image
/// size, every field of the settings' description that decides the film (a field the record
/// lacks as [`Absent`] says), and for a fixed-N sampler its N ([`TARGET_SPP`]), after `scene`
/// (what the caller records of the scene: its name, content hash, camera, options).
pub fn identity(scene: Identity, attributes: &Attributes, width: u32, height: u32) -> Identity {
    let mut out = scene;
    out.push(("width", Some(width.to_string())));
    out.push(("height", Some(height.to_string())));
    for f in FIELDS.iter().filter(|f| f.identity) {
        let recorded = attributes.get(f.key).cloned();
        out.push((
            f.name,
            match f.absent {
                Absent::Means(old) => recorded.or_else(|| Some(old.to_string())),
                Absent::Required | Absent::NotGiven => recorded,
            },
        ));
    }
    let sampler =
        attributes.get("furnace.sampler").and_then(|s| furnace_sampling::SamplerKind::from_str(s).ok());
    if sampler.is_some_and(|k| k.needs_sample_count()) {
        out.push(("sample count N of the fixed-N sampler (--spp)", attributes.get(TARGET_SPP).cloned()));
    }
    out
}

/// Fills every field of `settings` that the continuation was not `given` (by its flag) from the
/// record: its recorded value, or what a record without it means ([`Absent`]). A field given
/// keeps its value, for [`check_same`] to compare.
///
/// # Errors
/// A required field missing, or a recorded value that is not one of the field's.
pub fn restore(
    settings: &mut RenderSettings,
    attributes: &Attributes,
    given: impl Fn(&str) -> bool,
) -> Result<(), RecordError> {
    for f in FIELDS.iter().filter(|f| !given(f.flag)) {
        let value = match (attributes.get(f.key), f.absent) {
            (Some(v), _) => v.as_str(),
            (None, Absent::Required) => return Err(RecordError::Missing(f.key)),
            (None, Absent::Means(old)) => old,
            (None, Absent::NotGiven) => continue,
        };
        (f.set)(settings, value)
            .map_err(|_| RecordError::Invalid { key: f.key, value: value.to_string() })?;
    }
    Ok(())
}

/// Separates the backends of a backend record when a render was continued on another one.
pub const BACKEND_SEPARATOR: &str = " → ";

/// Why a saved render cannot be continued.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[non_exhaustive]
pub enum ResumeError {
    /// Settings that decide the film differ between the record and now.
    #[error("cannot resume with different settings: {}", .0.iter().map(ToString::to_string).collect::<Vec<_>>().join("; "))]
    Different(Vec<Difference>),
    /// The record's paths used another sampler-dimension layout.
    #[error(
        "its samples were drawn with sampler dimension layout {recorded}, this furnace traces layout \
         {now}: the same sample indices are other paths now, so the render cannot be continued (render it \
         again, or continue it with the furnace version that wrote it)"
    )]
    Layout {
        /// The recorded layout (as written).
        recorded: String,
        /// [`SAMPLER_LAYOUT_VERSION`].
        now: u32,
    },
}

/// One setting that differs ([`ResumeError::Different`]).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Difference {
    /// The setting's name.
    pub setting: &'static str,
    /// Its recorded value.
    pub recorded: Option<String>,
    /// Its value now.
    pub now: Option<String>,
}

impl std::fmt::Display for Difference {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let show = |v: &Option<String>| v.clone().unwrap_or_else(|| "(not recorded)".into());
        write!(f, "{} is {} in the file but {} now", self.setting, show(&self.recorded), show(&self.now))
    }
}

/// `Err` listing every setting whose recorded value differs from its value now, with both.
///
/// # Errors
/// [`ResumeError::Different`].
pub fn check_same(
    recorded: &[(&'static str, Option<String>)],
    now: &[(&'static str, Option<String>)],
) -> Result<(), ResumeError> {
    let differences: Vec<Difference> = recorded
        .iter()
        .zip(now)
        .filter(|((_, a), (_, b))| a != b)
        .map(|((setting, a), (_, b))| Difference { setting, recorded: a.clone(), now: b.clone() })
        .collect();
    if differences.is_empty() { Ok(()) } else { Err(ResumeError::Different(differences)) }
}

/// What a render's paths read of the dimensions later layout versions added: a file of an
/// earlier version is continued where the render reads none of them.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct LayoutUse {
    /// The scene samples lights (emitters or a sun disc): the light block of version 2.
    pub samples_lights: bool,
    /// The render chooses one point or spot light per event: the choices of version 3.
    pub chooses_point_lights: bool,
    /// A material disperses (KHR_materials_dispersion): the path's wavelength of version 4.
    pub samples_wavelengths: bool,
}

/// `Err` unless the recorded sampler layout (`None`: not recorded, which is layout 1, the layout
/// before the version was recorded) traces the paths [`SAMPLER_LAYOUT_VERSION`] traces now: the
/// same version, or an earlier one whose paths the later versions left unchanged for this
/// render ([`LayoutUse`]: version 3 without a dispersive material, 2 besides without point-light
/// choices, 1 besides without light samples).
///
/// # Errors
/// [`ResumeError::Layout`].
pub fn check_layout(recorded: Option<&str>, uses: LayoutUse) -> Result<(), ResumeError> {
    let recorded = recorded.unwrap_or("1");
    let LayoutUse { samples_lights, chooses_point_lights, samples_wavelengths } = uses;
    match recorded.trim().parse::<u32>() {
        Ok(SAMPLER_LAYOUT_VERSION) => Ok(()),
        Ok(3) if !samples_wavelengths => Ok(()),
        Ok(2) if !chooses_point_lights && !samples_wavelengths => Ok(()),
        Ok(1) if !samples_lights && !chooses_point_lights && !samples_wavelengths => Ok(()),
        _ => Err(ResumeError::Layout { recorded: recorded.to_string(), now: SAMPLER_LAYOUT_VERSION }),
    }
}

/// The backend record of a render continued (or begun, `recorded` = `None`) on `now`
/// ([`crate::Integrator::describe`]), and whether the backend changed: the record grows by `now`
/// only when `now` differs from the last backend recorded, so resuming on the same backend keeps
/// the record as it was.
pub fn backend_record(recorded: Option<&str>, now: &str) -> (String, bool) {
    match recorded.filter(|r| !r.is_empty()) {
        None => (now.to_string(), false),
        Some(r) if r.rsplit(BACKEND_SEPARATOR).next() == Some(now) => (r.to_string(), false),
        Some(r) => (format!("{r}{BACKEND_SEPARATOR}{now}"), true),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn attributes(pairs: &[(&str, &str)]) -> Attributes {
        pairs.iter().map(|(k, v)| (k.to_string(), v.to_string())).collect()
    }

    #[test]
    fn a_record_fills_what_was_not_given() {
        let file = attributes(&[
            ("furnace.bounces", "3"),
            ("furnace.sampler", "pmj02"),
            ("furnace.seed", "5"),
            ("furnace.masking", "separable"),
            ("furnace.compensation", "off"),
            ("furnace.specular_sampling", "ndf"),
            ("furnace.russian_roulette", "on"),
            ("furnace.clamp", "2"),
        ]);
        let mut s = RenderSettings { bounces: 6, ..RenderSettings::default() };
        restore(&mut s, &file, |flag| flag == "bounces").unwrap();
        assert_eq!((s.bounces, s.seed, s.clamp, s.russian_roulette), (6, 5, Some(2.0), true));
        // Files from before a choice existed: what every render then used.
        assert_eq!(s.light_selection, crate::LightSelection::Power);
        assert_eq!(s.point_lights, crate::PointLightSampling::All);
        let mut partial = file.clone();
        partial.remove("furnace.masking");
        assert_eq!(
            restore(&mut s, &partial, |_| false).unwrap_err().to_string(),
            "no 'furnace.masking' attribute; this file's render cannot be resumed"
        );
        partial.insert("furnace.masking".into(), "Separable".into());
        assert_eq!(
            restore(&mut s, &partial, |_| false),
            Err(RecordError::Invalid { key: "furnace.masking", value: "Separable".into() })
        );
    }

    #[test]
    fn the_identity_names_what_a_file_lacks() {
        let old = attributes(&[("furnace.sampler", "hammersley"), (TARGET_SPP, "64")]);
        let id = identity(vec![("scene", Some("a.glb".into()))], &old, 4, 2);
        let get = |name: &str| id.iter().find(|(n, _)| *n == name).map(|(_, v)| v.clone());
        assert_eq!(get("scene"), Some(Some("a.glb".into())));
        assert_eq!(get("height"), Some(Some("2".into())));
        assert_eq!(get("light selection"), Some(Some("power".into())));
        assert_eq!(get("sample clamp"), Some(None));
        assert_eq!(get("sample count N of the fixed-N sampler (--spp)"), Some(Some("64".into())));
    }

    #[test]
    fn differences_name_the_setting_and_both_values() {
        let a: Identity = vec![("height", Some("8".into())), ("bounces", Some("4".into())), ("camera", None)];
        let b: Identity =
            vec![("height", Some("6".into())), ("bounces", Some("4".into())), ("camera", Some("1".into()))];
        assert!(check_same(&a, &a).is_ok());
        assert_eq!(
            check_same(&a, &b).unwrap_err().to_string(),
            "cannot resume with different settings: height is 8 in the file but 6 now; camera is (not recorded) \
             in the file but 1 now"
        );
    }

    #[test]
    fn another_layout_is_refused() {
        let uses = |samples_lights, chooses_point_lights, samples_wavelengths| LayoutUse {
            samples_lights,
            chooses_point_lights,
            samples_wavelengths,
        };
        let none = LayoutUse::default();
        assert!(check_layout(None, none).is_ok(), "files without a version are layout 1");
        assert!(check_layout(None, uses(true, false, false)).is_err(), "layout 1 never sampled lights");
        assert!(check_layout(None, uses(false, true, false)).is_err(), "layout 1 never chose point lights");
        assert!(
            check_layout(Some("2"), uses(true, false, false)).is_ok(),
            "layout 3 added only the point-light choices"
        );
        assert!(
            check_layout(Some("2"), uses(false, true, false)).is_err(),
            "layout 2 never chose point lights"
        );
        assert!(
            check_layout(Some("3"), uses(true, true, false)).is_ok(),
            "layout 4 added only the wavelength"
        );
        for v in ["1", "2", "3"] {
            assert!(
                check_layout(Some(v), uses(false, false, true)).is_err(),
                "layout {v} never drew a wavelength"
            );
        }
        assert!(check_layout(Some(&SAMPLER_LAYOUT_VERSION.to_string()), uses(true, true, true)).is_ok());
        let e = check_layout(Some("5"), none).unwrap_err();
        assert!(e.to_string().contains("layout 5"), "{e}");
        assert!(check_layout(Some("two"), none).is_err());
    }

    #[test]
    fn backend_record_grows_only_when_the_backend_changes() {
        let gpu = "gpu: Some GPU (DiscreteGpu, Vulkan, driver 580)";
        assert_eq!(backend_record(None, "cpu"), ("cpu".to_string(), false));
        // Files written before the record existed, or with an empty value.
        assert_eq!(backend_record(Some(""), "cpu"), ("cpu".to_string(), false));
        assert_eq!(backend_record(Some("cpu"), "cpu"), ("cpu".to_string(), false));
        let both = format!("cpu{BACKEND_SEPARATOR}{gpu}");
        assert_eq!(backend_record(Some("cpu"), gpu), (both.clone(), true));
        assert_eq!(backend_record(Some(&both), gpu), (both.clone(), false));
        let back = format!("{both}{BACKEND_SEPARATOR}cpu");
        assert_eq!(backend_record(Some(&both), "cpu"), (back, true));
        // Another adapter, or another driver, is another backend (not bit for bit the same).
        let other = gpu.replace("580", "581");
        assert!(backend_record(Some(gpu), &other).1);
    }
}
