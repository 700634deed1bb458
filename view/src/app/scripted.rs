//! The script: its commands run in order, each acknowledged on standard output once done,
//! waits included; standard input read as it comes.

use super::input::fly_key;
use super::{App, UserEvent};
use crate::ViewError;
use crate::script::{self, Command};
use crate::ui;
use std::time::{Duration, Instant};
use winit::dpi::PhysicalSize;
use winit::event_loop::{ActiveEventLoop, EventLoopProxy};

/// A scripted wait in progress.
#[derive(Debug, Clone, Copy)]
pub(super) enum Wait {
    Spp(u32),
    Frames(u64),
    Until(Instant),
}

impl App<'_> {
    /// Runs script commands until one has to wait.
    pub(super) fn step_script(&mut self, el: &ActiveEventLoop) -> Result<(), ViewError> {
        loop {
            if let Some((line, wait)) = self.waiting.clone() {
                let done = match wait {
                    Wait::Spp(n) => self.spp >= n || !self.accumulating(),
                    Wait::Frames(f) => self.frame >= f,
                    Wait::Until(t) => Instant::now() >= t,
                };
                if !done {
                    return Ok(());
                }
                self.waiting = None;
                self.ack(&line);
            }
            let Some(line) = self.script.pop_front() else {
                if self.script_ended && self.script_stdin {
                    // Standard input closed: the session is over.
                    el.exit();
                }
                return Ok(());
            };
            let wait = match &line.command {
                Command::WaitSpp(n) => Some(Wait::Spp(*n)),
                Command::WaitFrames(n) => Some(Wait::Frames(self.frame + u64::from(*n))),
                Command::WaitSeconds(s) => Some(Wait::Until(Instant::now() + Duration::from_secs_f64(*s))),
                Command::Drag { button, dx, dy } => {
                    self.drag(*button, *dx, *dy);
                    None
                }
                Command::Scroll(steps) => {
                    self.rig.dolly(*steps);
                    self.interacted();
                    None
                }
                Command::Key(name) => {
                    self.key(el, name, true)?;
                    self.key(el, name, false)?;
                    None
                }
                Command::Hold { key, seconds } => {
                    let c = fly_key(key).ok_or_else(|| {
                        ViewError::Script(format!(
                            "line {}: 'hold' takes a fly key (w a s d q e), not '{key}'",
                            line.number
                        ))
                    })?;
                    self.held.insert(c);
                    let until = Instant::now() + Duration::from_secs_f64(*seconds);
                    self.held_until.push((c, until));
                    Some(Wait::Until(until))
                }
                Command::Set { name, value } => {
                    ui::set(&mut self.controls, name, value)
                        .map_err(|e| ViewError::Script(format!("line {}: {e}", line.number)))?;
                    self.interacted();
                    None
                }
                Command::Save(path) => {
                    // Bring the film up to the commands before (a camera move, a setting).
                    self.apply_changes()?;
                    let message = self.save(path.clone())?;
                    println!("{message}");
                    if message.starts_with("error:") {
                        return Err(ViewError::Script(format!("line {}: {message}", line.number)));
                    }
                    None
                }
                Command::Resize(w, h) => {
                    if let Some(win) = &self.win {
                        let _ = win.window.request_inner_size(PhysicalSize::new(*w, *h));
                    }
                    // Acknowledged once the window has the size (or after a second).
                    Some(Wait::Until(Instant::now() + Duration::from_millis(500)))
                }
                Command::Print => {
                    println!("{}", self.state_line());
                    None
                }
                Command::Quit => {
                    self.ack(&line);
                    el.exit();
                    return Ok(());
                }
            };
            // The command's change (a camera move, a setting) takes effect now, so that a wait
            // after it counts the samples of the new film.
            self.apply_changes()?;
            match wait {
                Some(w) => self.waiting = Some((line, w)),
                None => self.ack(&line),
            }
        }
    }

    pub(super) fn state_line(&self) -> String {
        let s = &self.applied;
        format!(
            "state: spp={} resets={} frame={} size={}x{} bounces={} sampler={} exposure={} tonemap={} paused={} noise={} \
             frame_ms={:.2} max_frame_ms={:.2} spp_per_frame={} msamples_per_s={}",
            self.spp,
            self.resets,
            self.frame,
            s.width,
            s.height,
            s.bounces,
            s.sampler,
            self.controls.exposure,
            self.controls.tonemap,
            self.controls.paused,
            self.hud.noise.map_or_else(|| "-".to_string(), |n| format!("{n:.6}")),
            self.hud.frame_ms,
            self.hud.max_frame_ms,
            self.hud.samples_per_frame,
            self.hud.rate.map_or_else(|| "-".to_string(), |r| format!("{r:.1}")),
        )
    }

    pub(super) fn ack(&self, line: &script::Line) {
        println!("script: {} -> spp={} resets={} frame={}", line.text, self.spp, self.resets, self.frame);
        use std::io::Write;
        let _ = std::io::stdout().flush();
    }
}

/// Reads standard input line by line into the loop.
pub(super) fn spawn_stdin_reader(proxy: EventLoopProxy<UserEvent>) {
    std::thread::spawn(move || {
        use std::io::BufRead;
        let stdin = std::io::stdin();
        for (i, line) in stdin.lock().lines().enumerate() {
            let Ok(text) = line else { break };
            let event = match script::parse_line(&text) {
                Ok(None) => continue,
                Ok(Some(command)) => {
                    Ok(script::Line { number: i + 1, text: text.trim().to_string(), command })
                }
                Err(e) => Err(format!("<stdin>:{}: {e}", i + 1)),
            };
            if proxy.send_event(UserEvent::ScriptLine(event)).is_err() {
                return;
            }
        }
        let _ = proxy.send_event(UserEvent::ScriptEnd);
    });
}
