//! The study's axes, listed once ([`AXES`]): the render settings it varies, each a field of
//! `furnace_render::fields::FIELDS` (its values spelt, checked and set by the field), then the
//! backend and denoising. The configurations (the product of the axes' values), their names,
//! the rows' keys and columns in chart.json and chart.csv, the configurations' entries in
//! chart.json and the study's recorded lists of values all follow from the list.
//!
//! The keys are the files' names from before the list: mostly a field's EXR attribute without
//! `furnace.`, but `sampling` for the GGX sampling and `noise_threshold`, and the study's lists
//! of samplers and backends are `samplers` and `backends`.

use super::data::{Row, default_env_sampling};
use super::study::{Study, dedup};
use crate::args::{ChartBackend, Switch};
use crate::resume;
use clap::ValueEnum;
use furnace_render::fields::{self, Field};
use furnace_render::{Choice, RenderSettings, Timing};

/// What an axis varies.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum Kind {
    /// A render setting: the field of this command-line flag. A field without a default (an
    /// option) is spelt [`UNSET`] where it is not set.
    Field(&'static str),
    /// The backend (`cpu`, `gpu`).
    Backend,
    /// Denoising of the finished image (`off`, `on`).
    Denoise,
}

/// The value of an option (a field without a default) that is not set: `off`.
pub(super) const UNSET: &str = "off";

/// An axis's part of a configuration's name (`None`: none), given its value and a lookup of
/// the configuration's value of another axis by key.
pub(super) type Part = fn(&str, &dyn Fn(&str) -> String) -> Option<String>;

/// One axis of the study.
#[derive(Debug)]
pub(super) struct Axis {
    /// Its key in the rows and configurations of chart.json, and its column of chart.csv.
    pub(super) key: &'static str,
    /// The key of the list of its values in chart.json's settings.
    pub(super) list: &'static str,
    /// What it varies.
    pub(super) kind: Kind,
    /// The study's values, as the command line spells them, each once, in the order given.
    pub(super) values: fn(&Study) -> Vec<String>,
    /// Its place among the configurations' nested loops (0: the outermost): the order of the
    /// configurations, in which they are rendered, saved and drawn.
    pub(super) nesting: usize,
    /// Its part of a configuration's name: the parts in the list's order, joined by `/`.
    pub(super) part: Part,
    /// What a row (and a study's list) saved before the axis existed means (`None`: every
    /// saved row has it).
    pub(super) before: Option<&'static str>,
    /// The single value for which the study records no list: a study from before the axis,
    /// which rendered only that, resumes (`None`: the list is always recorded).
    pub(super) unrecorded: Option<&'static str>,
}

/// The value itself as the name's part.
fn itself(value: &str, _: &dyn Fn(&str) -> String) -> Option<String> {
    Some(value.to_string())
}

/// The names of choices `v`, each once.
fn names<T: Choice>(v: &[T]) -> Vec<String> {
    dedup(v).iter().map(|c| c.name().to_string()).collect()
}

/// The command-line names of clap values `v`, each once.
fn cli_names<T: ValueEnum + PartialEq + Copy>(v: &[T]) -> Vec<String> {
    dedup(v).iter().map(resume::cli_name).collect()
}

