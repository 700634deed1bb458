//! The one description of [`RenderSettings`]' user-facing fields ([`FIELDS`]): for each, its
//! name in messages, its command-line flag and help, its EXR attribute, how it is parsed and
//! printed, what a record without it means, and whether it decides the film (the resume
//! identity). Derived from this table: the command line's settings flags (of `render`, `view`,
//! `info` and, for the fields marked `bench`, `bench`), the EXR record, the resume identity and
//! restore, `furnace info`'s lines of settings, the viewer's `set NAME VALUE` and the widgets of
//! its panel for the fields that take named values, and the spelling, checks and keys of
//! `furnace chart`'s axes that are settings. So a new setting is one row here (and its field in
//! [`RenderSettings`]); making it an axis of `furnace chart` is a row of the chart's own list of
//! axes (and its flag there, which takes a list of values).
//!
//! The image size is not in the table: its flags default from the camera and its record is the
//! image itself. Neither is the sample count of the fixed-N samplers, which is the render's
//! target spp.

use crate::choice::{Choice, choices, on_off, on_off_name, parse_choice, parse_on_off};
use crate::{AdaptiveSampling, MAX_BOUNCES, RenderSettings};
use furnace_sampling::SamplerKind;

/// What a saved record that lacks a field's attribute means.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Absent {
    /// The render cannot be continued: the field was recorded from the start.
    Required,
    /// The value of files made before the field was recorded (when every render used it).
    Means(&'static str),
    /// The field's option was not given (an optional setting, recorded only when on).
    NotGiven,
}

/// One user-facing field of [`RenderSettings`].
#[derive(Clone, Copy)]
pub struct Field {
    /// Its name in messages (`light sampling`).
    pub name: &'static str,
    /// Its command-line flag without the dashes (`light-sampling`); also its name in the
    /// viewer's `set` command and the id of its argument.
    pub flag: &'static str,
    /// Its EXR attribute (`furnace.light_sampling`).
    pub key: &'static str,
    /// The flag's help.
    pub help: &'static str,
    /// The flag's value name in the help (`LIGHT_SAMPLING`, `X`).
    pub value_name: &'static str,
    /// The command line's default, as the flag is given (`None`: unset).
    pub default: Option<&'static str>,
    /// The values it takes, with a line of help each (empty: a number).
    pub choices: fn() -> Vec<(&'static str, &'static str)>,
    /// The flag that must be given with it.
    pub requires: Option<&'static str>,
    /// What a record without its attribute means.
    pub absent: Absent,
    /// Whether it decides which samples the film holds: a render continues another only when
    /// they agree on it.
    pub identity: bool,
    /// Whether `furnace bench` takes it too (a setting whose speed it measures).
    pub bench: bool,
    /// Its value as the command line spells it and the EXR records it (`None`: not set).
    pub get: fn(&RenderSettings) -> Option<String>,
    /// Sets it from `value` (as [`Field::get`] spells it).
    pub set: fn(&mut RenderSettings, &str) -> Result<(), String>,
}

impl std::fmt::Debug for Field {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Field").field("flag", &self.flag).field("key", &self.key).finish_non_exhaustive()
    }
}

fn none() -> Vec<(&'static str, &'static str)> {
    Vec::new()
}

/// `--bounces N`: at most [`MAX_BOUNCES`].
fn parse_bounces(s: &str) -> Result<u32, String> {
    let n: u32 =
        s.trim().parse().map_err(|_| format!("'{s}' is not a whole number from 0 to {MAX_BOUNCES}"))?;
    if n > MAX_BOUNCES {
        return Err(format!(
            "at most {MAX_BOUNCES} scattering events per path (beyond that a path's light is negligible, \
             and a pass can take hours)"
        ));
    }
    Ok(n)
}

/// A finite number above 0; `what` names it in the error.
/// The value that unsets an optional number (the clamp, the noise threshold): what the viewer's
/// `set` takes to turn it off again.
const OFF: &str = "off";

fn positive(s: &str, what: &str) -> Result<f32, String> {
    s.trim().parse::<f32>().ok().filter(|x| x.is_finite() && *x > 0.0).ok_or_else(|| format!("'{s}': {what}"))
}

fn whole(s: &str) -> Result<u32, String> {
    s.parse::<u32>().map_err(|e| e.to_string())
}

