//! [`RenderSettings`]: image size, path length, sampler and material-model switches.

use crate::choice::impl_choice;
use furnace_brdf::SpecularOptions;
use furnace_sampling::SamplerKind;

/// `Display` (the CLI name) and `FromStr` (any case; the error lists the names, "a, b or c") of a
/// settings enum with `ALL` and `name()`.
macro_rules! named_choice {
    ($ty:ty, $what:literal) => {
        impl std::fmt::Display for $ty {
            fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
                f.write_str(self.name())
            }
        }

        impl std::str::FromStr for $ty {
            type Err = String;

            fn from_str(s: &str) -> Result<Self, String> {
                Self::ALL.into_iter().find(|k| k.name().eq_ignore_ascii_case(s.trim())).ok_or_else(|| {
                    let names: Vec<&str> = Self::ALL.iter().map(|k| k.name()).collect();
                    let (last, rest) = names.split_last().expect("a choice has names");
                    let list = if rest.is_empty() {
                        last.to_string()
                    } else {
                        format!("{} or {last}", rest.join(", "))
                    };
                    format!(concat!("unknown ", $what, " {:?} ({})"), s, list)
                })
            }
        }
    };
}

/// The most scattering events per path ([`RenderSettings::bounces`]) that furnace's command line
/// and its resume accept. Past it the light a path still carries is negligible in any plausible
/// scene: in a white furnace of albedo 0.99, the radiance gathered after event 1024 is
/// 0.99¹⁰²⁵ ≈ 3·10⁻⁵ of the total, below the noise of any practical sample count. Other renderers
/// stop at or below it (Blender Cycles caps its total bounces at 1024; pbrt-v4 defaults to 5).
/// It also bounds the time of a pass where no path ends early (a closed mirror box): without it
/// a pass of a million events per path never finishes.
pub const MAX_BOUNCES: u32 = 1024;

/// What to render and how. [`Default`] is 256×256, 4 bounces, Owen-scrambled Sobol, seed 0,
/// the glTF material model (height-correlated masking, spherical-cap sampling, Turquin
/// compensation), no Russian roulette, MIS of light and BSDF samples, emissive triangles chosen
/// by the light BVH and sampled by solid angle.
///
/// Sobol is the default by measurement (furnace-cpu's `examples/sampler_study.rs`, BENCHMARKS.md
/// "Sampler choice (cbox)"): on the Cornell box it has the lowest error at equal time of the
/// progressive samplers, level with PMJ02 at equal samples and well below random; Hammersley's
/// lower error needs N in advance, which progressive rendering (and these settings, without
/// `sample_count`) cannot give.
#[derive(Debug, Clone, Copy, PartialEq)]
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
    /// How light from emitters and sun discs is found ([`LightSampling`]); delta lights (the
    /// delta sun, point and spot lights) are always gathered by shadow rays.
    pub light_sampling: LightSampling,
    /// How a light sample chooses its point on an emissive triangle ([`TriangleSampling`]).
    pub triangle_sampling: TriangleSampling,
    /// How a light sample chooses which emissive triangle to sample ([`LightSelection`]).
    pub light_selection: LightSelection,
    /// How point and spot lights are gathered at a scattering event ([`PointLightSampling`]).
    pub point_lights: PointLightSampling,
    /// How an environment map is gathered ([`EnvSampling`]).
    pub env_sampling: EnvSampling,
    /// Sample clamp (firefly suppression): each sample's RGB is scaled so that its largest
    /// channel is at most this ([`crate::clamp_sample`]); `None` (the default): off. Biased: it
    /// removes energy from rare bright paths (caustics, small bright lights).
    pub clamp: Option<f32>,
    /// Whether the film also accumulates the first-hit AOVs (albedo, shading normal, depth;
    /// [`crate::AovSample`]) of the same samples, for a denoiser and compositing. Off by
    /// default: a render pays for them (memory, a little time) only when asked.
    pub aovs: bool,
    /// Adaptive sampling: pixels stop taking samples once their noise is below a threshold
    /// ([`crate::AdaptiveSampling`]); `None` (the default): every pixel takes every sample.
    pub adaptive: Option<crate::AdaptiveSampling>,
}

/// The strategies that find light of emitters and sun discs: BSDF-sampled rays that hit them,
/// light samples with shadow rays (next-event estimation), or both combined by multiple
/// importance sampling (power heuristic, Veach 1995). All three are unbiased; MIS is the
/// default because it is never much worse than the better of the other two and far better than
/// the worse (small bright emitters: NEE wins; glossy reflections of large ones: BSDF wins).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
pub enum LightSampling {
    /// Only BSDF sampling: light is found when a sampled ray hits it.
    Bsdf,
    /// Only next-event estimation: a BSDF-sampled ray that hits an emitter or disc adds nothing
    /// (except the camera ray's, which no light sample could find).
    Nee,
    /// Both, weighted by the power heuristic.
    #[default]
    Mis,
}

