//! The render loop's view of an integrator: it adds sample passes to a film it holds and hands
//! the film back. The loop (`render.rs`: progress, time limit, Ctrl-C, resume, output) knows
//! only this trait, so the wgpu integrator plugs in beside the CPU one.

use furnace_cpu::{Film, Renderer};

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
}
