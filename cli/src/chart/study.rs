//! The study: its configurations (sampler × BRDF sampling × light sampling × triangle sampling
//! × light selection × environment sampling × compensation × backend), their checkpoints, the references they are
//! scored against, and what is left to render.

use super::data::{Row, config_name, rows_of};
use super::reference::Reference;
use crate::args::{ChartArgs, ChartBackend, Switch, Threshold};
use crate::resume;
use furnace_brdf::{Masking, SpecularSampling};
use furnace_render::{
    Choice, EnvSampling, LightSampling, LightSelection, PointLightSampling, TriangleSampling,
};
use furnace_render::{RenderSettings, Timing};
use furnace_sampling::SamplerKind;
use furnace_scene::Scene;
use serde_json::{Value, json};

/// One configuration of the study.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) struct Config {
    pub(super) sampler: SamplerKind,
    pub(super) sampling: SpecularSampling,
    pub(super) light_sampling: LightSampling,
    pub(super) triangle_sampling: TriangleSampling,
    pub(super) light_selection: LightSelection,
    pub(super) env_sampling: EnvSampling,
    pub(super) point_lights: PointLightSampling,
    pub(super) compensation: Switch,
    pub(super) backend: ChartBackend,
    pub(super) noise_threshold: Threshold,
    pub(super) denoise: Switch,
}

impl Config {
    /// `sobol/caps/mis/solid-angle/bvh/comp-off/cpu` (`…/bvh/env-off/comp-off/cpu` for an
    /// environment sampling other than importance), then `/points-all` or `/points-one` for a
    /// point-light gathering other than auto, `/adaptive-T` with adaptive sampling and
    /// `/denoised` when denoised (absent otherwise: older studies' names stay valid).
    pub(super) fn name(&self) -> String {
        let mut name = self.base_name();
        if self.point_lights != PointLightSampling::Auto {
            name.push_str(&format!("/points-{}", Choice::name(self.point_lights)));
        }
        if let Some(t) = self.noise_threshold.value() {
            name.push_str(&format!("/adaptive-{t}"));
        }
        if self.denoise == Switch::On {
            name.push_str("/denoised");
        }
        name
    }

    fn base_name(&self) -> String {
        config_name(
            &self.sampler.to_string(),
            Choice::name(self.sampling),
            Choice::name(self.light_sampling),
            Choice::name(self.triangle_sampling),
            Choice::name(self.light_selection),
            Choice::name(self.env_sampling),
            &resume::cli_name(&self.compensation),
            &resume::cli_name(&self.backend),
        )
    }

    #[allow(clippy::too_many_arguments)]
    pub(super) fn row(
        &self,
        spp: u32,
        time: Timing,
        rmse: f64,
        relmse: f64,
        reference_matches: bool,
        mean_spp: f64,
    ) -> Row {
        Row {
            config: self.name(),
            sampler: self.sampler.to_string(),
            sampling: Choice::name(self.sampling).to_string(),
            light_sampling: Choice::name(self.light_sampling).to_string(),
            triangle_sampling: Choice::name(self.triangle_sampling).to_string(),
            light_selection: Choice::name(self.light_selection).to_string(),
            env_sampling: Choice::name(self.env_sampling).to_string(),
            point_lights: Choice::name(self.point_lights).to_string(),
            compensation: resume::cli_name(&self.compensation),
            backend: resume::cli_name(&self.backend),
            spp,
            seconds: time.wall,
            cpu_seconds: time.cpu,
            rmse,
            relmse,
            reference_matches,
            noise_threshold: self.noise_threshold.name(),
            denoise: resume::cli_name(&self.denoise),
            mean_spp,
        }
    }
}

/// 1, 2, 4, … below `spp`, then `spp`.
pub(super) fn checkpoints(spp: u32) -> Vec<u32> {
    let mut v: Vec<u32> = (0..32).map(|k| 1u32 << k).take_while(|&n| n < spp).collect();
    v.push(spp);
    v
}

/// `v` without repeated values, in first-seen order.
pub(super) fn dedup<T: PartialEq + Copy>(v: &[T]) -> Vec<T> {
    let mut out = Vec::new();
    for &x in v {
        if !out.contains(&x) {
            out.push(x);
        }
    }
    out
}

/// Everything a study's numbers depend on: a resumed study must have the same.
pub(super) struct Study {
    pub(super) args: ChartArgs,
    pub(super) scene: std::sync::Arc<Scene>,
    pub(super) scene_name: String,
    pub(super) settings: RenderSettings,
    pub(super) masking: Masking,
    pub(super) checkpoints: Vec<u32>,
    pub(super) configs: Vec<Config>,
    pub(super) reference: Reference,
    pub(super) compensated: Option<Reference>,
}

/// What is left of a study: each unfinished configuration with its checkpoints to render,
/// and the samples per pixel of the whole study and of what is done.
pub(super) struct Plan {
    pub(super) todo: Vec<(Config, Vec<u32>)>,
    pub(super) total_spp: u64,
    pub(super) done_spp: u64,
}

impl Study {
    /// The reference a configuration is scored against, and whether its model matches.
    pub(super) fn reference_for(&self, c: &Config) -> (&Reference, bool) {
        let r = match &self.compensated {
            Some(rc) if rc.compensation == c.compensation => rc,
            _ => &self.reference,
        };
        let masking_ok = r.masking.is_none_or(|m| m == self.masking);
        (r, masking_ok && r.compensation == c.compensation)
    }

