//! The study: its configurations (the product of the values of its axes, `axes::AXES`), their
//! checkpoints, the references they are scored against, and what is left to render.

use super::axes::{AXES, Config};
use super::data::{Row, rows_of};
use super::reference::Reference;
use crate::args::{ChartArgs, Switch};
use furnace_render::{Choice, RenderSettings};
use furnace_scene::Scene;
use serde_json::{Value, json};

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
    /// The settings every configuration shares (its axes' values aside), the masking included.
    pub(super) settings: RenderSettings,
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
            Some(rc) if rc.compensation == c.compensation() => rc,
            _ => &self.reference,
        };
        let masking_ok = r.masking.is_none_or(|m| m == self.settings.specular.masking);
        (r, masking_ok && r.compensation == c.compensation())
    }

    /// What the study's numbers depend on besides its configurations' rows: a saved study is
    /// resumed only with the same. Each axis records its list of values (an axis whose only
    /// value is the one of studies from before it records none, so that they resume).
    pub(super) fn settings_json(&self) -> Value {
        let mut v = json!({
            "scene": self.scene_name,
            "scene_hash": self.scene.content_hash(),
            "width": self.settings.width,
            "height": self.settings.height,
            "bounces": self.settings.bounces,
            "seed": self.settings.seed,
            "masking": Choice::name(self.settings.specular.masking),
            "russian_roulette": "off",
            "spp": self.args.spp,
            "checkpoints": self.checkpoints,
            "adapter": self.args.adapter,
            "reference": self.reference.settings(),
            "reference_compensated": self.compensated.as_ref().map(Reference::settings),
        });
        for axis in AXES {
            let values = (axis.values)(self);
            // The point-light axis is recorded too wherever `auto` is not what a study from
            // before it did (gather every light): there such a study is not resumed as `auto`.
            let points_chosen = axis.key == "point_lights"
                && self.scene.point_lights().count() > furnace_render::POINT_LIGHTS_ALL_UP_TO;
            if axis.unrecorded.is_none_or(|only| values != [only]) || points_chosen {
                v[axis.list] = Value::from(values);
            }
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
        if c.settings.sampler.needs_sample_count() {
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
            let left: Vec<u32> = if c.settings.sampler.needs_sample_count() {
                self.checkpoints.iter().copied().filter(|n| !have.contains(n)).collect()
            } else if self.checkpoints.iter().all(|n| have.contains(n)) {
                Vec::new()
            } else {
                rows.retain(|r| r.config != name);
                self.checkpoints.clone()
            };
            let left_spp: u64 = if c.settings.sampler.needs_sample_count() {
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
