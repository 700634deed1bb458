//! `--script`: the viewer driven by a file (or standard input) of commands, one per line, each
//! acknowledged on standard output once done — for tests, demos and reproducible sessions.
//!
//! Commands feed the same handlers as the mouse, the keyboard and the settings panel:
//!
//! | command | does |
//! |---|---|
//! | `wait-spp N` | waits until the film has N samples per pixel (or accumulation stops) |
//! | `wait-frames N` | waits N frames |
//! | `wait-seconds S` | waits S seconds |
//! | `drag left\|middle\|right DX DY` | a mouse drag of DX, DY pixels (left orbits, middle pans, right looks) |
//! | `scroll STEPS` | the wheel (positive: towards the pivot) |
//! | `key NAME` | presses and releases a key of the help (`r`, `ctrl+s`, `space`, `home`, `?`, …) |
//! | `hold NAME SECONDS` | holds a key (fly: `w`, `a`, `s`, `d`, `q`, `e`) for that long |
//! | `set NAME VALUE` | a setting of the panel (`exposure 1.5`, `tonemap clamp`, `bounces 2`, …) |
//! | `save [PATH]` | saves the film as `ctrl+s` does (to PATH.exr / PATH.png if given) |
//! | `resize W H` | asks the window for an inner size of W × H pixels |
//! | `print` | prints the state |
//! | `quit` | closes the viewer |
//!
//! Blank lines and `#` comments are skipped. Every command prints one line
//! `script: <command> -> spp=<n> resets=<k> frame=<f>` when done.

use std::path::PathBuf;

/// A mouse button of a scripted drag.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum DragButton {
    /// Orbit.
    Left,
    /// Pan.
    Middle,
    /// Look around (fly mode).
    Right,
}

/// One command of a script.
#[derive(Debug, Clone, PartialEq)]
pub enum Command {
    /// Until the film has this many samples per pixel.
    WaitSpp(u32),
    /// This many frames.
    WaitFrames(u32),
    /// This many seconds.
    WaitSeconds(f64),
    /// A mouse drag.
    Drag {
        /// The button.
        button: DragButton,
        /// Pixels right.
        dx: f32,
        /// Pixels down.
        dy: f32,
    },
    /// Wheel steps.
    Scroll(f32),
    /// A key pressed and released.
    Key(String),
    /// A key held.
    Hold {
        /// The key.
        key: String,
        /// For this long.
        seconds: f64,
    },
    /// A setting.
    Set {
        /// Its name.
        name: String,
        /// Its value, as typed.
        value: String,
    },
    /// Save the film (to this path instead of `--out`).
    Save(Option<PathBuf>),
    /// Resize the window.
    Resize(u32, u32),
    /// Print the state.
    Print,
    /// Close the viewer.
    Quit,
}

/// A command with where it came from.
#[derive(Debug, Clone, PartialEq)]
pub struct Line {
    /// 1-based line number.
    pub number: usize,
    /// The line as written (trimmed).
    pub text: String,
    /// The command.
    pub command: Command,
}