/// Every user-facing field of [`RenderSettings`], in the command line's order.
pub static FIELDS: &[Field] = &[
    Field {
        name: "bounces",
        flag: "bounces",
        key: "furnace.bounces",
        help: "Scattering events per path (0: only what the camera sees directly; 1: direct lighting; at \
               most 1024)",
        value_name: "BOUNCES",
        default: Some("4"),
        choices: none,
        requires: None,
        absent: Absent::Required,
        identity: true,
        bench: true,
        get: |s| Some(s.bounces.to_string()),
        set: |s, v| {
            s.bounces = parse_bounces(v)?;
            Ok(())
        },
    },
    Field {
        name: "sampler",
        flag: "sampler",
        key: "furnace.sampler",
        help: "Sampler: random, hammersley, cmj, pmj02, sobol",
        value_name: "SAMPLER",
        default: Some("sobol"),
        choices: none,
        requires: None,
        absent: Absent::Required,
        identity: true,
        bench: true,
        get: |s| Some(s.sampler.to_string()),
        set: |s, v| {
            s.sampler = v.parse::<SamplerKind>().map_err(|e| e.to_string())?;
            Ok(())
        },
    },
    Field {
        name: "seed",
        flag: "seed",
        key: "furnace.seed",
        help: "Seed of the sampler's scrambling",
        value_name: "SEED",
        default: Some("0"),
        choices: none,
        requires: None,
        absent: Absent::Required,
        identity: true,
        bench: false,
        get: |s| Some(s.seed.to_string()),
        set: |s, v| {
            s.seed = whole(v)?;
            Ok(())
        },
    },
    Field {
        name: "masking",
        flag: "masking",
        key: "furnace.masking",
        help: "Smith masking-shadowing of the GGX lobes",
        value_name: "MASKING",
        default: Some("height-correlated"),
        choices: choices::<furnace_brdf::Masking>,
        requires: None,
        absent: Absent::Required,
        identity: true,
        bench: false,
        get: |s| Some(s.specular.masking.name().into()),
        set: |s, v| {
            s.specular.masking = parse_choice(v)?;
            Ok(())
        },
    },
    Field {
        name: "compensation",
        flag: "compensation",
        key: "furnace.compensation",
        help: "Turquin energy compensation of the GGX lobes",
        value_name: "COMPENSATION",
        default: Some("on"),
        choices: on_off,
        requires: None,
        absent: Absent::Required,
        identity: true,
        bench: false,
        get: |s| Some(on_off_name(s.specular.compensation).into()),
        set: |s, v| {
            s.specular.compensation = parse_on_off(v)?;
            Ok(())
        },
    },
    Field {
        name: "specular sampling",
        flag: "specular-sampling",
        key: "furnace.specular_sampling",
        help: "How the GGX lobes sample microfacet normals",
        value_name: "SPECULAR_SAMPLING",
        default: Some("caps"),
        choices: choices::<furnace_brdf::SpecularSampling>,
        requires: None,
        absent: Absent::Required,
        identity: true,
        bench: false,
        get: |s| Some(s.specular.sampling.name().into()),
        set: |s, v| {
            s.specular.sampling = parse_choice(v)?;
            Ok(())
        },
    },
    Field {
        name: "russian roulette",
        flag: "russian-roulette",
        key: "furnace.russian_roulette",
        help: "Russian roulette from the third scattering event on (unbiased; faster, noisier)",
        value_name: "RUSSIAN_ROULETTE",
        default: Some("off"),
        choices: on_off,
        requires: None,
        absent: Absent::Required,
        identity: true,
        bench: false,
        get: |s| Some(on_off_name(s.russian_roulette).into()),
        set: |s, v| {
            s.russian_roulette = parse_on_off(v)?;
            Ok(())
        },
    },
    Field {
        name: "light sampling",
        flag: "light-sampling",
        key: "furnace.light_sampling",
        help: "How light of emitters and sun discs is found: bsdf (only by sampled rays that hit them), nee \
               (only by light samples with shadow rays) or mis (both, by the power heuristic)",
        value_name: "LIGHT_SAMPLING",
        default: Some("mis"),
        choices: choices::<crate::LightSampling>,
        requires: None,
        // Files from before light sampling had no choice to record.
        absent: Absent::Means("mis"),
        identity: true,
        bench: true,
        get: |s| Some(s.light_sampling.name().into()),
        set: |s, v| {
            s.light_sampling = parse_choice(v)?;
            Ok(())
        },
    },
    Field {
        name: "triangle sampling",
        flag: "triangle-sampling",
        key: "furnace.triangle_sampling",
        help: "How a light sample picks its point on an emissive triangle: solid-angle (uniform in the solid \
               angle it subtends, where that is precise) or area (uniform on its area)",
        value_name: "TRIANGLE_SAMPLING",
        default: Some("solid-angle"),
        choices: choices::<crate::TriangleSampling>,
        requires: None,
        // Files from before the choice sampled by area.
        absent: Absent::Means("area"),
        identity: true,
        bench: true,
        get: |s| Some(s.triangle_sampling.name().into()),
        set: |s, v| {
            s.triangle_sampling = parse_choice(v)?;
            Ok(())
        },
    },
    Field {
        name: "light selection",
        flag: "light-selection",
        key: "furnace.light_selection",
        help: "How a light sample chooses the emissive triangle: bvh (default) descends a light BVH by each \
               node's importance at the shading point (power, distance, orientation; Conty Estevez & Kulla \
               2018), power picks in proportion to power by an alias table",
        value_name: "LIGHT_SELECTION",
        default: Some("bvh"),
        choices: choices::<crate::LightSelection>,
        requires: None,
        // Files from before the light BVH chose every triangle in proportion to power.
        absent: Absent::Means("power"),
        identity: true,
        bench: true,
        get: |s| Some(s.light_selection.name().into()),
        set: |s, v| {
            s.light_selection = parse_choice(v)?;
            Ok(())
        },
    },
    Field {
        name: "point lights",
        flag: "point-lights",
        key: "furnace.point_lights",
        help: "How a scattering event gathers the point and spot lights: all (a shadow ray to each), one \
               (one light chosen in proportion to its power: one shadow ray per event whatever the number \
               of lights, more noise per sample) or auto (all up to 4 lights, one beyond: the faster to a \
               given noise, measured)",
        value_name: "POINT_LIGHTS",
        default: Some("auto"),
        choices: choices::<crate::PointLightSampling>,
        requires: None,
        // Files from before the choice gathered every point light at every event.
        absent: Absent::Means("all"),
        identity: true,
        bench: true,
        get: |s| Some(s.point_lights.name().into()),
        set: |s, v| {
            s.point_lights = parse_choice(v)?;
            Ok(())
        },
    },
    Field {
        name: "sample clamp",
        flag: "clamp",
        key: "furnace.clamp",
        help: "Clamp each sample so that its largest channel is at most X (firefly suppression; off by \
               default because it is biased: it darkens caustics and small bright lights)",
        value_name: "X",
        default: None,
        choices: none,
        requires: None,
        absent: Absent::NotGiven,
        identity: true,
        bench: false,
        get: |s| s.clamp.map(|x| x.to_string()),
        set: |s, v| {
            s.clamp = match v.trim() {
                OFF => None,
                v => Some(positive(v, "the clamp must be a finite number above 0, or off")?),
            };
            Ok(())
        },
    },
    Field {
        name: "noise threshold",
        flag: "noise-threshold",
        key: "furnace.noiseThreshold",
        help: "Adaptive sampling: a pixel stops taking samples once the relative standard error of its \
               luminance is below T (0.01: about 1 %), tested every 8 samples from --min-spp on; the \
               render ends when every pixel has (or at --spp / --time-limit). A pixel whose first samples \
               all miss its rare bright paths can stop too dark (--min-spp guards against it; measured in \
               docs/accuracy.md)",
        value_name: "T",
        default: None,
        choices: none,
        requires: None,
        absent: Absent::NotGiven,
        identity: true,
        bench: false,
        get: |s| s.adaptive.map(|a| a.threshold.to_string()),
        set: |s, v| {
            if v.trim() == OFF {
                s.adaptive = None;
                return Ok(());
            }
            let threshold =
                positive(v, "the noise threshold must be a finite number above 0 (0.01: 1 %), or off")?;
            let min_samples = s.adaptive.map_or(AdaptiveSampling::DEFAULT_MIN_SAMPLES, |a| a.min_samples);
            s.adaptive = Some(AdaptiveSampling { threshold, min_samples });
            Ok(())
        },
    },
    // After the noise threshold: it sets the minimum of the adaptive sampling that one turns on.
    Field {
        name: "minimum spp of adaptive sampling",
        flag: "min-spp",
        key: "furnace.minSpp",
        help: "Adaptive sampling: no pixel stops before this many samples",
        value_name: "N",
        default: Some("16"),
        choices: none,
        requires: Some("noise-threshold"),
        absent: Absent::NotGiven,
        identity: true,
        bench: false,
        get: |s| s.adaptive.map(|a| a.min_samples.to_string()),
        set: |s, v| {
            let n = whole(v)?;
            if let Some(a) = &mut s.adaptive {
                a.min_samples = n;
            }
            Ok(())
        },
    },
    Field {
        name: "environment sampling",
        flag: "env-sampling",
        key: "furnace.env_sampling",
        help: "How light samples gather the environment map: off (only BSDF rays that escape), importance \
               (also light samples in proportion to its luminance, weighted by --light-sampling), \
               compensated (the default: light samples where it outshines its mean, MIS compensation; \
               with --light-sampling nee the plain importance distribution is used)",
        value_name: "ENV_SAMPLING",
        default: Some("compensated"),
        choices: choices::<crate::EnvSampling>,
        requires: None,
        // Files from before environment maps had none to sample; importance is what they meant.
        absent: Absent::Means("importance"),
        identity: true,
        bench: true,
        get: |s| Some(s.env_sampling.name().into()),
        set: |s, v| {
            s.env_sampling = parse_choice(v)?;
            Ok(())
        },
    },
];

