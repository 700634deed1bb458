//! The window, its event loop and the frame: input → changes → a pass → the film and the panels
//! drawn.

mod input;
mod scripted;

use crate::budget::{FrameBudget, INTERACTIVE_SECONDS, STILL_SECONDS};
use crate::camera::CameraRig;
use crate::script::{self, DragButton};
use crate::ui::{self, Action, Controls, Hud};
use crate::{CameraPose, Outcome, SaveRequest, ScriptSource, ViewConfig, ViewError, ViewHost};
use furnace_gpu::GpuRenderer;
use furnace_gpu::present::{FilmPresenter, NoiseEstimator, Placement};
use furnace_render::{Integrator, RenderSettings};
use furnace_scene::{Camera, Projection, Scene};
use input::{fly_key, key_name};
use scripted::{Wait, spawn_stdin_reader};
use std::collections::{HashSet, VecDeque};
use std::sync::Arc;
use std::time::{Duration, Instant};
use winit::application::ApplicationHandler;
use winit::dpi::PhysicalSize;
use winit::event::{ElementState, MouseButton, MouseScrollDelta, WindowEvent};
use winit::event_loop::{ActiveEventLoop, ControlFlow, EventLoop, EventLoopProxy};
use winit::window::{Window, WindowId};

/// How often the noise estimate is refreshed.
const NOISE_EVERY: Duration = Duration::from_millis(500);
/// After an input, frames use the interactive budget for this long.
const INTERACTIVE_FOR: Duration = Duration::from_millis(300);
/// A message (saved, error) stays on the HUD this long.
const MESSAGE_FOR: Duration = Duration::from_secs(4);

/// Events sent to the loop from other threads.
#[derive(Debug)]
enum UserEvent {
    /// A line of the script read from standard input, parsed (or why not).
    ScriptLine(Result<script::Line, String>),
    /// Standard input ended.
    ScriptEnd,
}

/// Opens the window and runs the viewer until it is closed, the script quits, or the host
/// reports an interrupt.
///
/// # Errors
/// [`ViewError::NoDisplay`] without a window system, [`ViewError::Surface`] when the adapter
/// cannot draw into the window, device errors, and script errors (a bad line, a failed
/// command).
pub fn run(
    renderer: GpuRenderer,
    scene: Scene,
    config: ViewConfig,
    host: &mut dyn ViewHost,
) -> Result<Outcome, ViewError> {
    let event_loop =
        EventLoop::<UserEvent>::with_user_event().build().map_err(|e| ViewError::NoDisplay(e.to_string()))?;
    let proxy = event_loop.create_proxy();
    let mut app = App::new(renderer, scene, config, host, proxy)?;
    event_loop.run_app(&mut app).map_err(|e| ViewError::NoDisplay(e.to_string()))?;
    if let Some(e) = app.error.take() {
        return Err(e);
    }
    Ok(app.outcome)
}

/// What the window needs once it exists.
struct Window_ {
    window: Arc<Window>,
    surface: wgpu::Surface<'static>,
    config: wgpu::SurfaceConfiguration,
    presenter: FilmPresenter,
    egui: egui::Context,
    egui_state: egui_winit::State,
    egui_renderer: egui_wgpu::Renderer,
}