/// The study's axes, in the order of the parts of a configuration's name.
pub(super) static AXES: &[Axis] = &[
    Axis {
        key: "sampler",
        list: "samplers",
        kind: Kind::Field("sampler"),
        values: |s| dedup(&s.args.samplers).iter().map(ToString::to_string).collect(),
        nesting: 7,
        part: itself,
        before: None,
        unrecorded: None,
    },
    Axis {
        key: "sampling",
        list: "sampling",
        kind: Kind::Field("specular-sampling"),
        values: |s| names(&s.args.sampling),
        nesting: 6,
        part: itself,
        before: None,
        unrecorded: None,
    },
    Axis {
        key: "light_sampling",
        list: "light_sampling",
        kind: Kind::Field("light-sampling"),
        values: |s| names(&s.args.light_sampling),
        nesting: 2,
        part: itself,
        // Before the axis every configuration rendered with the renderer's default, MIS.
        before: Some("mis"),
        unrecorded: None,
    },
    Axis {
        key: "triangle_sampling",
        list: "triangle_sampling",
        kind: Kind::Field("triangle-sampling"),
        values: |s| names(&s.args.triangle_sampling),
        nesting: 3,
        part: itself,
        // Before the axis light samples picked their point on an emissive triangle by area.
        before: Some("area"),
        unrecorded: None,
    },
    Axis {
        key: "light_selection",
        list: "light_selection",
        kind: Kind::Field("light-selection"),
        values: |s| names(&s.args.light_selection),
        nesting: 4,
        part: itself,
        // Before the axis light samples chose their triangle in proportion to power.
        before: Some("power"),
        unrecorded: None,
    },
    Axis {
        key: "env_sampling",
        list: "env_sampling",
        kind: Kind::Field("env-sampling"),
        values: |s| names(&s.args.env_sampling),
        nesting: 5,
        // Left out where it is the default for the light sampling: names from before the axis
        // stay valid.
        part: |v, other| (v != default_env_sampling(&other("light_sampling"))).then(|| format!("env-{v}")),
        // Before the axis no scene had an environment map, and the default, compensated
        // (importance under nee, `EnvSampling::effective`), changed nothing.
        before: Some("compensated"),
        unrecorded: None,
    },
    Axis {
        key: "compensation",
        list: "compensation",
        kind: Kind::Field("compensation"),
        values: |s| s.compensations().iter().map(resume::cli_name).collect(),
        nesting: 1,
        part: |v, _| Some(format!("comp-{v}")),
        before: None,
        unrecorded: None,
    },
    Axis {
        key: "backend",
        list: "backends",
        kind: Kind::Backend,
        values: |s| cli_names(&s.args.backends),
        nesting: 0,
        part: itself,
        before: None,
        unrecorded: None,
    },
    Axis {
        key: "point_lights",
        list: "point_lights",
        kind: Kind::Field("point-lights"),
        values: |s| names(&s.args.point_lights),
        nesting: 10,
        part: |v, _| (v != "auto").then(|| format!("points-{v}")),
        // Rows saved before the axis are read as the default's (a study whose scene has lights
        // `auto` would not gather all of is not resumed: `Study::settings_json`).
        before: Some("auto"),
        unrecorded: Some("auto"),
    },
    Axis {
        key: "noise_threshold",
        list: "noise_threshold",
        kind: Kind::Field("noise-threshold"),
        values: |s| dedup(&s.args.noise_threshold).iter().map(|t| t.name()).collect(),
        nesting: 8,
        part: |v, _| (v != UNSET).then(|| format!("adaptive-{v}")),
        // Before the axis: no adaptive sampling.
        before: Some(UNSET),
        unrecorded: Some(UNSET),
    },
    Axis {
        key: "denoise",
        list: "denoise",
        kind: Kind::Denoise,
        values: |s| cli_names(&s.args.denoise),
        nesting: 9,
        part: |v, _| (v == "on").then(|| "denoised".to_string()),
        // Before the axis: not denoised.
        before: Some("off"),
        unrecorded: Some("off"),
    },
];

impl Axis {
    /// The settings' field it varies, if it is a render setting.
    pub(super) fn field(&self) -> Option<&'static Field> {
        match self.kind {
            Kind::Field(flag) => {
                Some(fields::field(flag).unwrap_or_else(|| unreachable!("the settings have a field {flag}")))
            }
            Kind::Backend | Kind::Denoise => None,
        }
    }
}

/// One configuration of the study: its render settings (the study's, with its values of the
/// settings' axes), its backend and whether it is denoised.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) struct Config {
    pub(super) settings: RenderSettings,
    pub(super) backend: ChartBackend,
    pub(super) denoise: Switch,
}

impl Config {
    /// Its value of `axis`, as the command line spells it.
    pub(super) fn value(&self, axis: &Axis) -> String {
        match axis.kind {
            Kind::Field(_) => {
                axis.field().and_then(|f| (f.get)(&self.settings)).unwrap_or_else(|| UNSET.to_string())
            }
            Kind::Backend => resume::cli_name(&self.backend),
            Kind::Denoise => resume::cli_name(&self.denoise),
        }
    }

    /// Its values of every axis, in the order of [`AXES`].
    pub(super) fn values(&self) -> Vec<String> {
        AXES.iter().map(|a| self.value(a)).collect()
    }

    /// The configuration with `axis` at `value` (an option's [`UNSET`] leaves it as it is: the
    /// study's settings set no option).
    ///
    /// # Errors
    /// A value the axis does not take.
    pub(super) fn with(mut self, axis: &Axis, value: &str) -> Result<Self, String> {
        let bad = |_| format!("{}: '{value}' is not a value", axis.key);
        match axis.kind {
            Kind::Field(_) => {
                let f = axis.field().unwrap_or_else(|| unreachable!("a field's axis"));
                if !(f.default.is_none() && value == UNSET) {
                    (f.set)(&mut self.settings, value).map_err(|e| format!("{}: {e}", axis.key))?;
                }
            }
            Kind::Backend => self.backend = ChartBackend::from_str(value, false).map_err(bad)?,
            Kind::Denoise => self.denoise = Switch::from_str(value, false).map_err(bad)?,
        }
        Ok(self)
    }

    /// Its name: the parts of the axes, `sobol/caps/mis/solid-angle/bvh/comp-off/cpu`, then
    /// `/points-all` or `/points-one`, `/adaptive-T` and `/denoised` where they apply (an
    /// environment sampling other than the light sampling's default after the light selection,
    /// as `env-off`).
    pub(super) fn name(&self) -> String {
        name(&self.values())
    }