/// Parses one line; `Ok(None)` for a blank line or a comment.
///
/// # Errors
/// What is wrong with the line, naming the command.
pub fn parse_line(text: &str) -> Result<Option<Command>, String> {
    let text = text.split('#').next().unwrap_or("").trim();
    if text.is_empty() {
        return Ok(None);
    }
    let words: Vec<&str> = text.split_whitespace().collect();
    let (name, args) = (words[0], &words[1..]);
    let want = |n: usize, usage: &str| {
        if args.len() == n { Ok(()) } else { Err(format!("'{name}' takes {n} argument(s): {usage}")) }
    };
    let num = |s: &str| -> Result<f64, String> {
        s.parse::<f64>()
            .ok()
            .filter(|v| v.is_finite())
            .ok_or_else(|| format!("'{name}': '{s}' is not a finite number"))
    };
    let count = |s: &str| -> Result<u32, String> {
        s.parse::<u32>().map_err(|_| format!("'{name}': '{s}' is not a whole number"))
    };
    let command = match name {
        "wait-spp" => {
            want(1, "wait-spp N")?;
            Command::WaitSpp(count(args[0])?)
        }
        "wait-frames" => {
            want(1, "wait-frames N")?;
            Command::WaitFrames(count(args[0])?)
        }
        "wait-seconds" => {
            want(1, "wait-seconds S")?;
            Command::WaitSeconds(num(args[0])?.max(0.0))
        }
        "drag" => {
            want(3, "drag left|middle|right DX DY")?;
            let button = match args[0] {
                "left" => DragButton::Left,
                "middle" => DragButton::Middle,
                "right" => DragButton::Right,
                b => return Err(format!("'drag': unknown button '{b}' (left, middle or right)")),
            };
            Command::Drag { button, dx: num(args[1])? as f32, dy: num(args[2])? as f32 }
        }
        "scroll" => {
            want(1, "scroll STEPS")?;
            Command::Scroll(num(args[0])? as f32)
        }
        "key" => {
            want(1, "key NAME")?;
            Command::Key(args[0].to_string())
        }
        "hold" => {
            want(2, "hold NAME SECONDS")?;
            Command::Hold { key: args[0].to_string(), seconds: num(args[1])?.max(0.0) }
        }
        "set" => {
            want(2, "set NAME VALUE")?;
            Command::Set { name: args[0].to_string(), value: args[1].to_string() }
        }
        "save" => match args {
            [] => Command::Save(None),
            [p] => Command::Save(Some(PathBuf::from(p))),
            _ => return Err("'save' takes at most one argument: save [PATH]".into()),
        },
        "resize" => {
            want(2, "resize W H")?;
            let (w, h) = (count(args[0])?, count(args[1])?);
            if w == 0 || h == 0 {
                return Err("'resize': the size must be at least 1 × 1".into());
            }
            Command::Resize(w, h)
        }
        "print" => {
            want(0, "print")?;
            Command::Print
        }
        "quit" => {
            want(0, "quit")?;
            Command::Quit
        }
        other => {
            return Err(format!(
                "unknown command '{other}' (wait-spp, wait-frames, wait-seconds, drag, scroll, key, hold, set, \
                 save, resize, print, quit)"
            ));
        }
    };
    Ok(Some(command))
}

/// Parses a whole script; errors name `source` and the line.
///
/// # Errors
/// The first bad line.
pub fn parse(source: &str, text: &str) -> Result<Vec<Line>, String> {
    let mut out = Vec::new();
    for (i, raw) in text.lines().enumerate() {
        match parse_line(raw) {
            Ok(Some(command)) => out.push(Line { number: i + 1, text: raw.trim().to_string(), command }),
            Ok(None) => {}
            Err(e) => return Err(format!("{source}:{}: {e}", i + 1)),
        }
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parses_every_command() {
        let s = "# a test\nwait-spp 16\ndrag left 120 -4.5\nscroll -2\nkey ctrl+s\nhold w 0.5\n\nset exposure 1.5 # brighter\nsave out/a\nresize 320 200\nprint\nquit\n";
        let lines = parse("t.txt", s).unwrap();
        let cmds: Vec<_> = lines.iter().map(|l| l.command.clone()).collect();
        assert_eq!(
            cmds,
            vec![
                Command::WaitSpp(16),
                Command::Drag { button: DragButton::Left, dx: 120.0, dy: -4.5 },
                Command::Scroll(-2.0),
                Command::Key("ctrl+s".into()),
                Command::Hold { key: "w".into(), seconds: 0.5 },
                Command::Set { name: "exposure".into(), value: "1.5".into() },
                Command::Save(Some("out/a".into())),
                Command::Resize(320, 200),
                Command::Print,
                Command::Quit,
            ]
        );
        assert_eq!(lines[0].number, 2);
    }

    #[test]
    fn bad_lines_name_the_file_and_line() {
        let e = parse("s.txt", "wait-spp 4\ndrag up 1 2\n").unwrap_err();
        assert!(e.starts_with("s.txt:2: 'drag': unknown button 'up'"), "{e}");
        let e = parse("s.txt", "wait-spp\n").unwrap_err();
        assert!(e.contains("s.txt:1: 'wait-spp' takes 1 argument"), "{e}");
        let e = parse("s.txt", "scroll nan\n").unwrap_err();
        assert!(e.contains("not a finite number"), "{e}");
        let e = parse("s.txt", "jump\n").unwrap_err();
        assert!(e.contains("unknown command 'jump'"), "{e}");
    }
}
