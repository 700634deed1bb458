//! Both integrators behind one [`Integrator`]: a test written once runs on the CPU reference and
//! on the GPU (lavapipe in CI).

use crate::gpu::test_context;
use furnace_cpu::CpuRenderer;
use furnace_gpu::GpuRenderer;
use furnace_render::{Integrator, RenderError, RenderSettings};
use furnace_scene::{Camera, Scene};
use std::fmt;
use std::sync::Arc;

/// Which integrator a test runs.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Backend {
    /// `furnace_cpu::CpuRenderer`.
    Cpu,
    /// `furnace_gpu::GpuRenderer` on [`test_context`]'s adapter.
    Gpu,
}

impl Backend {
    /// Both, CPU first.
    pub const ALL: [Backend; 2] = [Backend::Cpu, Backend::Gpu];

    /// Opens this backend's integrator on `scene` through `camera` with an empty film.
    ///
    /// `Ok(None)` only for the GPU when GPU tests are skipped on purpose
    /// (`FURNACE_SKIP_GPU_TESTS=1`); without an adapter otherwise, [`test_context`] panics.
    ///
    /// # Errors
    /// The integrator's own (a fixed-N sampler without N, a scene the GPU does not support).
    pub fn open(
        self,
        scene: &Scene,
        camera: &Camera,
        settings: RenderSettings,
    ) -> Result<Option<Box<dyn Integrator>>, RenderError> {
        Ok(match self {
            Backend::Cpu => Some(Box::new(CpuRenderer::new(Arc::new(scene.clone()), camera, settings)?)),
            Backend::Gpu => match test_context() {
                None => None,
                Some(ctx) => Some(Box::new(GpuRenderer::new(ctx, scene, camera, settings)?)),
            },
        })
    }

    /// [`open`](Self::open) through the scene's default camera, panicking on an error.
    ///
    /// # Panics
    /// If the integrator cannot be opened.
    pub fn open_default(self, scene: &Scene, settings: RenderSettings) -> Option<Box<dyn Integrator>> {
        self.open(scene, &scene.default_camera(), settings).unwrap_or_else(|e| panic!("{self}: {e}"))
    }
}

impl fmt::Display for Backend {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            Backend::Cpu => "cpu",
            Backend::Gpu => "gpu",
        })
    }
}