    /// The row of this configuration at checkpoint `spp`, with its errors `(rmse, relmse)`
    /// against the reference.
    pub(super) fn row(
        &self,
        spp: u32,
        time: Timing,
        (rmse, relmse): (f64, f64),
        reference_matches: bool,
        mean_spp: f64,
    ) -> Row {
        let axes = self.values();
        Row {
            config: name(&axes),
            axes,
            spp,
            seconds: time.wall,
            cpu_seconds: time.cpu,
            rmse,
            relmse,
            reference_matches,
            mean_spp,
        }
    }

    /// Its energy compensation.
    pub(super) fn compensation(&self) -> Switch {
        if self.settings.specular.compensation { Switch::On } else { Switch::Off }
    }
}

/// The name of the configuration of axis values `values` (in the order of [`AXES`]).
pub(super) fn name(values: &[String]) -> String {
    let other =
        |key: &str| AXES.iter().position(|a| a.key == key).map(|i| values[i].clone()).unwrap_or_default();
    AXES.iter().zip(values).filter_map(|(a, v)| (a.part)(v, &other)).collect::<Vec<_>>().join("/")
}

/// Every configuration of the study: the product of the axes' values over the study's
/// settings, nested in the axes' `nesting` order (the last axis varying fastest). `keep` may
/// change a configuration or leave it out.
///
/// # Errors
/// A value an axis does not take.
pub(super) fn configurations(
    study: &Study,
    keep: impl Fn(Config) -> Option<Config>,
) -> Result<Vec<Config>, String> {
    let base = Config { settings: study.settings, backend: ChartBackend::Cpu, denoise: Switch::Off };
    let mut nested: Vec<&Axis> = AXES.iter().collect();
    nested.sort_by_key(|a| a.nesting);
    let mut configs = vec![base];
    for axis in nested {
        let values = (axis.values)(study);
        configs = configs
            .iter()
            .flat_map(|c| values.iter().map(move |v| c.with(axis, v)))
            .collect::<Result<Vec<_>, _>>()?;
    }
    Ok(configs.into_iter().filter_map(keep).collect())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The axis of key `key`.
    ///
    /// # Panics
    /// If there is none: the keys are this module's.
    fn axis(key: &str) -> &'static Axis {
        AXES.iter().find(|a| a.key == key).unwrap_or_else(|| unreachable!("the study has an axis {key}"))
    }

    #[test]
    fn the_axes_are_named_and_nested_once_each() {
        let mut keys: Vec<&str> = AXES.iter().map(|a| a.key).collect();
        let mut lists: Vec<&str> = AXES.iter().map(|a| a.list).collect();
        let mut nesting: Vec<usize> = AXES.iter().map(|a| a.nesting).collect();
        keys.sort_unstable();
        keys.dedup();
        lists.sort_unstable();
        lists.dedup();
        nesting.sort_unstable();
        assert_eq!((keys.len(), lists.len()), (AXES.len(), AXES.len()));
        assert_eq!(nesting, (0..AXES.len()).collect::<Vec<_>>());
        for a in AXES {
            // Every field's axis names a field of the table.
            let _ = a.field();
        }
    }

    #[test]
    fn a_configuration_reads_back_the_values_it_was_given() {
        let base =
            Config { settings: RenderSettings::default(), backend: ChartBackend::Cpu, denoise: Switch::Off };
        let given = [
            ("sampler", "pmj02"),
            ("sampling", "vndf"),
            ("light_sampling", "nee"),
            ("triangle_sampling", "area"),
            ("light_selection", "power"),
            ("env_sampling", "off"),
            ("compensation", "on"),
            ("backend", "gpu"),
            ("point_lights", "one"),
            ("noise_threshold", "0.05"),
            ("denoise", "on"),
        ];
        assert_eq!(given.len(), AXES.len());
        let mut c = base;
        for (key, value) in given {
            c = c.with(axis(key), value).unwrap();
        }
        for (key, value) in given {
            assert_eq!(c.value(axis(key)), value, "{key}");
        }
        assert_eq!(
            c.name(),
            "pmj02/vndf/nee/area/power/env-off/comp-on/gpu/points-one/adaptive-0.05/denoised"
        );
        assert_eq!(base.value(axis("noise_threshold")), UNSET);
        assert_eq!(base.with(axis("noise_threshold"), UNSET).unwrap(), base);
        assert!(base.with(axis("light_sampling"), "all").is_err());
        assert!(base.with(axis("backend"), "tpu").is_err());
        // The defaults' parts are left out of the name.
        assert_eq!(base.name(), "sobol/caps/mis/solid-angle/bvh/comp-on/cpu");
    }
}
