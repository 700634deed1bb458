//! [`RenderSettings`]: image size, path length, sampler and material-model switches.

use furnace_brdf::SpecularOptions;
use furnace_sampling::SamplerKind;

/// What to render and how. [`Default`] is 256×256, 4 bounces, Owen-scrambled Sobol, seed 0,
/// the glTF material model (height-correlated masking, spherical-cap sampling, Turquin
/// compensation), no Russian roulette.
///
/// Sobol is the default by measurement (furnace-cpu's `examples/sampler_study.rs`, BENCHMARKS.md "Sampler
/// choice (cbox)"): on the Cornell box it has the lowest error at equal time of the progressive
/// samplers, within 1% of PMJ02 at equal samples (a difference within the seeds' spread) and
/// 2–3× below random over 16–256 spp; Hammersley's ~9% lower error needs N in advance, which
/// progressive rendering (and these settings, without `sample_count`) cannot give.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct RenderSettings {
    /// Image width in pixels.
    pub width: u32,
    /// Image height in pixels.
    pub height: u32,
    /// Number of surface scattering events per path (Mitsuba's `max_depth` − 1): light is
    /// gathered at each of them; 0 shows only what the camera sees directly (sky, emitters).
    pub bounces: u32,
    /// Which sampler drives the path (see [`crate::layout`] for the dimension layout).
    pub sampler: SamplerKind,
    /// Seed of the sampler's scrambling.
    pub seed: u32,
    /// Total samples per pixel N, required by the fixed-N samplers (Hammersley, CMJ), ignored
    /// by the progressive ones.
    pub sample_count: Option<u32>,
    /// Model switches of every material's GGX lobe (masking form, sampling, compensation).
    pub specular: SpecularOptions,
    /// Russian roulette from the third scattering event on (unbiased: survivors are reweighted).
    pub russian_roulette: bool,
}

impl Default for RenderSettings {
    fn default() -> Self {
        Self {
            width: 256,
            height: 256,
            bounces: 4,
            sampler: SamplerKind::Sobol,
            seed: 0,
            sample_count: None,
            specular: SpecularOptions::default(),
            russian_roulette: false,
        }
    }
}