struct App<'h> {
    host: &'h mut dyn ViewHost,
    renderer: GpuRenderer,
    scene: Scene,
    /// The film's and camera's state as rendered (what the controls are compared with).
    applied: RenderSettings,
    applied_camera: Camera,
    applied_env: Option<f32>,
    controls: Controls,
    rig: CameraRig,
    fixed_size: bool,
    time_limit: Option<f64>,
    title: String,
    win: Option<Window_>,
    noise: Option<NoiseEstimator>,
    budget: FrameBudget,
    hud: Hud,
    /// Samples per pixel in the film.
    spp: u32,
    /// Times the accumulation restarted.
    resets: u64,
    frame: u64,
    /// Seconds of passes since the last restart (plus the resumed film's).
    render_seconds: f64,
    last_frame: Instant,
    last_input: Instant,
    last_noise: Option<Instant>,
    /// Pointer state.
    cursor: Option<(f64, f64)>,
    buttons: HashSet<MouseButton>,
    shift: bool,
    ctrl: bool,
    /// Fly keys held (lower-case letters), with the scripted ones' release times.
    held: HashSet<char>,
    held_until: Vec<(char, Instant)>,
    script: VecDeque<script::Line>,
    script_stdin: bool,
    script_ended: bool,
    waiting: Option<(script::Line, Wait)>,
    proxy: EventLoopProxy<UserEvent>,
    outcome: Outcome,
    error: Option<ViewError>,
}

impl<'h> App<'h> {
    fn new(
        mut renderer: GpuRenderer,
        scene: Scene,
        config: ViewConfig,
        host: &'h mut dyn ViewHost,
        proxy: EventLoopProxy<UserEvent>,
    ) -> Result<Self, ViewError> {
        renderer.enable_display()?;
        let noise = NoiseEstimator::new(renderer.context())?;
        let mut spp = 0;
        let render_seconds = 0.0;
        if let Some((film, done)) = &config.resume {
            Integrator::set_film(&mut renderer, film)?;
            spp = *done;
        }
        let (lo, hi) = scene.bounds();
        let rig = CameraRig::new(config.camera, (lo, hi));
        let env_intensity = scene.environment().map(|e| e.intensity);
        let (script, script_stdin) = match &config.script {
            None => (VecDeque::new(), false),
            Some(ScriptSource::File(_, lines)) => (lines.iter().cloned().collect(), false),
            Some(ScriptSource::Stdin) => (VecDeque::new(), true),
        };
        let controls = Controls {
            settings: config.settings,
            env_intensity,
            exposure: config.exposure,
            tonemap: config.tonemap,
            target_spp: config.target_spp,
            paused: false,
            show_ui: true,
            show_help: false,
        };
        let now = Instant::now();
        Ok(Self {
            host,
            applied: config.settings,
            applied_camera: config.camera,
            applied_env: env_intensity,
            hud: Hud { initial_env: env_intensity, ..Hud::new(renderer.context().describe()) },
            renderer,
            scene,
            controls,
            rig,
            fixed_size: config.fixed_size,
            time_limit: config.time_limit,
            title: config.title,
            win: None,
            noise,
            budget: FrameBudget::default(),
            spp,
            resets: 0,
            frame: 0,
            render_seconds,
            last_frame: now,
            last_input: now - INTERACTIVE_FOR,
            last_noise: None,
            cursor: None,
            buttons: HashSet::new(),
            shift: false,
            ctrl: false,
            held: HashSet::new(),
            held_until: Vec::new(),
            script,
            script_stdin,
            script_ended: !script_stdin,
            waiting: None,
            proxy,
            outcome: Outcome::Closed,
            error: None,
        })
    }

