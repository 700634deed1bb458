//! The render loop's view of an integrator: it adds sample passes to a film it holds and hands
//! the film back. The loop (`render.rs`: progress, time limit, Ctrl-C, resume, output) knows
//! only this trait, so the wgpu integrator plugs in beside the CPU one.

use furnace_cpu::{Film, Renderer};
use furnace_gpu::GpuRenderer;
use furnace_gpu::film::FilmData;
use glam::DVec3;

/// An integrator accumulating into its own film.
///
/// Contract: after passes `(0, n₀)`, `(n₀, n₁)`, … the film holds, for every pixel, the `f64`
/// sum and count of the accepted samples with indices `0..n₀+n₁+…`, **added in index order**,
/// whatever the pass boundaries. A backend started from a restored film (resume) thus ends
/// bit-identical to one that rendered every pass itself.
pub trait Backend {
    /// A short name for messages (`cpu`).
    fn name(&self) -> &'static str;

    /// Adds samples `first_index .. first_index + n` of every pixel to the film.
    fn render_pass(&mut self, first_index: u32, n: u32) -> Result<(), String>;

    /// The film so far: per-pixel sums and counts, and the rejected-sample count (a device
    /// backend reads it back here).
    fn film(&mut self) -> Result<Film, String>;

    /// Samples per pixel per pass for an image of `pixels` pixels: small enough that the
    /// progress bar moves, `--time-limit` stops promptly and Ctrl-C is answered within about a
    /// fifth of a second.
    fn pass_samples(&self, pixels: u64) -> u32;

    /// What computes the samples, for the record (`furnace.backend`): `cpu: ` and the target,
    /// or `gpu: ` and the adapter's name, type, API and driver. Two backends that describe
    /// themselves alike give bit-identical films.
    fn describe(&self) -> String;
}

/// The CPU reference integrator (`furnace_cpu`, rayon over rows).
#[derive(Debug)]
pub struct CpuBackend {
    renderer: Renderer,
    film: Film,
}

impl CpuBackend {
    /// Renders with `renderer` into `film` (empty, or restored from a saved render).
    pub fn new(renderer: Renderer, film: Film) -> Self {
        Self { renderer, film }
    }

    /// The renderer (`furnace bench` reads its scene).
    pub fn renderer(&self) -> &Renderer {
        &self.renderer
    }
}

impl Backend for CpuBackend {
    fn name(&self) -> &'static str {
        "cpu"
    }

    fn render_pass(&mut self, first_index: u32, n: u32) -> Result<(), String> {
        self.renderer.render_pass(&mut self.film, first_index, n).map_err(|e| e.to_string())
    }

    fn film(&mut self) -> Result<Film, String> {
        Ok(self.film.clone())
    }

    /// At most 4, and about 2¹⁸ samples per pass (a fifth of a second on two cores).
    fn pass_samples(&self, pixels: u64) -> u32 {
        (262_144 / pixels.max(1)).clamp(1, 4) as u32
    }

    /// `cpu: ` and the target (`x86_64-linux`): the math library's `sin`, `exp`, … may round
    /// differently elsewhere.
    fn describe(&self) -> String {
        format!("cpu: {}-{}", std::env::consts::ARCH, std::env::consts::OS)
    }
}

/// The wgpu integrator (`furnace_gpu`); the film is read back when asked for.
#[derive(Debug)]
pub struct GpuBackend {
    renderer: GpuRenderer,
}

impl GpuBackend {
    /// Renders with `renderer`, continuing `film` if given (a restored render).
    pub fn new(mut renderer: GpuRenderer, film: Option<&Film>) -> Result<Self, String> {
        if let Some(f) = film {
            let data = FilmData {
                width: f.width(),
                height: f.height(),
                sum: f.sums().iter().map(|s| s.to_array()).collect(),
                count: f.counts().to_vec(),
                rejected: f.rejected(),
            };
            renderer.load_film(&data).map_err(|e| e.to_string())?;
        }
        Ok(Self { renderer })
    }

    /// The renderer (`furnace bench` turns ray counting on and reads the count and sizes).
    pub fn renderer_mut(&mut self) -> &mut GpuRenderer {
        &mut self.renderer
    }
}

impl Backend for GpuBackend {
    fn name(&self) -> &'static str {
        "gpu"
    }

    fn render_pass(&mut self, first_index: u32, n: u32) -> Result<(), String> {
        self.renderer.render_pass(first_index, n).map_err(|e| e.to_string())
    }

    fn film(&mut self) -> Result<Film, String> {
        let d = self.renderer.film().map_err(|e| e.to_string())?;
        let sums = d.sum.iter().map(|s| DVec3::from_array(*s)).collect();
        Film::from_parts(d.width, d.height, sums, d.count, d.rejected).map_err(|e| e.to_string())
    }

    /// About 2²⁴ samples per pass on hardware (tens of milliseconds on a large GPU), 2¹⁶ on a
    /// software adapter; 1 to 64 samples per pixel.
    fn pass_samples(&self, pixels: u64) -> u32 {
        let target: u64 =
            if furnace_gpu::context::is_hardware(&self.renderer.context().info) { 1 << 24 } else { 1 << 16 };
        (target / pixels.max(1)).clamp(1, 64) as u32
    }

    fn describe(&self) -> String {
        format!("gpu: {}", self.renderer.context().describe())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use furnace_cpu::RenderSettings;
    use furnace_scene::builtin;

    fn cpu(film: Option<Film>) -> CpuBackend {
        let settings = RenderSettings { width: 8, height: 8, russian_roulette: true, ..Default::default() };
        let renderer = Renderer::new(builtin::cornell_box().unwrap(), settings).unwrap();
        let film = film.unwrap_or_else(|| renderer.new_film());
        CpuBackend::new(renderer, film)
    }

    /// The film's bits: sums, counts and rejections (`==` on `f64` would let −0 equal +0).
    fn bits(film: &Film) -> (Vec<u64>, Vec<u64>, u64) {
        let sums = film.sums().iter().flat_map(|s| s.to_array().map(f64::to_bits)).collect();
        (sums, film.counts().to_vec(), film.rejected())
    }

    /// Renders passes of the given sizes from index 0 and returns the film.
    fn passes(backend: &mut CpuBackend, sizes: &[u32]) -> Film {
        let mut first = 0;
        for &n in sizes {
            backend.render_pass(first, n).unwrap();
            first += n;
        }
        backend.film().unwrap()
    }

    #[test]
    fn pass_boundaries_do_not_change_the_film() {
        let whole = passes(&mut cpu(None), &[6]);
        assert!(whole.counts().iter().all(|&c| c == 6), "no sample of the Cornell box is rejected");
        for sizes in [&[1, 5][..], &[5, 1], &[2, 2, 2], &[1, 1, 1, 1, 1, 1]] {
            assert_eq!(bits(&passes(&mut cpu(None), sizes)), bits(&whole), "{sizes:?}");
        }
    }

    #[test]
    fn a_restored_film_continues_exactly() {
        let whole = passes(&mut cpu(None), &[6]);
        let half = passes(&mut cpu(None), &[3]);
        let restored =
            Film::from_parts(8, 8, half.sums().to_vec(), half.counts().to_vec(), half.rejected()).unwrap();
        let mut backend = cpu(Some(restored));
        backend.render_pass(3, 3).unwrap();
        assert_eq!(bits(&backend.film().unwrap()), bits(&whole));
    }
}
