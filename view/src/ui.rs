//! The panels: the HUD, the settings, the help; and `set NAME VALUE`, the settings by name.

use crate::app::HudState;
use furnace_post::Tonemap;
use furnace_render::RenderSettings;
use furnace_render::fields::{self, FIELDS, Field};
use furnace_sampling::SamplerKind;
use std::path::PathBuf;
use std::time::{Duration, Instant};

/// What the user can change: the estimator's settings (a change restarts the accumulation) and
/// the display's (a change does not).
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Controls {
    /// The estimator's settings (the film's size is the window's or fixed).
    pub settings: RenderSettings,
    /// The environment's intensity (`None`: the scene has no environment map).
    pub env_intensity: Option<f32>,
    /// Exposure in EV (display).
    pub exposure: f32,
    /// Tone map (display).
    pub tonemap: Tonemap,
    /// Stop at this many samples per pixel.
    pub target_spp: Option<u32>,
    /// Accumulation paused.
    pub paused: bool,
    /// Panels shown.
    pub show_ui: bool,
    /// Help shown.
    pub show_help: bool,
}

/// What a key, a button or a script line asks for.
#[derive(Debug, Clone, PartialEq)]
pub(crate) enum Action {
    Save(Option<PathBuf>),
    Reset,
    ResetCamera,
    PrintCamera,
    TogglePause,
    ToggleUi,
    ToggleHelp,
    Exposure(f32),
    Quit,
}

/// The HUD's measurements and message.
#[derive(Debug, Clone)]
pub(crate) struct Hud {
    /// The adapter.
    pub adapter: String,
    /// Msamples/s of the last pass.
    pub rate: Option<f64>,
    /// Samples per pixel of the last frame.
    pub samples_per_frame: u32,
    /// Relative noise estimate.
    pub noise: Option<f64>,
    /// The scene's environment intensity as loaded.
    pub initial_env: Option<f32>,
    /// The last frame's wall time, and the longest since the accumulation restarted (ms).
    pub frame_ms: f64,
    pub max_frame_ms: f64,
    /// A message and until when it shows.
    pub message: String,
    pub message_until: Option<Instant>,
}

impl Hud {
    pub fn new(adapter: String) -> Self {
        Self {
            adapter,
            rate: None,
            samples_per_frame: 0,
            noise: None,
            initial_env: None,
            frame_ms: 0.0,
            max_frame_ms: 0.0,
            message: String::new(),
            message_until: None,
        }
    }

    pub fn say(&mut self, message: String, duration: Duration) {
        self.message = message;
        self.message_until = Some(Instant::now() + duration);
    }
}

/// The names `set` takes besides the render settings' flags (`furnace_render::fields::FIELDS`):
/// the display's, the environment's intensity, the target and the pause.
pub(crate) const VIEWER_SETTINGS: [&str; 5] = ["exposure", "tonemap", "env-intensity", "spp", "pause"];

/// Sets control `name` to `value` (the script's `set`, with the command line's spellings): a
/// render setting by its flag, through its row of `furnace_render::fields::FIELDS`, or one of
/// [`VIEWER_SETTINGS`].
///
/// # Errors
/// An unknown name or a value out of range, saying what is accepted.
pub(crate) fn set(c: &mut Controls, name: &str, value: &str) -> Result<(), String> {
    let number = |v: &str| {
        v.parse::<f32>()
            .ok()
            .filter(|x| x.is_finite())
            .ok_or_else(|| format!("{name}: '{v}' is not a number"))
    };
    match name {
        "exposure" => c.exposure = number(value)?.clamp(-20.0, 20.0),
        "tonemap" => c.tonemap = value.parse().map_err(|e: furnace_post::PostError| e.to_string())?,
        "env-intensity" => {
            let v = number(value)?;
            if c.env_intensity.is_none() {
                return Err("env-intensity: the scene has no environment map".into());
            }
            if !(v >= 0.0) {
                return Err(format!("env-intensity: {v} is negative"));
            }
            c.env_intensity = Some(v);
        }
        "spp" => set_target(c, value)?,
        "pause" => {
            c.paused = match value {
                "on" | "true" | "1" => true,
                "off" | "false" | "0" => false,
                _ => return Err(format!("pause: '{value}' is not on or off")),
            }
        }
        _ => {
            let Some(f) = fields::field(name) else {
                let names: Vec<&str> =
                    VIEWER_SETTINGS.iter().copied().chain(FIELDS.iter().map(|f| f.flag)).collect();
                return Err(format!("unknown setting '{name}' ({})", names.join(", ")));
            };
            // Parsed and checked by the field, on a copy: the sampler is then chosen by the
            // viewer's rule (the fixed-N ones take the target as N).
            let mut s = c.settings;
            (f.set)(&mut s, value).map_err(|e| format!("{name}: {e}"))?;
            if name == "sampler" {
                set_sampler(c, s.sampler)?;
            } else {
                c.settings = s;
            }
        }
    }
    Ok(())
}

