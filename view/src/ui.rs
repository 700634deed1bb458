//! The panels: the HUD, the settings, the help; and `set NAME VALUE`, the settings by name.

use crate::app::HudState;
use furnace_brdf::{Masking, SpecularSampling};
use furnace_post::Tonemap;
use furnace_render::{Choice, EnvSampling, LightSampling, LightSelection, RenderSettings, TriangleSampling};
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

const SAMPLERS: [SamplerKind; 5] = SamplerKind::ALL;
/// The panel's order of the masking functions (the default first).
const MASKINGS: [Masking; 2] = [Masking::HeightCorrelated, Masking::Separable];
/// The panel's order of the GGX sampling methods (the default first).
const SPECULAR_SAMPLINGS: [SpecularSampling; 3] =
    [SpecularSampling::SphericalCaps, SpecularSampling::Vndf, SpecularSampling::Ndf];

/// Sets control `name` to `value` (the script's `set`, with the command line's spellings).
///
/// # Errors
/// An unknown name or a value out of range, saying what is accepted.
pub(crate) fn set(c: &mut Controls, name: &str, value: &str) -> Result<(), String> {
    let on_off = |v: &str| match v {
        "on" | "true" | "1" => Ok(true),
        "off" | "false" | "0" => Ok(false),
        _ => Err(format!("{name}: '{v}' is not on or off")),
    };
    let number = |v: &str| {
        v.parse::<f32>()
            .ok()
            .filter(|x| x.is_finite())
            .ok_or_else(|| format!("{name}: '{v}' is not a number"))
    };
    let s = &mut c.settings;
    match name {
        "exposure" => c.exposure = number(value)?.clamp(-20.0, 20.0),
        "tonemap" => c.tonemap = value.parse().map_err(|e: furnace_post::PostError| e.to_string())?,
        "bounces" => {
            s.bounces = value.parse().ok().filter(|&b| b <= furnace_render::MAX_BOUNCES).ok_or_else(|| {
                format!("bounces: '{value}' is not a whole number from 0 to {}", furnace_render::MAX_BOUNCES)
            })?
        }
        "seed" => s.seed = value.parse().map_err(|_| format!("seed: '{value}' is not a whole number"))?,
        "sampler" => {
            let k: SamplerKind = value.parse().map_err(|e: furnace_sampling::SamplerError| e.to_string())?;
            set_sampler(c, k)?;
        }
        "masking" => {
            s.specular.masking = Masking::from_name(value)
                .ok_or_else(|| format!("masking: '{value}' (height-correlated or separable)"))?;
        }
        "compensation" => s.specular.compensation = on_off(value)?,
        "specular-sampling" => {
            s.specular.sampling = SpecularSampling::from_name(value)
                .ok_or_else(|| format!("specular-sampling: '{value}' (caps, vndf or ndf)"))?;
        }
        "russian-roulette" => s.russian_roulette = on_off(value)?,
        "light-sampling" => s.light_sampling = value.parse::<LightSampling>()?,
        "triangle-sampling" => s.triangle_sampling = value.parse::<TriangleSampling>()?,
        "light-selection" => s.light_selection = value.parse::<LightSelection>()?,
        "env-sampling" => s.env_sampling = value.parse::<EnvSampling>()?,
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
        "spp" => {
            c.target_spp = match value {
                "none" | "inf" => None,
                v => Some(
                    v.parse::<u32>()
                        .ok()
                        .filter(|n| *n > 0)
                        .ok_or_else(|| format!("spp: '{v}' (a positive whole number or none)"))?,
                ),
            };
            if s.sampler.needs_sample_count() {
                s.sample_count = c.target_spp;
                if c.target_spp.is_none() {
                    return Err(format!("spp: the {} sampler needs a sample count", s.sampler));
                }
            }
        }
        "pause" => c.paused = on_off(value)?,
        _ => {
            return Err(format!(
                "unknown setting '{name}' (exposure, tonemap, bounces, seed, sampler, masking, compensation, \
                 specular-sampling, russian-roulette, light-sampling, triangle-sampling, light-selection, \
                 env-sampling, env-intensity, spp, pause)"
            ));
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
    if !c.show_ui {
        return;
    }
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
            let s = &mut c.settings;
            ui.add(egui::Slider::new(&mut s.bounces, 0..=32).text("bounces"));
            let mut sampler = s.sampler;
            egui::ComboBox::from_label("sampler").selected_text(sampler.to_string()).show_ui(ui, |ui| {
                for k in SAMPLERS {
                    let enabled = !k.needs_sample_count() || c.target_spp.is_some();
                    ui.add_enabled_ui(enabled, |ui| ui.selectable_value(&mut sampler, k, k.to_string()));
                }
            });
            if sampler != c.settings.sampler {
                let _ = set_sampler(c, sampler);
            }
            let s = &mut c.settings;
            egui::ComboBox::from_label("masking").selected_text(s.specular.masking.name()).show_ui(
                ui,
                |ui| {
                    for m in MASKINGS {
                        ui.selectable_value(&mut s.specular.masking, m, m.name());
                    }
                },
            );
            egui::ComboBox::from_label("GGX sampling").selected_text(s.specular.sampling.name()).show_ui(
                ui,
                |ui| {
                    for m in SPECULAR_SAMPLINGS {
                        ui.selectable_value(&mut s.specular.sampling, m, m.name());
                    }
                },
            );
            ui.checkbox(&mut s.specular.compensation, "energy compensation");
            ui.checkbox(&mut s.russian_roulette, "Russian roulette");
            egui::ComboBox::from_label("light sampling").selected_text(s.light_sampling.to_string()).show_ui(
                ui,
                |ui| {
                    for k in LightSampling::ALL {
                        ui.selectable_value(&mut s.light_sampling, k, k.to_string());
                    }
                },
            );
            egui::ComboBox::from_label("light selection")
                .selected_text(s.light_selection.to_string())
                .show_ui(ui, |ui| {
                    for k in LightSelection::ALL {
                        ui.selectable_value(&mut s.light_selection, k, k.to_string());
                    }
                });
            egui::ComboBox::from_label("triangle sampling")
                .selected_text(s.triangle_sampling.to_string())
                .show_ui(ui, |ui| {
                    for k in TriangleSampling::ALL {
                        ui.selectable_value(&mut s.triangle_sampling, k, k.to_string());
                    }
                });
            if let Some(i) = &mut c.env_intensity {
                egui::ComboBox::from_label("env sampling").selected_text(s.env_sampling.to_string()).show_ui(
                    ui,
                    |ui| {
                        for k in EnvSampling::ALL {
                            ui.selectable_value(&mut s.env_sampling, k, k.to_string());
                        }
                    },
                );
                ui.add(egui::Slider::new(i, 0.0..=100.0).logarithmic(true).text("env intensity"));
            }
            ui.separator();
            ui.horizontal(|ui| {
                let mut unlimited = c.target_spp.is_none();
                if ui.checkbox(&mut unlimited, "no spp target").changed()
                    && !c.settings.sampler.needs_sample_count()
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
                if ui.button("save").clicked() {
                    actions.push(Action::Save(None));
                }
                if ui.button("restart").clicked() {
                    actions.push(Action::Reset);
                }
                if ui.button("scene camera").clicked() {
                    actions.push(Action::ResetCamera);
                }
                if ui.button("print camera").clicked() {
                    actions.push(Action::PrintCamera);
                }
                if ui.button("help").clicked() {
                    actions.push(Action::ToggleHelp);
                }
            });
        },
    );
}

#[cfg(test)]
mod tests {
    use super::*;

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
        assert!(set(&mut c, "bounces", "1025").unwrap_err().contains("0 to 1024"));
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
        assert!(set(&mut c, "bounce", "2").unwrap_err().contains("unknown setting 'bounce'"));
        assert!(set(&mut c, "compensation", "maybe").unwrap_err().contains("not on or off"));
        assert!(set(&mut c, "env-intensity", "-1").unwrap_err().contains("negative"));
        c.env_intensity = None;
        assert!(set(&mut c, "env-intensity", "1").unwrap_err().contains("no environment map"));
    }
}
