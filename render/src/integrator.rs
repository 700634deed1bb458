//! [`Integrator`]: what every backend (the CPU reference, the wgpu integrator) offers the code
//! that drives a render, and [`RenderError`], what it can fail with.

use crate::{Film, RenderSettings};
use furnace_sampling::SamplerError;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};

/// A flag that stops a render inside a pass: the caller raises it (from a Ctrl-C handler, a
/// viewer's close button), an integrator that polls it ([`Integrator::set_cancel_flag`]) drops
/// the unfinished part of its pass and returns [`RenderError::Interrupted`]. Clones share the
/// flag.
#[derive(Debug, Clone, Default)]
pub struct CancelFlag(Arc<AtomicBool>);

impl CancelFlag {
    /// A flag not raised.
    pub fn new() -> Self {
        Self::default()
    }

    /// Raises the flag: every integrator polling it stops at its next check.
    pub fn raise(&self) {
        self.0.store(true, Ordering::Relaxed);
    }

    /// Lowers it again (to render on after a stop).
    pub fn clear(&self) {
        self.0.store(false, Ordering::Relaxed);
    }

    /// Whether it is raised (a relaxed load: cheap enough to poll once per sample).
    #[inline]
    pub fn is_raised(&self) -> bool {
        self.0.load(Ordering::Relaxed)
    }
}

/// A renderer of one scene, through one camera, with one [`RenderSettings`], accumulating into a
/// film it holds.
///
/// Contract: after passes `(0, n₀)`, `(n₀, n₁)`, … the film holds, for every pixel, the `f64`
/// sum and count of the accepted samples with indices `0..n₀+n₁+…`, **added in index order**,
/// whatever the pass boundaries. An integrator given a saved film ([`Integrator::set_film`])
/// thus ends bit-identical to one that rendered every pass itself, and a render can be cut into
/// passes however the caller likes ([`crate::Session`] does).
///
/// One integrator keeps this contract only to rounding: `furnace_gpu::MultiGpuRenderer`, which
/// shares each pass among several devices and adds their films, so a pixel's samples are summed
/// in an order that depends on the pass cuts (its films equal a single device's to
/// [`crate::split::merge_bound`]).
///
/// Implementors build themselves from a scene, a camera and the settings (`CpuRenderer::new`,
/// `GpuRenderer::new`, which also takes the device); everything after that goes through this
/// trait.
pub trait Integrator {
    /// A short name for messages: `cpu`, `gpu`.
    fn name(&self) -> &'static str;

    /// What computes the samples, for the record: `cpu: ` and the target, or `gpu: ` and the
    /// adapter's name, type, API and driver. Two integrators that describe themselves alike give
    /// bit-identical films from the same settings.
    fn describe(&self) -> String;

    /// The settings it renders with.
    fn settings(&self) -> &RenderSettings;

    /// Adds samples `first_sample .. first_sample + samples_per_pixel` of every pixel to the
    /// film (of every pixel still taking samples, under adaptive sampling: the rule of
    /// [`crate::AdaptiveSampling`], applied at each multiple of [`crate::ADAPTIVE_STEP`] the
    /// pass reaches, whatever the pass boundaries).
    ///
    /// # Errors
    /// [`RenderError::Sampler`] when a fixed-N sampler would run past N (nothing is added then);
    /// [`RenderError::Device`] for a device's failure.
    fn render_pass(&mut self, first_sample: u32, samples_per_pixel: u32) -> Result<(), RenderError>;

    /// The film so far (a device integrator reads it back here).
    ///
    /// # Errors
    /// [`RenderError::Device`] if it cannot be read back.
    fn film(&mut self) -> Result<Film, RenderError>;

    /// Replaces the film, to continue a saved render (or, with an empty film, to start again).
    ///
    /// # Errors
    /// [`RenderError::FilmSize`] if `film` is not of the settings' size; a device's errors.
    fn set_film(&mut self, film: &Film) -> Result<(), RenderError>;

    /// Samples per pixel per pass for this image: small enough that progress shows, a time
    /// limit stops promptly and cancellation is answered within about a fifth of a second.
    fn pass_samples(&self) -> u32;

