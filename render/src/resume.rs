//! What decides a film, and whether a saved render may be continued.
//!
//! A saved render records its *identity*: every setting that decides which samples its film
//! holds (scene and its content hash, size, bounces, sampler, seed, material model, camera,
//! Russian roulette, N of a fixed-N sampler) and the [`SAMPLER_LAYOUT_VERSION`] its paths drew
//! their dimensions with. Continuing it is exact — each pixel keeps adding samples in index
//! order — only when the identity now equals the recorded one ([`check_same`],
//! [`check_layout`]).
//!
//! The backend is recorded too ([`backend_record`]) but is not part of the identity: both
//! integrators trace the same sample indices, so a render continued on another backend adds
//! exactly the missing samples, computed there — an unbiased estimate of the same image, equal
//! to an uninterrupted render to the rounding of each path, not bit for bit.

use crate::SAMPLER_LAYOUT_VERSION;

/// The settings that decide a film, as `(setting, value)` pairs in a fixed order; a value a
/// saved render lacks is `None`.
pub type Identity = Vec<(&'static str, Option<String>)>;

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

/// `Err` unless the recorded sampler layout (`None`: not recorded, which is layout 1, the layout
/// before the version was recorded) traces the paths [`SAMPLER_LAYOUT_VERSION`] traces now: the
/// same version; or layout 2 for a render that chooses no point light (`chooses_point_lights`
/// false: `--point-lights all`, or no point lights), whose paths version 3 left unchanged; or
/// layout 1 where, besides, the scene samples no light (`samples_lights` false: no emitters,
/// no sun disc), whose paths version 2 left unchanged.
///
/// # Errors
/// [`ResumeError::Layout`].
pub fn check_layout(
    recorded: Option<&str>,
    samples_lights: bool,
    chooses_point_lights: bool,
) -> Result<(), ResumeError> {
    let recorded = recorded.unwrap_or("1");
    match recorded.trim().parse::<u32>() {
        Ok(SAMPLER_LAYOUT_VERSION) => Ok(()),
        Ok(2) if !chooses_point_lights => Ok(()),
        Ok(1) if !samples_lights && !chooses_point_lights => Ok(()),
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
        assert!(check_layout(None, false, false).is_ok(), "files without a version are layout 1");
        assert!(check_layout(None, true, false).is_err(), "layout 1 never sampled lights");
        assert!(check_layout(None, false, true).is_err(), "layout 1 never chose point lights");
        assert!(check_layout(Some("2"), true, false).is_ok(), "layout 3 added only the point-light choices");
        assert!(check_layout(Some("2"), false, true).is_err(), "layout 2 never chose point lights");
        assert!(check_layout(Some(&SAMPLER_LAYOUT_VERSION.to_string()), true, true).is_ok());
        let e = check_layout(Some("4"), false, false).unwrap_err();
        assert!(e.to_string().contains("layout 4"), "{e}");
        assert!(check_layout(Some("two"), false, false).is_err());
    }

    #[test]
    fn backend_record_grows_only_when_the_backend_changes() {
        let gpu = "gpu: NVIDIA H100 80GB HBM3 (DiscreteGpu, Vulkan, driver NVIDIA 580)";
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