/// `set spp N|none`: the target, which is also N of a fixed-N sampler.
fn set_target(c: &mut Controls, value: &str) -> Result<(), String> {
    c.target_spp = match value {
        "none" | "inf" => None,
        v => Some(
            v.parse::<u32>()
                .ok()
                .filter(|n| *n > 0)
                .ok_or_else(|| format!("spp: '{v}' (a positive whole number or none)"))?,
        ),
    };
    let s = &mut c.settings;
    if s.sampler.needs_sample_count() {
        s.sample_count = c.target_spp;
        if c.target_spp.is_none() {
            return Err(format!("spp: the {} sampler needs a sample count", s.sampler));
        }
    }
    Ok(())
}

/// Chooses a sampler; the fixed-N ones (hammersley, cmj) take the target spp as N.
fn set_sampler(c: &mut Controls, k: SamplerKind) -> Result<(), String> {
    if k.needs_sample_count() {
        let Some(n) = c.target_spp else {
            return Err(format!(
                "the {k} sampler builds one pattern of N samples per pixel: set a target (spp) first"
            ));
        };
        c.settings.sample_count = Some(n);
    } else {
        c.settings.sample_count = None;
    }
    c.settings.sampler = k;
    Ok(())
}

/// The help's lines: input, what it does.
pub(crate) const HELP: &[(&str, &str)] = &[
    ("left drag", "orbit about the pivot"),
    ("middle drag / Shift + left drag", "pan"),
    ("wheel", "dolly towards / away from the pivot"),
    ("right drag", "look around"),
    ("W A S D, Q E (Shift: faster)", "fly forward, left, back, right, down, up"),
    ("Home", "back to the scene's camera"),
    ("R", "restart the accumulation"),
    ("Space", "pause / continue"),
    ("Ctrl+S", "save EXR + PNG (as furnace render)"),
    ("C", "print the camera as command-line options"),
    ("[ / ]", "exposure -/+ 1/2 EV"),
    ("Tab", "hide / show the panels"),
    ("? or F1", "this help"),
    ("Esc", "quit"),
];

fn fmt_seconds(s: f64) -> String {
    if s < 60.0 { format!("{s:.1} s") } else { format!("{}:{:04.1}", (s / 60.0) as u64, s % 60.0) }
}

/// Draws the panels; buttons push actions.
pub(crate) fn draw(
    ctx: &egui::Context,
    c: &mut Controls,
    hud: &Hud,
    state: &HudState,
    actions: &mut Vec<Action>,
) {
    if c.show_help {
        draw_help(ctx);
    }
    if !c.show_ui {
        return;
    }
    draw_status(ctx, c, hud, state);
    egui::Window::new("settings").anchor(egui::Align2::RIGHT_TOP, [-8.0, 8.0]).default_open(false).show(
        ctx,
        |ui| {
            ui.heading("display");
            ui.add(egui::Slider::new(&mut c.exposure, -10.0..=10.0).text("exposure (EV)"));
            egui::ComboBox::from_label("tone map").selected_text(c.tonemap.name()).show_ui(ui, |ui| {
                for t in Tonemap::ALL {
                    ui.selectable_value(&mut c.tonemap, t, t.name());
                }
            });
            ui.separator();
            ui.heading("render (restarts)");
            render_settings(ui, c);
            ui.separator();
            accumulation(ui, c, state, actions);
        },
    );
}

/// The help window: the input of each action.
fn draw_help(ctx: &egui::Context) {
    egui::Window::new("Help").collapsible(false).anchor(egui::Align2::CENTER_CENTER, [0.0, 0.0]).show(
        ctx,
        |ui| {
            egui::Grid::new("help").striped(true).show(ui, |ui| {
                for (k, what) in HELP {
                    ui.monospace(*k);
                    ui.label(*what);
                    ui.end_row();
                }
            });
        },
    );
}