impl LightSampling {
    /// Every strategy, in CLI order.
    pub const ALL: [LightSampling; 3] = [Self::Bsdf, Self::Nee, Self::Mis];

    /// The CLI name: `bsdf`, `nee`, `mis`.
    pub fn name(self) -> &'static str {
        match self {
            Self::Bsdf => "bsdf",
            Self::Nee => "nee",
            Self::Mis => "mis",
        }
    }

    /// The weight of a light sample whose light pdf is `light` and BSDF pdf `bsdf` (solid angle).
    #[inline]
    pub fn light_weight(self, light: f32, bsdf: f32) -> f32 {
        match self {
            Self::Bsdf => 0.0,
            Self::Nee => 1.0,
            Self::Mis => power_heuristic(light, bsdf),
        }
    }

    /// The weight of a BSDF-sampled hit on a light whose light pdf is `light` (solid angle, as
    /// the light sampler would have chosen it from the previous vertex) and BSDF pdf `bsdf`.
    #[inline]
    pub fn bsdf_weight(self, bsdf: f32, light: f32) -> f32 {
        match self {
            Self::Bsdf => 1.0,
            Self::Nee => 0.0,
            Self::Mis => power_heuristic(bsdf, light),
        }
    }
}

named_choice!(LightSampling, "light sampling");

impl_choice!(LightSampling {
    Bsdf => "BSDF sampling only",
    Nee => "Next-event estimation only",
    Mis => "Both, weighted by multiple importance sampling (power heuristic)",
});

/// How a light sample of an emissive triangle chooses its point: uniformly on the triangle's
/// **area**, or uniformly in the **solid angle** it subtends at the shading point (spherical
/// triangles, Arvo 1995; [`furnace_sampling::warp::square_to_spherical_triangle`]). Solid
/// angle is the default by measurement (docs/accuracy.md, "Area against solid-angle triangle
/// sampling"): it removes the `cos θ_light / d²` factor from the estimate, which dominates the
/// variance of emitters seen close or at a grazing angle. Triangles subtending less than
/// `SPHERICAL_TRIANGLE_MIN_SOLID_ANGLE` or more than `SPHERICAL_TRIANGLE_MAX_SOLID_ANGLE` are
/// still sampled by area ([`TriangleSampling::solid_angle`]): there the spherical construction
/// loses precision in `f32`, and a small triangle's area pdf is nearly uniform in solid angle.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
pub enum TriangleSampling {
    /// Uniform on the triangle's area (pdf `d² / (A cos θ_light)` in solid angle).
    Area,
    /// Uniform in the triangle's solid angle where that is precise, else by area.
    #[default]
    SolidAngle,
}

impl TriangleSampling {
    /// Both methods, in CLI order.
    pub const ALL: [TriangleSampling; 2] = [Self::Area, Self::SolidAngle];

    /// The CLI name: `area`, `solid-angle`.
    pub fn name(self) -> &'static str {
        match self {
            Self::Area => "area",
            Self::SolidAngle => "solid-angle",
        }
    }

    /// The solid angle of the triangle with vertices `a`, `b`, `c` relative to the shading
    /// point, when this method samples it by solid angle from there; `None` when it is sampled
    /// by area. The light sample and the MIS weight of a BSDF hit both decide by this, from the
    /// same point (the offset ray origin), so they always agree on the pdf.
    #[inline]
    pub fn solid_angle(self, a: glam::Vec3, b: glam::Vec3, c: glam::Vec3) -> Option<f32> {
        use furnace_sampling::warp::{
            SPHERICAL_TRIANGLE_MAX_SOLID_ANGLE, SPHERICAL_TRIANGLE_MIN_SOLID_ANGLE,
            spherical_triangle_solid_angle,
        };
        match self {
            Self::Area => None,
            Self::SolidAngle => {
                let omega = spherical_triangle_solid_angle(a, b, c);
                (SPHERICAL_TRIANGLE_MIN_SOLID_ANGLE..=SPHERICAL_TRIANGLE_MAX_SOLID_ANGLE)
                    .contains(&omega)
                    .then_some(omega)
            }
        }
    }
}

named_choice!(TriangleSampling, "triangle sampling");

impl_choice!(TriangleSampling {
    Area => "Uniform on the triangle's area",
    SolidAngle => "Uniform in the solid angle the triangle subtends (by area where that is imprecise)",
});