    /// Creates the window, its surface and the drawing state.
    fn open(&mut self, el: &ActiveEventLoop) -> Result<(), ViewError> {
        let s = &self.controls.settings;
        let attributes = Window::default_attributes()
            .with_title(self.title.clone())
            .with_inner_size(PhysicalSize::new(s.width.max(1), s.height.max(1)));
        let window = Arc::new(el.create_window(attributes).map_err(|e| ViewError::NoDisplay(e.to_string()))?);
        let ctx = self.renderer.context();
        let surface = furnace_gpu::context::instance()
            .create_surface(window.clone())
            .map_err(|e| ViewError::Surface(format!("cannot draw into the window: {e}")))?;
        let caps = surface.get_capabilities(&ctx.adapter);
        // A non-sRGB 8-bit format: the shader encodes sRGB exactly as furnace-post does; an sRGB
        // one (the hardware encodes) only when that is all there is.
        let format = [wgpu::TextureFormat::Bgra8Unorm, wgpu::TextureFormat::Rgba8Unorm]
            .into_iter()
            .find(|f| caps.formats.contains(f))
            .or_else(|| caps.formats.first().copied())
            .ok_or_else(|| {
                ViewError::Surface(format!(
                    "the adapter {} cannot present to this window (no surface format); choose another with --adapter",
                    ctx.describe()
                ))
            })?;
        let size = window.inner_size();
        let config = wgpu::SurfaceConfiguration {
            usage: wgpu::TextureUsages::RENDER_ATTACHMENT,
            format,
            color_space: wgpu::SurfaceColorSpace::Auto,
            width: size.width.max(1),
            height: size.height.max(1),
            present_mode: wgpu::PresentMode::AutoVsync,
            desired_maximum_frame_latency: 2,
            alpha_mode: caps.alpha_modes.first().copied().unwrap_or(wgpu::CompositeAlphaMode::Auto),
            view_formats: vec![],
        };
        surface.configure(&ctx.device, &config);
        let presenter = FilmPresenter::new(ctx, self.renderer.film_precision(), format)?;
        let egui = egui::Context::default();
        let egui_state = egui_winit::State::new(
            egui.clone(),
            egui::ViewportId::ROOT,
            &window,
            Some(window.scale_factor() as f32),
            None,
            Some(ctx.device.limits().max_texture_dimension_2d as usize),
        );
        let egui_renderer =
            egui_wgpu::Renderer::new(&ctx.device, format, egui_wgpu::RendererOptions::default());
        self.win = Some(Window_ { window, surface, config, presenter, egui, egui_state, egui_renderer });
        if self.script_stdin {
            spawn_stdin_reader(self.proxy.clone());
        }
        Ok(())
    }

    fn request_redraw(&self) {
        if let Some(w) = &self.win {
            w.window.request_redraw();
        }
    }

    /// Whether more frames are wanted now (else the loop sleeps until an event).
    fn busy(&self) -> bool {
        // A timed wait wakes the loop at its end (`about_to_wait`), not every frame.
        let waiting = self.waiting.as_ref().is_some_and(|(_, w)| !matches!(w, Wait::Until(_)));
        self.accumulating()
            || !self.held.is_empty()
            || waiting
            || !self.script.is_empty()
            || self.hud.message_until.is_some_and(|t| t > Instant::now())
    }

    fn accumulating(&self) -> bool {
        !self.controls.paused
            && self.controls.target_spp.is_none_or(|t| self.spp < t)
            && self.time_limit.is_none_or(|t| self.render_seconds < t)
            && self.spp < u32::MAX - crate::budget::MAX_SAMPLES
    }

    fn interacted(&mut self) {
        self.last_input = Instant::now();
        self.request_redraw();
    }

    /// The film size for the window's inner size (the film follows the window unless fixed).
    fn film_size(&self) -> (u32, u32) {
        match (&self.win, self.fixed_size) {
            (Some(w), false) => (w.config.width.max(1), w.config.height.max(1)),
            _ => (self.controls.settings.width, self.controls.settings.height),
        }
    }

    /// Brings the renderer to the controls: settings, environment, film size, camera. A change
    /// restarts the accumulation.
    fn apply_changes(&mut self) -> Result<(), ViewError> {
        let (w, h) = self.film_size();
        self.controls.settings.width = w;
        self.controls.settings.height = h;
        let camera = self.rig.camera();
        let settings = self.controls.settings;
        let env_changed = self.controls.env_intensity != self.applied_env;
        if settings != self.applied || env_changed {
            if env_changed
                && let (Some(i), Some(env)) = (self.controls.env_intensity, self.scene.environment().cloned())
            {
                self.scene.set_environment(Some(furnace_scene::Environment { intensity: i, ..env }));
            }
            self.renderer.reconfigure(&self.scene, &camera, settings)?;
            if (settings.width, settings.height) != (self.applied.width, self.applied.height)
                || settings.bounces != self.applied.bounces
            {
                self.budget.forget();
            }
            self.applied = settings;
            self.applied_env = self.controls.env_intensity;
            self.applied_camera = camera;
            self.restart();
        } else if camera != self.applied_camera {
            self.renderer.set_camera(&camera);
            self.renderer.clear_film()?;
            self.applied_camera = camera;
            self.restart();
        }
        Ok(())
    }