/// The field of command-line flag `flag`.
pub fn field(flag: &str) -> Option<&'static Field> {
    FIELDS.iter().find(|f| f.flag == flag)
}

/// The EXR record of `settings`: `(attribute, value)` for every field that is set, in table
/// order.
pub fn record(settings: &RenderSettings) -> Vec<(&'static str, String)> {
    FIELDS.iter().filter_map(|f| (f.get)(settings).map(|v| (f.key, v))).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_defaults_are_the_settings_defaults() {
        let default = RenderSettings::default();
        for f in FIELDS {
            let mut s = default;
            if let Some(d) = f.default {
                (f.set)(&mut s, d).unwrap();
            }
            assert_eq!(s, default, "{}", f.flag);
            assert!((f.get)(&default).is_none() || (f.get)(&default).as_deref() == f.default, "{}", f.flag);
        }
        let min = AdaptiveSampling::DEFAULT_MIN_SAMPLES.to_string();
        assert_eq!(field("min-spp").unwrap().default, Some(min.as_str()));
    }

    #[test]
    fn every_field_reads_back_what_it_records() {
        let mut s = RenderSettings {
            bounces: 7,
            seed: 3,
            clamp: Some(0.25),
            adaptive: Some(AdaptiveSampling { threshold: 0.05, min_samples: 16 }),
            ..RenderSettings::default()
        };
        s.specular.masking = furnace_brdf::Masking::Separable;
        s.russian_roulette = true;
        s.env_sampling = crate::EnvSampling::Off;
        let mut back = RenderSettings::default();
        for (key, value) in record(&s) {
            let f = FIELDS.iter().find(|f| f.key == key).unwrap();
            (f.set)(&mut back, &value).unwrap();
        }
        assert_eq!(back, s);
        let keys: Vec<&str> = FIELDS.iter().map(|f| f.key).collect();
        let flags: Vec<&str> = FIELDS.iter().map(|f| f.flag).collect();
        for list in [keys, flags] {
            let mut unique = list.clone();
            unique.sort_unstable();
            unique.dedup();
            assert_eq!(unique.len(), list.len(), "{list:?}");
        }
    }

    #[test]
    fn values_are_checked_with_a_reason() {
        let set = |flag: &str, v: &str| (field(flag).unwrap().set)(&mut RenderSettings::default(), v);
        assert!(set("bounces", "1025").unwrap_err().contains("at most 1024 scattering events"));
        assert!(set("bounces", "x").unwrap_err().contains("whole number from 0 to 1024"));
        assert_eq!(
            set("clamp", "-1").unwrap_err(),
            "'-1': the clamp must be a finite number above 0, or off"
        );
        assert!(set("noise-threshold", "nan").is_err());
        assert!(set("light-sampling", "MIS").is_err());
        assert!(set("compensation", "on").is_ok());
        // The minimum spp alone does not turn adaptive sampling on.
        let mut s = RenderSettings::default();
        (field("min-spp").unwrap().set)(&mut s, "4").unwrap();
        assert_eq!(s.adaptive, None);
    }

    #[test]
    fn optional_numbers_are_unset_by_off() {
        let mut s = RenderSettings::default();
        for (flag, v) in [("clamp", "2"), ("noise-threshold", "0.01")] {
            let f = field(flag).unwrap();
            (f.set)(&mut s, v).unwrap();
            assert_eq!((f.get)(&s).as_deref(), Some(v));
            (f.set)(&mut s, "off").unwrap();
            assert_eq!((f.get)(&s), None, "{flag}");
        }
        assert_eq!(s, RenderSettings::default());
    }
}