/// The HUD: samples, speed, frame and render time, noise, film size and adapter, message.
fn draw_status(ctx: &egui::Context, c: &Controls, hud: &Hud, state: &HudState) {
    egui::Window::new("furnace")
        .anchor(egui::Align2::LEFT_TOP, [8.0, 8.0])
        .resizable(false)
        .collapsible(true)
        .show(ctx, |ui| {
            let target = state.target.map_or_else(|| "∞".to_string(), |t| t.to_string());
            let status = if c.paused {
                " (paused)"
            } else if !state.accumulating {
                " (done)"
            } else {
                ""
            };
            ui.label(format!("{} / {target} spp{status}", state.spp));
            if let Some(r) = hud.rate {
                ui.label(format!("{r:.1} Msamples/s · {} spp/frame", hud.samples_per_frame));
            }
            ui.label(format!("frame {:.1} ms", hud.frame_ms));
            ui.label(format!("time {}", fmt_seconds(state.seconds)));
            ui.label(match hud.noise {
                Some(n) => format!("noise ≈ {:.2} % (rel. std. error)", 100.0 * n),
                None => "noise: —".to_string(),
            });
            ui.label(format!("{}×{} · {}", state.film.0, state.film.1, hud.adapter));
            if hud.message_until.is_some_and(|t| t > Instant::now()) {
                ui.separator();
                ui.label(&hud.message);
            }
        });
}

/// The panel's most bounces: fewer than the command line's, so that the slider stays usable
/// (`set bounces N` takes up to [`furnace_render::MAX_BOUNCES`]).
const PANEL_MAX_BOUNCES: u32 = 32;

/// The render settings: the bounces, the sampler (the fixed-N ones only with a target), a
/// widget for every choice of `FIELDS` (a checkbox for an on/off switch, else a combo box;
/// the environment sampling only when the scene has an environment map), and the
/// environment's intensity.
fn render_settings(ui: &mut egui::Ui, c: &mut Controls) {
    ui.add(egui::Slider::new(&mut c.settings.bounces, 0..=PANEL_MAX_BOUNCES).text("bounces"));
    sampler_choice(ui, c);
    for f in FIELDS.iter().filter(|f| f.flag != "sampler") {
        if f.flag == "env-sampling" && c.env_intensity.is_none() {
            continue;
        }
        choice_widget(ui, &mut c.settings, f);
    }
    if let Some(i) = &mut c.env_intensity {
        ui.add(egui::Slider::new(i, 0.0..=100.0).logarithmic(true).text("env intensity"));
    }
}

/// The sampler's combo box: the fixed-N samplers are offered only with a target (their N).
fn sampler_choice(ui: &mut egui::Ui, c: &mut Controls) {
    let mut sampler = c.settings.sampler;
    egui::ComboBox::from_label("sampler").selected_text(sampler.to_string()).show_ui(ui, |ui| {
        for k in SamplerKind::ALL {
            let enabled = !k.needs_sample_count() || c.target_spp.is_some();
            ui.add_enabled_ui(enabled, |ui| ui.selectable_value(&mut sampler, k, k.to_string()));
        }
    });
    if sampler != c.settings.sampler {
        let _ = set_sampler(c, sampler);
    }
}

/// The widget of field `f` if it takes named values (nothing for a number): labelled by its
/// name, showing its value (`get`) and setting the one chosen (`set`).
fn choice_widget(ui: &mut egui::Ui, settings: &mut RenderSettings, f: &Field) {
    let choices = (f.choices)();
    if choices.is_empty() {
        return;
    }
    let current = (f.get)(settings).unwrap_or_default();
    let mut chosen = current.clone();
    if choices == furnace_render::on_off() {
        let mut on = current == "on";
        ui.checkbox(&mut on, f.name).on_hover_text(f.help);
        chosen = furnace_render::on_off_name(on).to_string();
    } else {
        egui::ComboBox::from_label(f.name).selected_text(current.as_str()).show_ui(ui, |ui| {
            for (name, help) in choices {
                ui.selectable_value(&mut chosen, name.to_string(), name).on_hover_text(help);
            }
        });
    }
    if chosen != current {
        // A value of the field's own list: its `set` takes it.
        let _ = (f.set)(settings, &chosen);
    }
}

/// The target, the pause and the buttons.
fn accumulation(ui: &mut egui::Ui, c: &mut Controls, state: &HudState, actions: &mut Vec<Action>) {
    ui.horizontal(|ui| {
        let mut unlimited = c.target_spp.is_none();
        if ui.checkbox(&mut unlimited, "no spp target").changed() && !c.settings.sampler.needs_sample_count()
        {
            c.target_spp = if unlimited { None } else { Some(state.spp.max(1024)) };
        }
        if let Some(t) = &mut c.target_spp
            && !c.settings.sampler.needs_sample_count()
        {
            ui.add(egui::DragValue::new(t).range(1..=1 << 24).suffix(" spp"));
        }
    });
    ui.checkbox(&mut c.paused, "paused");
    ui.horizontal(|ui| {
        let buttons = [
            ("save", Action::Save(None)),
            ("restart", Action::Reset),
            ("scene camera", Action::ResetCamera),
            ("print camera", Action::PrintCamera),
            ("help", Action::ToggleHelp),
        ];
        for (label, action) in buttons {
            if ui.button(label).clicked() {
                actions.push(action);
            }
        }
    });
}