    fn restart(&mut self) {
        self.spp = 0;
        self.resets += 1;
        self.render_seconds = 0.0;
        self.last_noise = None;
        self.hud.noise = None;
    }

    /// Restarts the accumulation without any change (R).
    fn reset(&mut self) -> Result<(), ViewError> {
        self.renderer.clear_film()?;
        self.restart();
        Ok(())
    }

    /// Renders this frame's samples.
    fn render(&mut self) -> Result<(), ViewError> {
        if !self.accumulating() {
            self.hud.rate = None;
            return Ok(());
        }
        let interactive = self.last_input.elapsed() < INTERACTIVE_FOR || !self.held.is_empty();
        let budget = if interactive { INTERACTIVE_SECONDS } else { STILL_SECONDS };
        // A script waiting for N samples gets exactly N (its next command sees that film).
        let stop = match self.waiting {
            Some((_, Wait::Spp(n))) if n > self.spp => self.controls.target_spp.map_or(n, |t| t.min(n)),
            _ => self.controls.target_spp.unwrap_or(u32::MAX),
        };
        let left = stop.saturating_sub(self.spp).max(1);
        let n = self.budget.samples(budget, left);
        let start = Instant::now();
        Integrator::render_pass(&mut self.renderer, self.spp, n)?;
        let seconds = start.elapsed().as_secs_f64();
        self.budget.record(n, seconds);
        self.spp += n;
        self.render_seconds += seconds;
        let s = &self.applied;
        let samples = f64::from(s.width) * f64::from(s.height) * f64::from(n);
        self.hud.rate = Some(samples / seconds.max(1e-9) / 1e6);
        self.hud.samples_per_frame = n;
        Ok(())
    }

    fn update_noise(&mut self) -> Result<(), ViewError> {
        let Some(est) = &self.noise else {
            return Ok(());
        };
        if self.last_noise.is_some_and(|t| t.elapsed() < NOISE_EVERY) {
            return Ok(());
        }
        self.last_noise = Some(Instant::now());
        self.hud.noise =
            est.estimate(self.renderer.context(), self.renderer.gpu_film())?.and_then(|e| e.relative());
        Ok(())
    }

    /// Handles one action of the keyboard, the panel or the script.
    fn act(&mut self, el: &ActiveEventLoop, action: Action) -> Result<(), ViewError> {
        match action {
            Action::Save(path) => {
                let message = self.save(path)?;
                println!("{message}");
                self.hud.say(message, MESSAGE_FOR);
            }
            Action::Reset => self.reset()?,
            Action::ResetCamera => self.rig.reset(),
            Action::PrintCamera => {
                let line = self.camera_line();
                println!("{line}");
                self.hud.say(line, MESSAGE_FOR);
            }
            Action::TogglePause => self.controls.paused = !self.controls.paused,
            Action::ToggleUi => self.controls.show_ui = !self.controls.show_ui,
            Action::ToggleHelp => self.controls.show_help = !self.controls.show_help,
            Action::Exposure(d) => self.controls.exposure = (self.controls.exposure + d).clamp(-20.0, 20.0),
            Action::Quit => el.exit(),
        }
        self.interacted();
        Ok(())
    }

