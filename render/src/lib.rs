//! # furnace-render
//!
//! The contract between furnace's integrators and the code that drives them, in one small crate
//! that the CPU reference (`furnace-cpu`), the wgpu integrator (`furnace-gpu`), the image
//! output (`furnace-post`) and the `furnace` binary share:
//!
//! * [`RenderSettings`] — image size, path length, sampler, material-model switches;
//! * [`fields`] — the one description of the settings' user-facing fields (flag, help, EXR
//!   attribute, parsing, resume identity), from which the command line, the EXR record and the
//!   resume check are derived; [`Choice`] — the named values of a setting;
//! * [`Film`] — the one accumulation buffer: per-pixel `f64` sums and counts, rejected samples,
//!   and optionally the first-hit AOVs ([`AovSample`]: albedo, normal, depth) of the same samples;
//! * [`layout`] — which sampler dimension each random decision of a path reads, with its
//!   version ([`SAMPLER_LAYOUT_VERSION`]), recorded with saved renders;
//! * [`Integrator`] — what every backend offers (passes of samples into its film), with typed
//!   errors ([`RenderError`]);
//! * [`Session`] — a progressive render: passes until a [`Budget`] (spp, time limit) is spent
//!   or the caller cancels, with progress reports and pass timing;
//! * [`resume`] — the identity of a saved render and the checks that decide whether it may be
//!   continued;
//! * [`split`] — ranges of global sample indices ([`SampleRange`]), so that one render can be
//!   traced in parts on many machines and their films merged ([`Coverage`], [`merge_bound`]).
//!
//! ## Example
//!
//! An integrator whose samples are constant, driven by a session:
//!
//! ```
//! use furnace_render::{Budget, Film, Integrator, RenderError, RenderSettings, Session};
//! use glam::Vec3;
//!
//! struct Grey { settings: RenderSettings, film: Film }
//!
//! impl Integrator for Grey {
//!     fn name(&self) -> &'static str { "grey" }
//!     fn describe(&self) -> String { "grey: 18 %".into() }
//!     fn settings(&self) -> &RenderSettings { &self.settings }
//!     fn render_pass(&mut self, first: u32, n: u32) -> Result<(), RenderError> {
//!         for _ in first..first + n {
//!             for mut row in self.film.rows_mut() {
//!                 (0..self.settings.width as usize).for_each(|x| { row.add_sample(x, Vec3::splat(0.18)); });
//!             }
//!         }
//!         Ok(())
//!     }
//!     fn film(&mut self) -> Result<Film, RenderError> { Ok(self.film.clone()) }
//!     fn set_film(&mut self, film: &Film) -> Result<(), RenderError> {
//!         RenderError::check_film(film, &self.settings)?;
//!         self.film = film.clone();
//!         Ok(())
//!     }
//!     fn pass_samples(&self) -> u32 { 4 }
//! }
//!
//! let settings = RenderSettings { width: 8, height: 4, ..Default::default() };
//! let mut grey = Grey { settings, film: Film::new(8, 4) };
//! let mut session = Session::new(&mut grey, 0);
//! session.run(&Budget::spp(10), &|| false, &mut |p| println!("{}/{} spp", p.done, p.target))?;
//! let film = session.film()?;
//! assert_eq!(film.sample_count(7, 3), 10);
//! assert!((film.pixel(0, 0).x - 0.18).abs() < 1e-7);
//! # Ok::<(), RenderError>(())
//! ```

mod adaptive;
mod choice;
pub mod fields;
mod film;
mod integrator;
pub mod layout;
pub mod resume;
mod session;
mod settings;
pub mod split;

pub use adaptive::{ADAPTIVE_STEP, AdaptiveSampling, LUMINANCE, luminance, relative_noise};
pub use choice::{Choice, choices, on_off, on_off_name, parse_choice, parse_on_off};
pub use film::{AovImages, AovMean, AovSample, AovSum, Film, FilmRow, FilmSizeError};
pub use integrator::{CancelFlag, Integrator, RenderError};
pub use layout::SAMPLER_LAYOUT_VERSION;
pub use session::{Budget, Progress, Session, Stop, Timing, process_cpu_seconds};
pub use settings::{
    EnvSampling, LightSampling, LightSelection, MAX_BOUNCES, POINT_LIGHTS_ALL_UP_TO, PointLightSampling,
    RenderSettings, TriangleSampling, power_heuristic,
};
pub use split::{Coverage, SampleRange, merge_bound};

/// A shadow ray towards a point light stops this fraction of the distance short of it (pbrt's
/// `ShadowEpsilon`), so that a light mounted on a surface is not shadowed by that surface. Both
/// integrators use it (the GPU's WGSL gets it as a generated `const`).
pub const SHADOW_EPSILON: f32 = 1e-4;

/// How many thin-walled sheets a path may pass straight through between two scattering events
/// (a pass is no event): a guard against a ray caught between coincident sheets; real scenes
/// stay far below it. Both integrators use it.
pub const MAX_SHEET_PASSES: u32 = 64;

/// Russian roulette's survival probability for a path of `throughput`: its largest channel, at
/// most 1 (a path whose throughput has grown past 1 always survives). NaN channels are ignored
/// (`f32::max`). Both integrators play roulette from the
/// third scattering event on, with the sample of `layout::BOUNCE_RUSSIAN_ROULETTE`.
pub fn russian_roulette_survival(throughput: glam::Vec3) -> f32 {
    throughput.max_element().min(1.0)
}

/// A sample scaled so that its largest channel is at most `max` (the sample clamp of
/// [`RenderSettings::clamp`]; hue kept). Non-finite samples are returned unchanged, so that the
/// film still rejects and counts them. Both integrators call it (the GPU's WGSL twin is
/// `clamp_sample` in `integrator.wgsl`).
pub fn clamp_sample(v: glam::Vec3, max: f32) -> glam::Vec3 {
    let m = v.max_element();
    if v.is_finite() && m > max { v * (max / m) } else { v }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Vec3;

    #[test]
    fn clamp_sample_scales_to_the_largest_channel_and_keeps_non_finite_samples() {
        assert_eq!(clamp_sample(Vec3::new(4.0, 2.0, 1.0), 2.0), Vec3::new(2.0, 1.0, 0.5));
        assert_eq!(clamp_sample(Vec3::new(0.5, 2.0, 1.0), 2.0), Vec3::new(0.5, 2.0, 1.0));
        assert!(clamp_sample(Vec3::new(f32::NAN, 5.0, 1.0), 1.0).x.is_nan());
        assert_eq!(clamp_sample(Vec3::new(f32::INFINITY, 5.0, 1.0), 1.0).x, f32::INFINITY);
    }
}
