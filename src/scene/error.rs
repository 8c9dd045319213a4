//! The one error type of the scene module.

use std::fmt;

/// A scene, mesh or method-declaration error, pointing at the offending file, line and field.
///
/// Displayed on one line as `{file}:{line}: {field}: {message}` (`:{line}` is left out when the
/// line is unknown), e.g. `scenes/bad.toml:12: lights[1].intensity: expected 3 non-negative
/// numbers, got -2`.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("{file}{}: {field}: {message}", LineSuffix(*.line))]
pub struct SceneError {
    /// The scene file (as given to [`crate::scene::Scene::from_file`]), `<built-in default>`, or
    /// the mesh file the error is about.
    pub file: String,
    /// 1-based line in `file`, when known.
    pub line: Option<usize>,
    /// Dotted path of the offending field, e.g. `lights[1].intensity`, `syntax` for TOML syntax
    /// errors, `file` for an unreadable file, `vertex 3` for a bad OBJ vertex.
    pub field: String,
    /// What is wrong, on one line.
    pub message: String,
}

struct LineSuffix(Option<usize>);

impl fmt::Display for LineSuffix {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self.0 {
            Some(line) => write!(f, ":{line}"),
            None => Ok(()),
        }
    }
}

impl SceneError {
    pub fn new(
        file: impl Into<String>,
        line: Option<usize>,
        field: impl Into<String>,
        message: impl Into<String>,
    ) -> Self {
        // Messages from other crates (toml, std::io) may span several lines; the format promises
        // one line, so fold them.
        let message: String = message.into();
        let message = message
            .lines()
            .map(str::trim)
            .filter(|l| !l.is_empty())
            .collect::<Vec<_>>();
        SceneError {
            file: file.into(),
            line,
            field: field.into(),
            message: message.join(", "),
        }
    }
}

/// 1-based line number of byte `offset` in `text` (offsets past the end give the last line).
pub(crate) fn line_of(text: &str, offset: usize) -> usize {
    let end = offset.min(text.len());
    text.as_bytes()
        .get(..end)
        .map_or(0, |b| b.iter().filter(|&&c| c == b'\n').count())
        + 1
}

/// 1-based column of byte `offset` in `text`, counted in characters.
pub(crate) fn column_of(text: &str, offset: usize) -> usize {
    let mut end = offset.min(text.len());
    while !text.is_char_boundary(end) {
        end -= 1;
    }
    let before = text.get(..end).unwrap_or("");
    let line_start = before.rfind('\n').map_or(0, |i| i + 1);
    before.get(line_start..).map_or(0, |s| s.chars().count()) + 1
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn display_with_and_without_line() {
        let e = SceneError::new("scenes/bad.toml", Some(12), "lights[1].intensity", "oops");
        assert_eq!(e.to_string(), "scenes/bad.toml:12: lights[1].intensity: oops");
        let e = SceneError::new("a.toml", None, "file", "first\n  second\n");
        assert_eq!(e.to_string(), "a.toml: file: first, second");
    }

    #[test]
    fn lines_and_columns() {
        let t = "ab\ncdé\nf";
        assert_eq!(line_of(t, 0), 1);
        assert_eq!(line_of(t, 2), 1);
        assert_eq!(line_of(t, 3), 2);
        assert_eq!(line_of(t, 100), 3);
        assert_eq!(column_of(t, 3), 1);
        assert_eq!(column_of(t, 7), 4); // after 'é' (2 bytes)
        assert_eq!(column_of(t, 6), 3); // inside 'é' rounds down
    }
}