    /// The camera as `furnace render` options.
    fn camera_line(&self) -> String {
        match self.pose() {
            CameraPose::Start => {
                "camera: the scene's (unmoved; `furnace render` renders it with the same --camera)".into()
            }
            CameraPose::LookAt { eye, target, up, yfov_degrees } => format!(
                "camera: --look-at {},{},{},{},{},{},{},{},{} --yfov {yfov_degrees}",
                eye.x, eye.y, eye.z, target.x, target.y, target.z, up.x, up.y, up.z
            ),
            CameraPose::MovedOrthographic => {
                "camera: a moved orthographic camera has no command-line form".into()
            }
        }
    }

    fn pose(&self) -> CameraPose {
        if !self.rig.moved() {
            return CameraPose::Start;
        }
        match self.rig.projection {
            Projection::Perspective { .. } => CameraPose::LookAt {
                eye: self.rig.eye,
                target: self.rig.target,
                up: self.rig.up,
                yfov_degrees: self.rig.yfov_degrees().unwrap_or(45.0),
            },
            Projection::Orthographic { .. } => CameraPose::MovedOrthographic,
        }
    }

    /// Reads the film back and hands it to the host.
    fn save(&mut self, path: Option<std::path::PathBuf>) -> Result<String, ViewError> {
        if self.spp == 0 {
            return Ok("nothing to save yet: no samples".into());
        }
        let film = Integrator::film(&mut self.renderer)?;
        let request = SaveRequest {
            film,
            spp: self.spp,
            seconds: self.render_seconds,
            settings: self.applied,
            camera: self.pose(),
            exposure: self.controls.exposure,
            tonemap: self.controls.tonemap,
            env_intensity: self.applied_env.filter(|_| self.applied_env != self.initial_env()),
            path,
            backend: self.renderer.context().describe(),
        };
        Ok(match self.host.save(&self.scene, request) {
            Ok(m) => m,
            Err(e) => format!("error: {e}"),
        })
    }

    /// The scene's environment intensity as loaded (before the viewer's slider).
    fn initial_env(&self) -> Option<f32> {
        self.hud.initial_env
    }

    /// One frame: input held, script, changes, a pass, the noise estimate, the drawing.
    fn frame(&mut self, el: &ActiveEventLoop) -> Result<(), ViewError> {
        if self.host.interrupted() {
            self.outcome = Outcome::Interrupted;
            el.exit();
            return Ok(());
        }
        let now = Instant::now();
        let dt = now.duration_since(self.last_frame).as_secs_f32();
        self.last_frame = now;
        let restarts = self.resets;
        self.fly(dt);
        self.step_script(el)?;
        self.apply_changes()?;
        self.render()?;
        self.update_noise()?;
        self.draw(el)?;
        self.frame += 1;
        // The frame's wall time (input to present): what the window's responsiveness is.
        let ms = now.elapsed().as_secs_f64() * 1e3;
        self.hud.frame_ms = ms;
        self.hud.max_frame_ms = if self.resets != restarts { ms } else { self.hud.max_frame_ms.max(ms) };
        // A script waiting for this frame count, or the end of accumulation, moves on now.
        self.step_script(el)?;
        if self.busy() {
            self.request_redraw();
        }
        Ok(())
    }