    pub(super) fn settings_json(&self) -> Value {
        let names = |v: Vec<String>| Value::from(v);
        let mut v = json!({
            "scene": self.scene_name,
            "scene_hash": self.scene.content_hash(),
            "width": self.settings.width,
            "height": self.settings.height,
            "bounces": self.settings.bounces,
            "seed": self.settings.seed,
            "masking": Choice::name(self.masking),
            "russian_roulette": "off",
            "spp": self.args.spp,
            "checkpoints": self.checkpoints,
            "samplers": names(dedup(&self.args.samplers).iter().map(ToString::to_string).collect()),
            "sampling": names(dedup(&self.args.sampling).iter().map(|v| v.name().to_string()).collect()),
            "light_sampling": names(dedup(&self.args.light_sampling).iter().map(|v| v.name().to_string()).collect()),
            "triangle_sampling":
                names(dedup(&self.args.triangle_sampling).iter().map(|v| v.name().to_string()).collect()),
            "light_selection":
                names(dedup(&self.args.light_selection).iter().map(|v| v.name().to_string()).collect()),
            "env_sampling": names(dedup(&self.args.env_sampling).iter().map(|v| v.name().to_string()).collect()),
            "compensation": names(self.compensations().iter().map(resume::cli_name).collect()),
            "backends": names(dedup(&self.args.backends).iter().map(resume::cli_name).collect()),
            "adapter": self.args.adapter,
            "reference": self.reference.settings(),
            "reference_compensated": self.compensated.as_ref().map(Reference::settings),
        });
        // The adaptive and denoising axes are recorded only when used: a study from before them
        // resumes.
        let thresholds = dedup(&self.args.noise_threshold);
        if thresholds != [Threshold(None)] {
            v["noise_threshold"] = names(thresholds.iter().map(|t| t.name()).collect());
        }
        // The point-light axis too, and wherever `auto` is not what a study from before it did
        // (gather every light): there such a study is not resumed as `auto`.
        let points = dedup(&self.args.point_lights);
        if points != [PointLightSampling::Auto]
            || self.scene.point_lights().count() > furnace_render::POINT_LIGHTS_ALL_UP_TO
        {
            v["point_lights"] = names(points.iter().map(|v| v.name().to_string()).collect());
        }
        let denoise = dedup(&self.args.denoise);
        if denoise != [Switch::Off] {
            v["denoise"] = names(denoise.iter().map(resume::cli_name).collect());
        }
        v
    }

    pub(super) fn compensations(&self) -> Vec<Switch> {
        if self.args.compensation.is_empty() {
            // Default: the references' models (both, when a compensated one is given).
            let mut v = vec![self.reference.compensation];
            v.extend(self.compensated.as_ref().map(|r| r.compensation));
            dedup(&v)
        } else {
            dedup(&self.args.compensation)
        }
    }

    /// Samples per pixel a configuration renders in all: `spp`, or the sum of the checkpoints
    /// for a fixed-N sampler.
    pub(super) fn config_spp(&self, c: &Config) -> u64 {
        if c.sampler.needs_sample_count() {
            self.checkpoints.iter().map(|&n| u64::from(n)).sum()
        } else {
            u64::from(self.args.spp)
        }
    }

    /// What is left given the saved `rows`: complete configurations are skipped; a
    /// progressive one stopped part-way starts again (its rows are removed); a fixed-N one
    /// keeps its finished checkpoints.
    pub(super) fn plan(&self, rows: &mut Vec<Row>) -> Plan {
        let mut todo: Vec<(Config, Vec<u32>)> = Vec::new();
        let (mut total, mut done_spp) = (0u64, 0u64);
        for c in &self.configs {
            let name = c.name();
            let have: Vec<u32> = rows_of(rows, &name).iter().map(|r| r.spp).collect();
            total += self.config_spp(c);
            let left: Vec<u32> = if c.sampler.needs_sample_count() {
                self.checkpoints.iter().copied().filter(|n| !have.contains(n)).collect()
            } else if self.checkpoints.iter().all(|n| have.contains(n)) {
                Vec::new()
            } else {
                rows.retain(|r| r.config != name);
                self.checkpoints.clone()
            };
            let left_spp: u64 = if c.sampler.needs_sample_count() {
                left.iter().map(|&n| u64::from(n)).sum()
            } else if left.is_empty() {
                0
            } else {
                u64::from(self.args.spp)
            };
            done_spp += self.config_spp(c) - left_spp;
            if !left.is_empty() {
                todo.push((*c, left));
            }
        }
        Plan { todo, total_spp: total, done_spp }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn checkpoints_are_powers_of_two_then_spp() {
        assert_eq!(checkpoints(1), vec![1]);
        assert_eq!(checkpoints(8), vec![1, 2, 4, 8]);
        assert_eq!(checkpoints(12), vec![1, 2, 4, 8, 12]);
    }

    #[test]
    fn dedup_keeps_first_order() {
        assert_eq!(dedup(&[3, 1, 3, 2, 1]), vec![3, 1, 2]);
    }
}
