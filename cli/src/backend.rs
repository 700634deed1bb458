//! Which integrator renders: `--backend auto|cpu|gpu` and `--adapter`, decided in one place
//! ([`open`]) for `furnace render`, `chart`, `bench` and the tests.

use furnace_cpu::CpuRenderer;
use furnace_gpu::{AdapterChoice, GpuContext, GpuError, GpuRenderer};
use furnace_render::{Film, Integrator, RenderError, RenderSettings};
use furnace_scene::{Camera, Scene};
use std::sync::Arc;

/// Where to render.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum BackendChoice {
    /// A hardware GPU if there is one (or the adapter named), else the CPU: software adapters
    /// such as lavapipe are slower than the CPU integrator and used only when asked for.
    #[default]
    Auto,
    /// The CPU reference integrator.
    Cpu,
    /// The wgpu integrator on the best adapter (or the adapter named), software ones included.
    Gpu,
}

/// The GPU context `choice` and `adapter` ask for: `None` for the CPU.
///
/// # Errors
/// [`GpuError::NoAdapter`] when a GPU is required (`Gpu`, or an adapter named) and none is
/// found; other device errors.
pub fn gpu_context(choice: BackendChoice, adapter: Option<&str>) -> Result<Option<GpuContext>, GpuError> {
    Ok(match (choice, adapter) {
        (BackendChoice::Cpu, _) => None,
        (BackendChoice::Gpu | BackendChoice::Auto, Some(name)) => {
            Some(GpuContext::new(&AdapterChoice::Named(name.to_string()))?)
        }
        (BackendChoice::Gpu, None) => Some(GpuContext::new(&AdapterChoice::Best)?),
        // auto: a hardware adapter if there is one; without, the CPU integrator.
        (BackendChoice::Auto, None) => GpuContext::new(&AdapterChoice::Hardware).ok(),
    })
}

/// An open integrator: the CPU reference or the wgpu one, as [`gpu_context`] decides.
#[derive(Debug)]
pub enum Backend {
    /// The CPU reference integrator.
    Cpu(Box<CpuRenderer>),
    /// The wgpu integrator.
    Gpu(Box<GpuRenderer>),
}

/// Opens the integrator that `choice` and `adapter` ask for on `scene` seen through `camera`,
/// with an empty film.
///
/// # Errors
/// The GPU's ([`gpu_context`], upload, pipeline) and the sampler's (a fixed-N sampler without
/// N), as [`RenderError`]s.
pub fn open(
    choice: BackendChoice,
    adapter: Option<&str>,
    scene: Arc<Scene>,
    camera: &Camera,
    settings: RenderSettings,
) -> Result<Backend, RenderError> {
    match gpu_context(choice, adapter)? {
        Some(ctx) => Ok(Backend::Gpu(Box::new(GpuRenderer::new(ctx, &scene, camera, settings)?))),
        None => Ok(Backend::Cpu(Box::new(CpuRenderer::new(scene, camera, settings)?))),
    }
}

impl Backend {
    /// The integrator.
    pub fn integrator(&mut self) -> &mut dyn Integrator {
        match self {
            Self::Cpu(c) => c.as_mut(),
            Self::Gpu(g) => g.as_mut(),
        }
    }

    /// The integrator, shared.
    pub fn integrator_ref(&self) -> &dyn Integrator {
        match self {
            Self::Cpu(c) => c.as_ref(),
            Self::Gpu(g) => g.as_ref(),
        }
    }

    /// The wgpu integrator, if that is what this is (benchmarks read its counters).
    pub fn gpu(&mut self) -> Option<&mut GpuRenderer> {
        match self {
            Self::Gpu(g) => Some(g),
            Self::Cpu(_) => None,
        }
    }
}

impl Integrator for Backend {
    fn name(&self) -> &'static str {
        self.integrator_ref().name()
    }

    fn describe(&self) -> String {
        self.integrator_ref().describe()
    }

    fn settings(&self) -> &RenderSettings {
        self.integrator_ref().settings()
    }

    fn render_pass(&mut self, first_sample: u32, samples_per_pixel: u32) -> Result<(), RenderError> {
        self.integrator().render_pass(first_sample, samples_per_pixel)
    }

    fn film(&mut self) -> Result<Film, RenderError> {
        self.integrator().film()
    }

    fn set_film(&mut self, film: &Film) -> Result<(), RenderError> {
        self.integrator().set_film(film)
    }

    fn pass_samples(&self) -> u32 {
        self.integrator_ref().pass_samples()
    }

    fn last_pass_device_seconds(&self) -> Option<f64> {
        self.integrator_ref().last_pass_device_seconds()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use furnace_scene::builtin;

    fn cpu() -> Backend {
        let settings = RenderSettings { width: 8, height: 8, russian_roulette: true, ..Default::default() };
        let scene = builtin::cornell_box().unwrap();
        let camera = scene.default_camera();
        open(BackendChoice::Cpu, None, Arc::new(scene), &camera, settings).unwrap()
    }

    /// The film's bits: sums, counts and rejections (`==` on `f64` would let −0 equal +0).
    fn bits(film: &Film) -> (Vec<u64>, Vec<u64>, u64) {
        let sums = film.sums().iter().flat_map(|s| s.to_array().map(f64::to_bits)).collect();
        (sums, film.counts().to_vec(), film.rejected())
    }

    /// Renders passes of the given sizes from index 0 and returns the film.
    fn passes(backend: &mut Backend, sizes: &[u32]) -> Film {
        let mut first = 0;
        for &n in sizes {
            backend.render_pass(first, n).unwrap();
            first += n;
        }
        backend.film().unwrap()
    }

    #[test]
    fn pass_boundaries_do_not_change_the_film() {
        let whole = passes(&mut cpu(), &[6]);
        assert!(whole.counts().iter().all(|&c| c == 6), "no sample of the Cornell box is rejected");
        for sizes in [&[1, 5][..], &[5, 1], &[2, 2, 2], &[1, 1, 1, 1, 1, 1]] {
            assert_eq!(bits(&passes(&mut cpu(), sizes)), bits(&whole), "{sizes:?}");
        }
    }

    #[test]
    fn a_restored_film_continues_exactly() {
        let whole = passes(&mut cpu(), &[6]);
        let half = passes(&mut cpu(), &[3]);
        let restored =
            Film::from_parts(8, 8, half.sums().to_vec(), half.counts().to_vec(), half.rejected()).unwrap();
        let mut backend = cpu();
        backend.set_film(&restored).unwrap();
        backend.render_pass(3, 3).unwrap();
        assert_eq!(bits(&backend.film().unwrap()), bits(&whole));
        assert!(backend.set_film(&Film::new(4, 4)).is_err(), "a film of another size");
    }
}
