//! Scripted input (`demo --script FILE`): timed events for tests and reproducible runs,
//! since synthetic window-system input is not always available. One event a line,
//! `FRAME EVENT ARGS…`, applied before frame FRAME (counted from 0) is drawn; `#` starts a comment.
//!
//! - `key NAME`: a key press as from the keyboard (`M`, `R`, `F12`, `1`…`5`, `V`, …);
//! - `move DX DY DZ`: the camera moves by this many metres;
//! - `turn YAW PITCH`: the camera turns by these many radians;
//! - `budget SHARE`: the live reference's share of the frame time (0 switches it off);
//! - `split FRACTION`: the split view's divider;
//! - `screenshot PATH`: saves the view on screen as PATH (PNG) and its values beside it (EXR);
//! - `param NAME VALUE`: sets a parameter of the configuration in the panel (`NAME` or
//!   `METHOD.NAME`, the value as TOML) and applies it, as the Apply button does;
//! - `minimise`, `restore`: the resize events a window system sends when the window is
//!   minimised (to no area) and restored.

use std::path::{Path, PathBuf};

use crate::error::{Error, Result};

#[derive(Clone, Debug, PartialEq)]
pub enum Event {
    Key(String),
    Move([f32; 3]),
    Turn([f32; 2]),
    Budget(f32),
    Split(f32),
    Screenshot(PathBuf),
    /// A parameter's name and its value (TOML text).
    Param(String, String),
    Minimise,
    Restore,
}

#[derive(Clone, Debug, Default, PartialEq)]
pub struct Script {
    /// (frame, event) in file order.
    pub events: Vec<(u64, Event)>,
}

impl Script {
    pub fn load(path: &Path) -> Result<Script> {
        let text = std::fs::read_to_string(path).map_err(|e| Error::Usage(format!("{}: {e}", path.display())))?;
        Script::parse(&text).map_err(|(line, m)| Error::Usage(format!("{}:{line}: {m}", path.display())))
    }

    /// The events; an error names the 1-based line.
    pub fn parse(text: &str) -> std::result::Result<Script, (usize, String)> {
        let mut events = Vec::new();
        for (i, line) in text.lines().enumerate() {
            let line = line.split('#').next().unwrap_or("").trim();
            if line.is_empty() {
                continue;
            }
            let words: Vec<&str> = line.split_whitespace().collect();
            let err = |m: String| (i + 1, m);
            let frame: u64 = words[0]
                .parse()
                .map_err(|_| err(format!("`{}` is not a frame number", words[0])))?;
            let args = &words[1..];
            let nums = |n: usize| -> std::result::Result<Vec<f32>, (usize, String)> {
                if args.len() != n + 1 {
                    return Err(err(format!("`{}` takes {n} number(s)", args[0])));
                }
                args[1..]
                    .iter()
                    .map(|a| {
                        a.parse::<f32>()
                            .ok()
                            .filter(|v| v.is_finite())
                            .ok_or_else(|| err(format!("`{a}` is not a number")))
                    })
                    .collect()
            };
            let event = match args {
                ["key", name] => Event::Key(name.to_string()),
                ["move", ..] => nums(3).map(|v| Event::Move([v[0], v[1], v[2]]))?,
                ["turn", ..] => nums(2).map(|v| Event::Turn([v[0], v[1]]))?,
                ["budget", ..] => nums(1).map(|v| Event::Budget(v[0]))?,
                ["split", ..] => nums(1).map(|v| Event::Split(v[0]))?,
                ["screenshot", path] => Event::Screenshot(PathBuf::from(path)),
                ["param", name, value @ ..] if !value.is_empty() => Event::Param(name.to_string(), value.join(" ")),
                ["minimise"] => Event::Minimise,
                ["restore"] => Event::Restore,
                _ => {
                    return Err(err(format!(
                        "unknown event `{}`: expected key, move, turn, budget, split, screenshot, param, minimise or restore",
                        args.join(" ")
                    )))
                }
            };
            events.push((frame, event));
        }
        Ok(Script { events })
    }

    /// The events due before frame `frame` is drawn.
    pub fn due(&self, frame: u64) -> impl Iterator<Item = &Event> {
        self.events.iter().filter(move |(f, _)| *f == frame).map(|(_, e)| e)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn events_parse_and_errors_name_the_line() {
        let s = Script::parse(
            "# still\n3 key M\n5 move 0 0 0.5\n6 budget 0.5 # half\n7 param radiosity.mode \"faithful\"\n",
        )
        .unwrap();
        assert_eq!(
            s.events,
            [
                (3, Event::Key("M".into())),
                (5, Event::Move([0.0, 0.0, 0.5])),
                (6, Event::Budget(0.5)),
                (7, Event::Param("radiosity.mode".into(), "\"faithful\"".into()))
            ]
        );
        assert_eq!(s.due(5).count(), 1);
        assert_eq!(Script::parse("1 key M\n2 move 1 x 2").unwrap_err().0, 2);
        assert_eq!(Script::parse("x key M").unwrap_err().0, 1);
        assert_eq!(Script::parse("1 jump").unwrap_err().0, 1);
        assert_eq!(Script::parse("1 param patch_size").unwrap_err().0, 1);
        let s = Script::parse("2 minimise\n4 restore").unwrap();
        assert_eq!(s.events, [(2, Event::Minimise), (4, Event::Restore)]);
        assert_eq!(Script::parse("2 minimise now").unwrap_err().0, 1);
    }
}