    /// Draws the film and the panels, and presents.
    fn draw(&mut self, el: &ActiveEventLoop) -> Result<(), ViewError> {
        let accumulating = self.accumulating();
        let Some(win) = &mut self.win else {
            return Ok(());
        };
        let ctx = self.renderer.context();
        let frame = match win.surface.get_current_texture() {
            wgpu::CurrentSurfaceTexture::Success(f) | wgpu::CurrentSurfaceTexture::Suboptimal(f) => f,
            wgpu::CurrentSurfaceTexture::Outdated | wgpu::CurrentSurfaceTexture::Lost => {
                win.surface.configure(&ctx.device, &win.config);
                return Ok(());
            }
            other => {
                // Timeout or occluded: skip this frame.
                let _ = other;
                return Ok(());
            }
        };
        let view = frame.texture.create_view(&Default::default());
        let hud = HudState {
            spp: self.spp,
            target: self.controls.target_spp,
            seconds: self.render_seconds,
            accumulating,
            film: (self.applied.width, self.applied.height),
        };
        let raw = win.egui_state.take_egui_input(&win.window);
        let mut actions = Vec::new();
        let mut output = win.egui.run_pass(raw, |c| {
            ui::draw(c, &mut self.controls, &self.hud, &hud, &mut actions);
        });
        win.egui_state.handle_platform_output(&win.window, output.platform_output);
        let ppp = output.pixels_per_point;
        let prims = win.egui.tessellate(output.shapes, ppp);
        // egui's texture changes: applied before painting, frees after (taken out of the
        // output at once, which must not be dropped with changes left in it).
        for (id, deltas) in output.textures_delta.set.drain() {
            for delta in &deltas {
                win.egui_renderer.update_texture(&ctx.device, &ctx.queue, id, delta);
            }
        }
        let freed: Vec<egui::TextureId> = output.textures_delta.free.drain().collect();
        let screen = egui_wgpu::ScreenDescriptor {
            size_in_pixels: [win.config.width, win.config.height],
            pixels_per_point: ppp,
        };
        let mut encoder = ctx.device.create_command_encoder(&Default::default());
        let extra = win.egui_renderer.update_buffers(&ctx.device, &ctx.queue, &mut encoder, &prims, &screen);
        let film = self.renderer.gpu_film();
        let placement = Placement::fit((film.width(), film.height()), (win.config.width, win.config.height));
        {
            let mut pass = encoder
                .begin_render_pass(&wgpu::RenderPassDescriptor {
                    label: Some("viewer"),
                    color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                        view: &view,
                        depth_slice: None,
                        resolve_target: None,
                        ops: wgpu::Operations {
                            load: wgpu::LoadOp::Clear(wgpu::Color::BLACK),
                            store: wgpu::StoreOp::Store,
                        },
                    })],
                    ..Default::default()
                })
                .forget_lifetime();
            win.presenter.draw(
                ctx,
                &mut pass,
                film,
                &placement,
                self.controls.exposure,
                self.controls.tonemap,
            )?;
            if self.controls.show_ui || self.controls.show_help {
                win.egui_renderer.render(&mut pass, &prims, &screen);
            }
        }
        ctx.queue.submit(extra.into_iter().chain([encoder.finish()]));
        win.window.pre_present_notify();
        ctx.queue.present(frame);
        for id in &freed {
            win.egui_renderer.free_texture(id);
        }
        if win.egui.has_requested_repaint() {
            win.window.request_redraw();
        }
        for a in actions {
            self.act(el, a)?;
        }
        Ok(())
    }

    fn fail(&mut self, el: &ActiveEventLoop, e: ViewError) {
        if self.error.is_none() {
            self.error = Some(e);
        }
        el.exit();
    }
}

/// What the HUD shows of the render (the rest is in [`Hud`]).
pub(crate) struct HudState {
    pub spp: u32,
    pub target: Option<u32>,
    pub seconds: f64,
    pub accumulating: bool,
    pub film: (u32, u32),
}

