//! Input: keys, drags and the fly keys, from the window or a script.

use super::App;
use crate::ViewError;
use crate::script::DragButton;
use crate::ui::Action;
use std::time::Instant;
use winit::event_loop::ActiveEventLoop;
use winit::keyboard::{Key, NamedKey};

impl App<'_> {
    /// Keys: actions on press; fly keys held.
    pub(super) fn key(&mut self, el: &ActiveEventLoop, name: &str, pressed: bool) -> Result<(), ViewError> {
        if let Some(c) = fly_key(name) {
            if pressed {
                self.held.insert(c);
            } else {
                self.held.remove(&c);
            }
            self.interacted();
            return Ok(());
        }
        if !pressed {
            return Ok(());
        }
        let action = match name {
            "ctrl+s" => Action::Save(None),
            "r" => Action::Reset,
            "home" => Action::ResetCamera,
            "c" => Action::PrintCamera,
            "space" => Action::TogglePause,
            "tab" => Action::ToggleUi,
            "?" | "f1" => Action::ToggleHelp,
            "[" => Action::Exposure(-0.5),
            "]" => Action::Exposure(0.5),
            "escape" => Action::Quit,
            _ => return Ok(()),
        };
        self.act(el, action)
    }

    /// A drag of `dx`, `dy` pixels with `button` (Shift + left pans).
    pub(super) fn drag(&mut self, button: DragButton, dx: f32, dy: f32) {
        let height = self.win.as_ref().map_or(self.applied.height, |w| w.config.height);
        match button {
            DragButton::Left if self.shift => self.rig.pan(dx, dy, height),
            DragButton::Left => self.rig.orbit(dx, dy),
            DragButton::Middle => self.rig.pan(dx, dy, height),
            DragButton::Right => self.rig.look(dx, dy),
        }
        self.interacted();
    }

    /// Moves the camera by the fly keys held, for `seconds`.
    pub(super) fn fly(&mut self, seconds: f32) {
        let now = Instant::now();
        let released: Vec<char> =
            self.held_until.iter().filter(|(_, t)| *t <= now).map(|(c, _)| *c).collect();
        self.held_until.retain(|(_, t)| *t > now);
        for c in released {
            self.held.remove(&c);
        }
        if self.held.is_empty() {
            return;
        }
        let axis = |plus: char, minus: char| {
            f32::from(u8::from(self.held.contains(&plus))) - f32::from(u8::from(self.held.contains(&minus)))
        };
        let (f, r, u) = (axis('w', 's'), axis('d', 'a'), axis('e', 'q'));
        self.rig.fly(f, r, u, seconds.min(0.1), self.shift);
        self.last_input = now;
    }
}

/// The key names of the help (and of the script's `key` / `hold`).
pub(super) fn key_name(key: &Key, ctrl: bool) -> Option<String> {
    let base = match key {
        Key::Named(NamedKey::Space) => "space".to_string(),
        Key::Named(NamedKey::Escape) => "escape".to_string(),
        Key::Named(NamedKey::Home) => "home".to_string(),
        Key::Named(NamedKey::Tab) => "tab".to_string(),
        Key::Named(NamedKey::F1) => "f1".to_string(),
        Key::Character(c) => c.to_lowercase(),
        _ => return None,
    };
    Some(if ctrl { format!("ctrl+{base}") } else { base })
}

/// The fly keys: forward, left, back, right, down, up.
pub(super) fn fly_key(name: &str) -> Option<char> {
    match name {
        "w" | "a" | "s" | "d" | "q" | "e" => name.chars().next(),
        _ => None,
    }
}