    /// With adaptive sampling ([`RenderSettings::adaptive`]): how many pixels have converged
    /// (they take no more samples); `None` without it.
    fn converged_pixels(&self) -> Option<u64> {
        None
    }

    /// The device time of the last pass, where the backend measures it (GPU timestamps).
    fn last_pass_device_seconds(&self) -> Option<f64> {
        None
    }

    /// Gives the integrator a flag to poll during its passes: once it is raised, the pass in
    /// progress stops within about a sample's time, its unfinished samples are dropped (the
    /// film keeps whole samples only, in index order) and it returns
    /// [`RenderError::Interrupted`]. The default ignores the flag: such an integrator is only
    /// stopped between passes ([`crate::Session::run`]'s `cancel`).
    fn set_cancel_flag(&mut self, flag: CancelFlag) {
        let _ = flag;
    }
}

/// What rendering can fail with.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum RenderError {
    /// The sampler's: a fixed-N sampler without N, or run past N.
    #[error(transparent)]
    Sampler(#[from] SamplerError),
    /// A film of another size than the render's.
    #[error("a {film_width}×{film_height} film cannot hold a {width}×{height} render")]
    FilmSize {
        /// The film's width.
        film_width: u32,
        /// The film's height.
        film_height: u32,
        /// The render's width.
        width: u32,
        /// The render's height.
        height: u32,
    },
    /// A film with AOVs for a render without them, or the other way round.
    #[error("{}", if *film_has_aovs {
        "the film has AOVs but the render does not take them (render with AOVs on to continue it)"
    } else {
        "the film has no AOVs, so a render with AOVs cannot continue it (AOVs must sum the same samples as the image, from the first)"
    })]
    FilmAovs {
        /// Whether the film has AOVs.
        film_has_aovs: bool,
    },
    /// A film with adaptive-sampling state for a render without adaptive sampling, or the other
    /// way round.
    #[error("{}", if *film_has_state {
        "the film was rendered with adaptive sampling; continue it with the same noise threshold"
    } else {
        "the film was rendered without adaptive sampling, so an adaptive render cannot continue it (its pixels' squared luminances were not summed)"
    })]
    FilmAdaptive {
        /// Whether the film has adaptive-sampling state.
        film_has_state: bool,
    },
    /// The backend's device failed (a GPU's validation error, out of memory, device lost, …).
    #[error(transparent)]
    Device(Box<dyn std::error::Error + Send + Sync>),
    /// Memory for the pass could not be allocated (the film keeps the passes before it).
    #[error("out of memory: {what} needs {} MB", bytes.div_ceil(1_000_000))]
    OutOfMemory {
        /// What needed it.
        what: &'static str,
        /// How many bytes it asked for.
        bytes: u64,
    },
    /// The pass was stopped by its [`CancelFlag`]: the film holds the pass's first `samples`
    /// samples per pixel (whole samples of every pixel, added in index order) and nothing of
    /// the rest.
    #[error("interrupted after {samples} samples per pixel of the pass")]
    Interrupted {
        /// Samples per pixel of the pass that the film holds.
        samples: u32,
    },
}

impl RenderError {
    /// [`RenderError::FilmSize`] unless `film` is `settings.width × settings.height`;
    /// [`RenderError::FilmAovs`] unless it has AOVs exactly when [`RenderSettings::aovs`] asks;
    /// [`RenderError::FilmAdaptive`] unless it has adaptive-sampling state exactly when
    /// [`RenderSettings::adaptive`] is set.
    pub fn check_film(film: &Film, settings: &RenderSettings) -> Result<(), RenderError> {
        if (film.width(), film.height()) == (settings.width, settings.height) {
            if film.has_aovs() != settings.aovs {
                return Err(RenderError::FilmAovs { film_has_aovs: film.has_aovs() });
            }
            if film.has_adaptive() != settings.adaptive.is_some() {
                return Err(RenderError::FilmAdaptive { film_has_state: film.has_adaptive() });
            }
            return Ok(());
        }
        Err(RenderError::FilmSize {
            film_width: film.width(),
            film_height: film.height(),
            width: settings.width,
            height: settings.height,
        })
    }
}