impl ApplicationHandler<UserEvent> for App<'_> {
    fn resumed(&mut self, el: &ActiveEventLoop) {
        if self.win.is_some() {
            return;
        }
        if let Err(e) = self.open(el) {
            self.fail(el, e);
            return;
        }
        el.set_control_flow(ControlFlow::Wait);
        self.request_redraw();
    }

    fn user_event(&mut self, el: &ActiveEventLoop, event: UserEvent) {
        match event {
            UserEvent::ScriptLine(Ok(line)) => self.script.push_back(line),
            UserEvent::ScriptLine(Err(e)) => self.fail(el, ViewError::Script(e)),
            UserEvent::ScriptEnd => self.script_ended = true,
        }
        self.request_redraw();
    }

    fn window_event(&mut self, el: &ActiveEventLoop, _id: WindowId, event: WindowEvent) {
        let Some(win) = &mut self.win else {
            return;
        };
        let response = win.egui_state.on_window_event(&win.window, &event);
        if response.repaint {
            win.window.request_redraw();
        }
        let egui_pointer = win.egui.egui_wants_pointer_input() || win.egui.is_pointer_over_egui();
        let egui_keys = win.egui.egui_wants_keyboard_input();
        let result = match event {
            WindowEvent::CloseRequested => {
                el.exit();
                Ok(())
            }
            // A minimised window (0 × 0) keeps its film and surface: nothing to draw into.
            WindowEvent::Resized(size) if size.width > 0 && size.height > 0 => {
                let ctx = self.renderer.context();
                win.config.width = size.width;
                win.config.height = size.height;
                win.surface.configure(&ctx.device, &win.config);
                self.interacted();
                Ok(())
            }
            WindowEvent::RedrawRequested => self.frame(el),
            WindowEvent::ModifiersChanged(m) => {
                self.shift = m.state().shift_key();
                self.ctrl = m.state().control_key();
                Ok(())
            }
            WindowEvent::KeyboardInput { event, .. }
                if !egui_keys || event.state == ElementState::Released =>
            {
                match key_name(&event.logical_key, self.ctrl) {
                    Some(name) if !event.repeat || fly_key(&name).is_some() => {
                        self.key(el, &name, event.state == ElementState::Pressed)
                    }
                    _ => Ok(()),
                }
            }
            WindowEvent::MouseInput { state, button, .. } => {
                match state {
                    ElementState::Pressed if !egui_pointer || response.consumed => {
                        if !response.consumed {
                            self.buttons.insert(button);
                        }
                    }
                    ElementState::Pressed => {}
                    ElementState::Released => {
                        self.buttons.remove(&button);
                    }
                }
                Ok(())
            }
            WindowEvent::CursorMoved { position, .. } => {
                let (x, y) = (position.x, position.y);
                if let Some((px, py)) = self.cursor {
                    let (dx, dy) = ((x - px) as f32, (y - py) as f32);
                    let button = if self.buttons.contains(&MouseButton::Left) {
                        Some(DragButton::Left)
                    } else if self.buttons.contains(&MouseButton::Middle) {
                        Some(DragButton::Middle)
                    } else if self.buttons.contains(&MouseButton::Right) {
                        Some(DragButton::Right)
                    } else {
                        None
                    };
                    if let Some(b) = button {
                        self.drag(b, dx, dy);
                    }
                }
                self.cursor = Some((x, y));
                Ok(())
            }
            WindowEvent::CursorLeft { .. } => {
                self.cursor = None;
                Ok(())
            }
            WindowEvent::MouseWheel { delta, .. } if !egui_pointer => {
                let steps = match delta {
                    MouseScrollDelta::LineDelta(_, y) => y,
                    MouseScrollDelta::PixelDelta(p) => (p.y / 40.0) as f32,
                };
                self.rig.dolly(steps);
                self.interacted();
                Ok(())
            }
            _ => Ok(()),
        };
        if let Err(e) = result {
            self.fail(el, e);
        }
    }

    fn about_to_wait(&mut self, el: &ActiveEventLoop) {
        if self.host.interrupted() {
            self.outcome = Outcome::Interrupted;
            el.exit();
        }
        // Wake now and then even when idle: Ctrl-C in the terminal is noticed within 100 ms; a
        // timed script wait or a held key's release at its time.
        let now = Instant::now();
        let mut wake = now + Duration::from_millis(100);
        if let Some((_, Wait::Until(t))) = &self.waiting {
            if *t <= now {
                self.request_redraw();
            }
            wake = wake.min(*t);
        }
        el.set_control_flow(ControlFlow::WaitUntil(wake));
    }
}