/// How a light sample chooses the emissive triangle it samples: in proportion to the
/// triangles' **power** (an alias table, the same choice at every shading point), or by a
/// **light BVH** (Conty Estevez & Kulla 2018, pbrt-v4's `BVHLightSampler`) that descends a tree
/// of the emitters' bounds, choosing each child in proportion to a conservative bound of what it
/// sends to the shading point (power, distance, the emitters' and the receiver's orientation).
/// The BVH costs a descent of about `log₂ n` levels per light sample where the alias table costs
/// one lookup; it pays where emitters differ in distance or face away from much of the scene
/// (docs/accuracy.md, "Light selection").
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
pub enum LightSelection {
    /// In proportion to power (luminance × area), by an alias table.
    Power,
    /// By the light BVH's importance at the shading point.
    #[default]
    Bvh,
}

impl LightSelection {
    /// Both methods, in CLI order.
    pub const ALL: [LightSelection; 2] = [Self::Power, Self::Bvh];

    /// The CLI name: `power`, `bvh`.
    pub fn name(self) -> &'static str {
        match self {
            Self::Power => "power",
            Self::Bvh => "bvh",
        }
    }
}

named_choice!(LightSelection, "light selection");

impl_choice!(LightSelection {
    Power => "In proportion to the triangles' power, by an alias table (the same choice everywhere)",
    Bvh => "By a light BVH's importance at the shading point (power, distance, orientation)",
});

/// How a scattering event gathers the point and spot lights (delta lights: only a shadow ray
/// finds them): a shadow ray to **all** of them, or to **one**, chosen in proportion to its
/// power (`furnace_scene::PointLightDistribution`) and weighted by the inverse of that
/// probability; **auto** (the default) is `All` for at most [`POINT_LIGHTS_ALL_UP_TO`] lights
/// and `One` for more ([`PointLightSampling::effective`]). Both are unbiased. `All` has less
/// noise per sample and costs a shadow ray per light; `One` costs one shadow ray whatever the
/// number of lights, as Mitsuba's and pbrt's one-light-per-event estimators do (it reads one
/// sampler dimension per event of its own, [`crate::layout::point_light`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
pub enum PointLightSampling {
    /// `All` up to [`POINT_LIGHTS_ALL_UP_TO`] lights, `One` beyond.
    #[default]
    Auto,
    /// A shadow ray to every light at every event.
    All,
    /// One light per event, chosen by power.
    One,
}

/// The most point and spot lights [`PointLightSampling::Auto`] gathers all of: by measurement
/// of error at equal time on the point-light box (BENCHMARKS.md, "One point light per event"),
/// `All` is the better up to 4 lights and `One` from 5.
pub const POINT_LIGHTS_ALL_UP_TO: usize = 4;

impl PointLightSampling {
    /// Every method, in CLI order.
    pub const ALL: [PointLightSampling; 3] = [Self::Auto, Self::All, Self::One];

    /// The CLI name: `auto`, `all`, `one`.
    pub fn name(self) -> &'static str {
        match self {
            Self::Auto => "auto",
            Self::All => "all",
            Self::One => "one",
        }
    }

    /// The method used for a scene of `lights` point and spot lights: `All` or `One`.
    pub fn effective(self, lights: usize) -> PointLightSampling {
        match self {
            Self::Auto if lights <= POINT_LIGHTS_ALL_UP_TO => Self::All,
            Self::Auto => Self::One,
            other => other,
        }
    }

    /// Whether a scene of `lights` point and spot lights reads the point-light choices'
    /// sampler dimensions (layout version 3).
    pub fn chooses(self, lights: usize) -> bool {
        lights > 0 && self.effective(lights) == Self::One
    }
}

named_choice!(PointLightSampling, "point-light sampling");

impl_choice!(PointLightSampling {
    Auto => "All up to 4 lights, one beyond",
    All => "A shadow ray to every point and spot light at every scattering event",
    One => "One light per event, chosen in proportion to its power",
});

/// How paths gather an environment map (`furnace_scene::Environment`): by BSDF-sampled rays
/// that escape only (**off**), or also by light samples of the map's importance distribution
/// (luminance × sin θ over its texels, pbrt's and Mitsuba's `envmap`) combined with them by
/// [`RenderSettings::light_sampling`] (**importance**), or of its **compensated** distribution
/// (Karlík et al. 2019, "MIS compensation": the luminance minus its mean, clamped at 0, so light
/// samples go where the map outshines its average and BSDF sampling, weighted by MIS, covers the
/// rest). Compensation needs MIS: with [`LightSampling::Nee`] the plain distribution is used
/// ([`EnvSampling::effective`]).
///
/// Compensated is the default by measurement (docs/accuracy.md, "Environment maps"): it has
/// the lower error at equal samples on the reference sky and on a map with a tiny sun, and is
/// cheaper per sample (fewer shadow rays sent to the dim sky, which BSDF rays find anyway).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
pub enum EnvSampling {
    /// BSDF-sampled rays only.
    Off,
    /// Light samples in proportion to the map's luminance × sin θ.
    Importance,
    /// Light samples of the MIS-compensated distribution.
    #[default]
    Compensated,
}

