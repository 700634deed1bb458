//! # furnace-view
//!
//! A live window on a progressive render: the GPU integrator of `furnace-gpu` accumulates its
//! film pass after pass, and every frame the film is drawn straight from the GPU's buffers
//! (`furnace_gpu::present`: exposure, tone map and the exact sRGB encoding of `furnace-post`,
//! twinned in WGSL; nothing is read back), with an [`egui`] panel of settings and a HUD.
//!
//! The viewer is a thin loop over the integrator contract (`furnace_render::Integrator::
//! render_pass` on a [`furnace_gpu::GpuRenderer`]): each frame renders as many samples per
//! pixel as fit its time budget ([`budget`]), and any change that alters the estimator (the
//! camera, bounces, sampler, BRDF options, light sampling, the environment's intensity, the
//! film's size) restarts the accumulation at sample 0, while display changes (exposure, tone
//! map) do not. Saving hands the film to the application ([`ViewHost::save`]), which writes
//! what `furnace render` writes.
//!
//! | input | does |
//! |---|---|
//! | left drag | orbit about the pivot |
//! | middle drag, Shift + left drag | pan |
//! | wheel | dolly towards / away from the pivot |
//! | right drag | look around (fly) |
//! | W A S D, Q E (hold; Shift: faster) | fly forward, left, back, right, down, up |
//! | Home | back to the scene's camera |
//! | R | restart the accumulation |
//! | Space | pause / continue |
//! | Ctrl+S | save EXR + PNG |
//! | C | print the camera as command-line options |
//! | `[` / `]` | exposure −/+ ½ EV |
//! | Tab | hide / show the panels |
//! | ? or F1 | help |
//! | Esc | quit |
//!
//! Scripts ([`script`]) drive the same handlers, for tests and demos.

pub mod budget;
pub mod camera;
pub mod script;

mod app;
mod ui;

pub use app::run;
pub use camera::CameraRig;

use furnace_post::Tonemap;
use furnace_render::{Film, RenderSettings};
use furnace_scene::{Camera, Scene};
use glam::Vec3;
use std::path::PathBuf;

/// What the viewer starts with.
#[derive(Debug, Clone)]
pub struct ViewConfig {
    /// The window's title.
    pub title: String,
    /// The estimator's settings; `width × height` is the film's (and the window's first) size.
    pub settings: RenderSettings,
    /// The camera it starts from (a scene camera or the framed default).
    pub camera: Camera,
    /// Whether the film keeps its size when the window is resized (the size was given); else
    /// the film follows the window.
    pub fixed_size: bool,
    /// Stop accumulating at this many samples per pixel (`None`: never).
    pub target_spp: Option<u32>,
    /// Stop accumulating after this many seconds of rendering.
    pub time_limit: Option<f64>,
    /// Exposure in EV.
    pub exposure: f32,
    /// Tone map.
    pub tonemap: Tonemap,
    /// A saved film to continue (its samples per pixel) instead of an empty one.
    pub resume: Option<(Film, u32)>,
    /// The script's source (a file name, or `-` for standard input) and, for a file, its
    /// commands (standard input is read as the viewer runs).
    pub script: Option<ScriptSource>,
}

/// Where script commands come from.
#[derive(Debug, Clone)]
pub enum ScriptSource {
    /// A file's commands, parsed up front.
    File(PathBuf, Vec<script::Line>),
    /// Standard input, read line by line while the viewer runs.
    Stdin,
}

/// The camera of a saved film.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum CameraPose {
    /// The camera the viewer started from (unmoved).
    Start,
    /// A perspective look-at pose: `furnace render --look-at eye,target,up --yfov deg` renders
    /// it bit for bit.
    LookAt {
        /// The eye.
        eye: Vec3,
        /// The point looked at.
        target: Vec3,
        /// World up.
        up: Vec3,
        /// Vertical field of view in degrees.
        yfov_degrees: f32,
    },
    /// An orthographic camera the user moved (no command-line form).
    MovedOrthographic,
}

/// A request to save the film.
#[derive(Debug, Clone)]
pub struct SaveRequest {
    /// The film, read back.
    pub film: Film,
    /// Samples per pixel in it.
    pub spp: u32,
    /// Seconds spent rendering it.
    pub seconds: f64,
    /// The settings it was rendered with.
    pub settings: RenderSettings,
    /// The camera.
    pub camera: CameraPose,
    /// The exposure shown (EV).
    pub exposure: f32,
    /// The tone map shown.
    pub tonemap: Tonemap,
    /// The environment's intensity, when the viewer changed it.
    pub env_intensity: Option<f32>,
    /// Where to save instead of the application's default (`save PATH` in a script).
    pub path: Option<PathBuf>,
    /// The adapter, as `furnace_gpu::GpuContext::describe` gives it.
    pub backend: String,
}

/// The application's side of the viewer.
pub trait ViewHost {
    /// Writes the film (EXR + PNG, as the application's render command would) and says what was
    /// written.
    ///
    /// # Errors
    /// Why it could not be written.
    fn save(&mut self, scene: &Scene, request: SaveRequest) -> Result<String, String>;

    /// Whether the user asked the process to stop (Ctrl-C in the terminal).
    fn interrupted(&self) -> bool {
        false
    }
}

/// How the viewer ended.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Outcome {
    /// The window was closed (or the script quit).
    Closed,
    /// [`ViewHost::interrupted`].
    Interrupted,
}

/// Why the viewer could not run or stopped.
#[derive(Debug, thiserror::Error)]
pub enum ViewError {
    /// No window system (no `DISPLAY` / `WAYLAND_DISPLAY`, or it refused).
    #[error("cannot open a window: {0} (furnace view needs X11 or Wayland; `furnace render` works without)")]
    NoDisplay(String),
    /// The adapter cannot present to the window.
    #[error("{0}")]
    Surface(String),
    /// A device error.
    #[error(transparent)]
    Gpu(#[from] furnace_gpu::GpuError),
    /// The integrator failed (a pass, reading the film, loading a saved one).
    #[error(transparent)]
    Render(#[from] furnace_render::RenderError),
    /// A script command failed.
    #[error("script: {0}")]
    Script(String),
}