#[cfg(test)]
mod tests {
    use super::*;
    use furnace_brdf::Masking;
    use furnace_render::LightSampling;

    fn controls() -> Controls {
        Controls {
            settings: RenderSettings::default(),
            env_intensity: Some(1.0),
            exposure: 0.0,
            tonemap: Tonemap::Aces,
            target_spp: None,
            paused: false,
            show_ui: true,
            show_help: false,
        }
    }

    #[test]
    fn set_changes_the_named_control_with_the_command_line_spellings() {
        let mut c = controls();
        set(&mut c, "exposure", "1.5").unwrap();
        set(&mut c, "tonemap", "pbr-neutral").unwrap();
        assert!(set(&mut c, "bounces", "1025").unwrap_err().contains("at most 1024"));
        set(&mut c, "bounces", "2").unwrap();
        set(&mut c, "masking", "separable").unwrap();
        set(&mut c, "compensation", "off").unwrap();
        set(&mut c, "light-sampling", "nee").unwrap();
        set(&mut c, "env-intensity", "0.25").unwrap();
        assert_eq!((c.exposure, c.tonemap), (1.5, Tonemap::PbrNeutral));
        let s = c.settings;
        assert_eq!((s.bounces, s.specular.masking, s.specular.compensation), (2, Masking::Separable, false));
        assert_eq!((s.light_sampling, c.env_intensity), (LightSampling::Nee, Some(0.25)));
    }

    #[test]
    fn fixed_n_samplers_need_a_target_and_take_it_as_n() {
        let mut c = controls();
        let e = set(&mut c, "sampler", "hammersley").unwrap_err();
        assert!(e.contains("set a target"), "{e}");
        set(&mut c, "spp", "64").unwrap();
        set(&mut c, "sampler", "hammersley").unwrap();
        assert_eq!((c.settings.sampler, c.settings.sample_count), (SamplerKind::Hammersley, Some(64)));
        set(&mut c, "sampler", "sobol").unwrap();
        assert_eq!(c.settings.sample_count, None);
    }

    #[test]
    fn bad_settings_say_what_is_accepted() {
        let mut c = controls();
        let e = set(&mut c, "bounce", "2").unwrap_err();
        assert!(
            e.contains("unknown setting 'bounce'") && e.contains("light-sampling, triangle-sampling"),
            "{e}"
        );
        assert!(set(&mut c, "bounces", "x").unwrap_err().starts_with("bounces: 'x' is not a whole number"));
        assert!(set(&mut c, "compensation", "maybe").unwrap_err().contains("not on or off"));
        assert!(set(&mut c, "env-intensity", "-1").unwrap_err().contains("negative"));
        c.env_intensity = None;
        assert!(set(&mut c, "env-intensity", "1").unwrap_err().contains("no environment map"));
    }

    /// Every render setting's flag is a name of `set`, taking the command line's default; the
    /// optional ones (no default: the clamp, the noise threshold) a number, and off unsets them.
    /// Each sets what the field itself sets, and every name the unknown-setting error lists is
    /// taken.
    #[test]
    fn set_takes_every_field_of_the_table() {
        for f in FIELDS {
            let value = f.default.unwrap_or("0.5");
            let mut c = controls();
            set(&mut c, f.flag, value).unwrap_or_else(|e| panic!("set {} {value}: {e}", f.flag));
            let mut expected = RenderSettings::default();
            (f.set)(&mut expected, value).unwrap();
            assert_eq!(c.settings, expected, "{}", f.flag);
            if f.default.is_none() {
                set(&mut c, f.flag, "off").unwrap();
                assert_eq!(c.settings, RenderSettings::default(), "set {} off", f.flag);
            }
        }
        let e = set(&mut controls(), "no-such-setting", "1").unwrap_err();
        let listed = e.split_once('(').unwrap().1.trim_end_matches(')');
        for name in listed.split(", ") {
            let value = match name {
                "tonemap" => "aces",
                n => fields::field(n).and_then(|f| f.default).unwrap_or("1"),
            };
            set(&mut controls(), name, value).unwrap_or_else(|e| panic!("set {name} {value}: {e}"));
        }
        assert_eq!(listed.split(", ").count(), VIEWER_SETTINGS.len() + FIELDS.len());
    }
}