impl EnvSampling {
    /// The three methods, in CLI order.
    pub const ALL: [EnvSampling; 3] = [Self::Off, Self::Importance, Self::Compensated];

    /// The CLI name: `off`, `importance`, `compensated`.
    pub fn name(self) -> &'static str {
        match self {
            Self::Off => "off",
            Self::Importance => "importance",
            Self::Compensated => "compensated",
        }
    }

    /// The method actually used with `light_sampling`: none without light samples
    /// ([`LightSampling::Bsdf`]), the plain distribution instead of the compensated one without
    /// MIS ([`LightSampling::Nee`]: a compensated light-only estimator would miss the dim part).
    pub fn effective(self, light_sampling: LightSampling) -> Self {
        match (light_sampling, self) {
            (LightSampling::Bsdf, _) => Self::Off,
            (LightSampling::Nee, Self::Compensated) => Self::Importance,
            (_, s) => s,
        }
    }

    /// Whether light samples take the environment with `light_sampling`, and from which
    /// distribution: `Some(compensated)`, or `None` (BSDF rays only).
    pub fn light_samples(self, light_sampling: LightSampling) -> Option<bool> {
        match self.effective(light_sampling) {
            Self::Off => None,
            s => Some(s == Self::Compensated),
        }
    }

    /// How the environment's two strategies are weighted: as `light_sampling` says when it is
    /// light-sampled, else all by BSDF rays.
    pub fn weights(self, light_sampling: LightSampling) -> LightSampling {
        match self.effective(light_sampling) {
            Self::Off => LightSampling::Bsdf,
            _ => light_sampling,
        }
    }
}

named_choice!(EnvSampling, "environment sampling");

impl_choice!(EnvSampling {
    Off => "Only BSDF-sampled rays that escape",
    Importance => "Also light samples in proportion to the map's luminance × sin θ",
    Compensated => "Light samples of the MIS-compensated distribution (needs --light-sampling mis)",
});

/// Veach's power heuristic with β = 2 for one sample of each strategy: `a² / (a² + b²)`,
/// formed as `1 / (1 + (b/a)²)` so that pdfs near `f32::MAX` (a tiny emitter seen from afar)
/// do not overflow; 1 when `b` is 0, 0 when `a` is 0 (and 0 for NaN).
#[inline]
pub fn power_heuristic(a: f32, b: f32) -> f32 {
    if !(a > 0.0) {
        return 0.0;
    }
    let r = b / a;
    let w = 1.0 / (1.0 + r * r);
    if w.is_nan() { 0.0 } else { w }
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
            light_sampling: LightSampling::Mis,
            triangle_sampling: TriangleSampling::SolidAngle,
            light_selection: LightSelection::Bvh,
            point_lights: PointLightSampling::Auto,
            env_sampling: EnvSampling::Compensated,
            clamp: None,
            aovs: false,
            adaptive: None,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn choices_parse_their_names_and_list_them_when_wrong() {
        assert_eq!("MIS".parse::<LightSampling>(), Ok(LightSampling::Mis));
        assert_eq!(" solid-angle".parse::<TriangleSampling>(), Ok(TriangleSampling::SolidAngle));
        assert_eq!(LightSelection::Bvh.to_string(), "bvh");
        assert_eq!("One".parse::<PointLightSampling>(), Ok(PointLightSampling::One));
        use PointLightSampling::{All, Auto, One};
        assert_eq!([0, 1, 4, 5, 1000].map(|n| Auto.effective(n)), [All, All, All, One, One]);
        assert_eq!([All.effective(1000), One.effective(1)], [All, One]);
        assert_eq!(
            [Auto.chooses(0), Auto.chooses(4), Auto.chooses(5), One.chooses(0), One.chooses(1)],
            [false, false, true, false, true]
        );
        assert_eq!(
            "x".parse::<LightSampling>(),
            Err("unknown light sampling \"x\" (bsdf, nee or mis)".to_string())
        );
        assert_eq!(
            "x".parse::<TriangleSampling>(),
            Err("unknown triangle sampling \"x\" (area or solid-angle)".into())
        );
        assert_eq!("x".parse::<LightSelection>(), Err("unknown light selection \"x\" (power or bvh)".into()));
        assert_eq!(EnvSampling::Compensated.light_samples(LightSampling::Mis), Some(true));
        assert_eq!(EnvSampling::Compensated.light_samples(LightSampling::Nee), Some(false));
        assert_eq!(EnvSampling::Importance.light_samples(LightSampling::Bsdf), None);
        assert_eq!(EnvSampling::Off.light_samples(LightSampling::Mis), None);
    }
}
