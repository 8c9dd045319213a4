//! A TOML document as a tree whose every key and value remembers its byte span, plus typed
//! readers that turn it into checked values with errors naming file, line and field.
//!
//! Why not plain `#[derive(Deserialize)]` structs with `deny_unknown_fields`: serde's errors carry
//! a span but not the path of the field (`lights[1].intensity`), and our own range checks
//! (negative intensity, fov out of range) need the line of each value anyway. Reading a spanned
//! tree gives both, and lets the unknown-field message list exactly the keys that are valid in
//! that table (which for objects and lights depends on their `mesh`/`type`).

use std::fmt;
use std::ops::Range;
use std::path::{Path, PathBuf};

use glam::{Vec2, Vec3};
use serde::de::{Deserialize, Deserializer, MapAccess, SeqAccess, Visitor};

use super::error::{column_of, line_of, SceneError};

// `toml::Spanned` fails outright on values the parser has no span for (tables created implicitly
// by a dotted header such as `[a.b]`, the inner map of a date-time). These are the hidden protocol
// names of serde_spanned 0.6, which toml 0.8 uses: asking for them gets the span where the parser
// has one and the plain value otherwise. The line-number tests fail if the protocol ever changes.
const SPANNED_NAME: &str = "$__serde_spanned_private_Spanned";
const SPANNED_START: &str = "$__serde_spanned_private_start";
const SPANNED_END: &str = "$__serde_spanned_private_end";
const SPANNED_VALUE: &str = "$__serde_spanned_private_value";
const SPANNED_FIELDS: &[&str] = &[SPANNED_START, SPANNED_END, SPANNED_VALUE];
const DATETIME_KEY: &str = "$__toml_private_datetime";

/// A TOML value with the byte span of its text, when the parser knows it.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct Node {
    pub span: Option<Range<usize>>,
    pub val: Val,
}

#[derive(Debug, Clone, PartialEq)]
pub(crate) enum Val {
    Str(String),
    Int(i64),
    Float(f64),
    Bool(bool),
    Datetime(String),
    Array(Vec<Node>),
    /// Entries in document order; the key node is always a `Val::Str`.
    Table(Vec<(Node, Node)>),
}

impl<'de> Deserialize<'de> for Node {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Node, D::Error> {
        d.deserialize_struct(SPANNED_NAME, SPANNED_FIELDS, NodeVisitor)
    }
}

struct NodeVisitor;

fn plain(val: Val) -> Node {
    Node { span: None, val }
}

impl<'de> Visitor<'de> for NodeVisitor {
    type Value = Node;

    fn expecting(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str("any TOML value")
    }
    fn visit_bool<E>(self, v: bool) -> Result<Node, E> {
        Ok(plain(Val::Bool(v)))
    }
    fn visit_i64<E>(self, v: i64) -> Result<Node, E> {
        Ok(plain(Val::Int(v)))
    }
    fn visit_u64<E>(self, v: u64) -> Result<Node, E> {
        Ok(plain(i64::try_from(v).map_or(Val::Float(v as f64), Val::Int)))
    }
    fn visit_f64<E>(self, v: f64) -> Result<Node, E> {
        Ok(plain(Val::Float(v)))
    }
    fn visit_str<E>(self, v: &str) -> Result<Node, E> {
        Ok(plain(Val::Str(v.to_owned())))
    }
    fn visit_string<E>(self, v: String) -> Result<Node, E> {
        Ok(plain(Val::Str(v)))
    }
    fn visit_seq<A: SeqAccess<'de>>(self, mut seq: A) -> Result<Node, A::Error> {
        let mut items = Vec::new();
        while let Some(item) = seq.next_element::<Node>()? {
            items.push(item);
        }
        Ok(plain(Val::Array(items)))
    }
    fn visit_map<A: MapAccess<'de>>(self, mut map: A) -> Result<Node, A::Error> {
        let Some(first) = map.next_key::<Node>()? else {
            return Ok(plain(Val::Table(Vec::new())));
        };
        match &first.val {
            Val::Str(k) if k == SPANNED_START => {
                let start: usize = map.next_value()?;
                let _end_key = map.next_key::<Node>()?;
                let end: usize = map.next_value()?;
                let _value_key = map.next_key::<Node>()?;
                let inner: Node = map.next_value_seed(AnyNode)?;
                Ok(Node {
                    span: Some(start..end),
                    val: inner.val,
                })
            }
            Val::Str(k) if k == DATETIME_KEY => {
                let text: Node = map.next_value()?;
                let shown = match text.val {
                    Val::Str(s) => s,
                    _ => String::from("?"),
                };
                Ok(plain(Val::Datetime(shown)))
            }
            _ => {
                let mut entries = vec![(first, map.next_value::<Node>()?)];
                while let Some(key) = map.next_key::<Node>()? {
                    entries.push((key, map.next_value::<Node>()?));
                }
                Ok(plain(Val::Table(entries)))
            }
        }
    }
}

/// The value inside a span wrapper: read without asking for a span again.
struct AnyNode;

impl<'de> serde::de::DeserializeSeed<'de> for AnyNode {
    type Value = Node;
    fn deserialize<D: Deserializer<'de>>(self, d: D) -> Result<Node, D::Error> {
        d.deserialize_any(NodeVisitor)
    }
}

/// Where errors point: the file's display name and text (for byte offset → line).
pub(crate) struct Ctx<'a> {
    pub file: &'a str,
    pub text: &'a str,
    pub base_dir: &'a Path,
    /// Byte offsets where lines start, built on first use: every field asks for its line, and
    /// counting newlines from the top each time made a scene of n entries O(n²) to read
    /// (4,096 explicit lights took 25 s).
    pub line_starts: std::cell::OnceCell<Vec<usize>>,
}

impl<'a> Ctx<'a> {
    pub fn new(file: &'a str, text: &'a str, base_dir: &'a Path) -> Ctx<'a> {
        Ctx {
            file,
            text,
            base_dir,
            line_starts: std::cell::OnceCell::new(),
        }
    }

    pub fn line(&self, span: &Option<Range<usize>>) -> Option<usize> {
        let starts = self.line_starts.get_or_init(|| {
            std::iter::once(0)
                .chain(
                    self.text
                        .bytes()
                        .enumerate()
                        .filter(|&(_, c)| c == b'\n')
                        .map(|(i, _)| i + 1),
                )
                .collect()
        });
        // The 1-based line of a byte: how many lines start at or before it.
        span.as_ref()
            .map(|s| starts.partition_point(|&start| start <= s.start.min(self.text.len())))
    }

    pub fn err(&self, line: Option<usize>, field: &str, msg: impl Into<String>) -> SceneError {
        SceneError::new(self.file, line, field, msg)
    }

    /// Parses the whole document; syntax errors carry line and column.
    pub fn parse(&self) -> Result<Node, SceneError> {
        toml::from_str::<Node>(self.text).map_err(|e| {
            let (line, col) = match e.span() {
                Some(s) => (Some(line_of(self.text, s.start)), Some(column_of(self.text, s.start))),
                None => (None, None),
            };
            let mut msg = e.message().to_owned();
            if let Some(c) = col {
                msg.push_str(&format!(" (column {c})"));
            }
            self.err(line, "syntax", msg)
        })
    }
}

/// Short human rendering of a value for "expected …, got …" messages.
pub(crate) fn describe(node: &Node) -> String {
    match &node.val {
        Val::Str(s) => {
            let mut short: String = s.chars().take(40).collect();
            if short.len() < s.len() {
                short.push('…');
            }
            format!("{short:?}")
        }
        Val::Int(i) => i.to_string(),
        Val::Float(f) => fmt_float(*f),
        Val::Bool(b) => b.to_string(),
        Val::Datetime(d) => format!("the date-time {d}"),
        Val::Array(items) => {
            let mut parts: Vec<String> = items.iter().take(6).map(describe).collect();
            if items.len() > 6 {
                parts.push("…".into());
            }
            format!("[{}]", parts.join(", "))
        }
        Val::Table(_) => "a table".into(),
    }
}

fn fmt_float(f: f64) -> String {
    if f.is_nan() {
        "nan".into()
    } else if f.is_infinite() {
        if f > 0.0 { "inf" } else { "-inf" }.into()
    } else if f.fract() == 0.0 && f.abs() < 1e15 {
        format!("{f:.1}")
    } else {
        f.to_string()
    }
}

pub(crate) fn as_number(node: &Node) -> Option<f64> {
    match node.val {
        Val::Int(i) => Some(i as f64),
        Val::Float(f) => Some(f),
        _ => None,
    }
}

/// One table being read: checks its keys against the allowed ones and hands out its fields.
pub(crate) struct Table<'a> {
    pub ctx: &'a Ctx<'a>,
    /// Field path of the table itself ("camera", "lights[1]"); empty for the document root.
    pub path: String,
    /// Line of the table (its header), for "missing field" errors.
    pub line: Option<usize>,
    entries: Vec<(&'a Node, &'a Node)>,
}

impl<'a> Table<'a> {
    /// `fallback_line` is used when the table itself has no span (implicit tables).
    pub fn new(
        ctx: &'a Ctx<'a>,
        path: String,
        node: &'a Node,
        fallback_line: Option<usize>,
    ) -> Result<Table<'a>, SceneError> {
        let line = ctx.line(&node.span).or(fallback_line);
        let Val::Table(entries) = &node.val else {
            return Err(ctx.err(line, &path, format!("expected a table, got {}", describe(node))));
        };
        let mut entries: Vec<(&Node, &Node)> = entries.iter().map(|(k, v)| (k, v)).collect();
        entries.sort_by_key(|(k, _)| k.span.as_ref().map_or(usize::MAX, |s| s.start));
        Ok(Table {
            ctx,
            path,
            line,
            entries,
        })
    }

    fn child_path(&self, key: &str) -> String {
        if self.path.is_empty() {
            key.to_owned()
        } else {
            format!("{}.{key}", self.path)
        }
    }

    /// Declares all the keys this table may have and errors on the first other key (in file
    /// order), listing the allowed ones. Call it before reading fields, so a misspelt key is
    /// reported as such rather than as a missing one.
    pub fn allow(&self, keys: &[&str]) -> Result<(), SceneError> {
        for (k, _) in &self.entries {
            let name = match &k.val {
                Val::Str(s) => s.as_str(),
                _ => "?",
            };
            if !keys.contains(&name) {
                let known = keys.join(", ");
                let line = self.ctx.line(&k.span).or(self.line);
                let msg = format!("unknown field; expected one of: {known}");
                return Err(self.ctx.err(line, &self.child_path(name), msg));
            }
        }
        Ok(())
    }

    /// Keys present in this table, in file order, with their key line.
    pub fn keys(&self) -> Vec<(&'a str, Option<usize>)> {
        let key_line = |k: &Node| self.ctx.line(&k.span).or(self.line);
        self.entries
            .iter()
            .filter_map(|(k, _)| match &k.val {
                Val::Str(s) => Some((s.as_str(), key_line(k))),
                _ => None,
            })
            .collect()
    }

    /// The field `key`, if present.
    pub fn get(&self, key: &str) -> Option<Field<'a>> {
        let (k, v) = self
            .entries
            .iter()
            .find(|(k, _)| matches!(&k.val, Val::Str(s) if s == key))?;
        let line = self.ctx.line(&v.span).or(self.ctx.line(&k.span)).or(self.line);
        Some(Field {
            ctx: self.ctx,
            path: self.child_path(key),
            line,
            node: v,
        })
    }

    /// The field `key`, or an error naming it as missing.
    pub fn require(&self, key: &str, what: &str) -> Result<Field<'a>, SceneError> {
        self.get(key).ok_or_else(|| self.missing(key, what))
    }

    /// The error for a missing `key`; `what` says what it should be.
    pub fn missing(&self, key: &str, what: &str) -> SceneError {
        self.ctx.err(
            self.line,
            &self.child_path(key),
            format!("missing required field ({what})"),
        )
    }
}

/// One value being read, with everything needed to complain about it.
#[derive(Clone)]
pub(crate) struct Field<'a> {
    pub ctx: &'a Ctx<'a>,
    pub path: String,
    pub line: Option<usize>,
    pub node: &'a Node,
}

impl<'a> Field<'a> {
    pub fn err(&self, msg: impl Into<String>) -> SceneError {
        self.ctx.err(self.line, &self.path, msg)
    }

    fn expected(&self, what: &str) -> SceneError {
        self.err(format!("expected {what}, got {}", describe(self.node)))
    }

    /// This value as a table.
    pub fn table(&self) -> Result<Table<'a>, SceneError> {
        Table::new(self.ctx, self.path.clone(), self.node, self.line)
    }

    /// Elements of an array, each as a field `path[i]`.
    pub fn array(&self) -> Result<Vec<Field<'a>>, SceneError> {
        let Val::Array(items) = &self.node.val else {
            return Err(self.expected("an array"));
        };
        Ok(items
            .iter()
            .enumerate()
            .map(|(i, n)| Field {
                ctx: self.ctx,
                path: format!("{}[{i}]", self.path),
                line: self.ctx.line(&n.span).or(self.line),
                node: n,
            })
            .collect())
    }

    pub fn string(&self) -> Result<&'a str, SceneError> {
        match &self.node.val {
            Val::Str(s) => Ok(s.as_str()),
            _ => Err(self.expected("a string")),
        }
    }

    pub fn boolean(&self) -> Result<bool, SceneError> {
        match self.node.val {
            Val::Bool(b) => Ok(b),
            _ => Err(self.expected("true or false")),
        }
    }

    /// An integer in `lo..=hi`.
    pub fn int_in(&self, lo: u32, hi: u32) -> Result<u32, SceneError> {
        match self.node.val {
            Val::Int(i) if i >= i64::from(lo) && i <= i64::from(hi) => Ok(i as u32),
            _ => Err(self.expected(&format!("an integer from {lo} to {hi}"))),
        }
    }

    /// A finite number accepted by `ok`, described by `what` ("a positive number").
    pub fn number_where(&self, what: &str, ok: impl Fn(f32) -> bool) -> Result<f32, SceneError> {
        match as_number(self.node) {
            Some(x) if x.is_finite() && (x as f32).is_finite() && ok(x as f32) => Ok(x as f32),
            _ => Err(self.expected(what)),
        }
    }

    /// Exactly `N` finite numbers accepted by `ok`; with `scalar_ok`, one number stands for all.
    fn numbers<const N: usize>(
        &self,
        what: &str,
        scalar_ok: bool,
        ok: impl Fn(f32) -> bool,
    ) -> Result<[f32; N], SceneError> {
        let good = |n: &Node| as_number(n).filter(|x| x.is_finite() && (*x as f32).is_finite() && ok(*x as f32));
        match &self.node.val {
            Val::Array(items) if items.len() == N => {
                let mut out = [0.0f32; N];
                for (o, item) in out.iter_mut().zip(items) {
                    *o = good(item).ok_or_else(|| self.expected(what))? as f32;
                }
                Ok(out)
            }
            Val::Int(_) | Val::Float(_) if scalar_ok => {
                let x = good(self.node).ok_or_else(|| self.expected(what))? as f32;
                Ok([x; N])
            }
            _ => Err(self.expected(what)),
        }
    }

    /// A point or vector: 3 finite numbers.
    pub fn vec3(&self) -> Result<Vec3, SceneError> {
        self.numbers::<3>("3 finite numbers", false, |_| true).map(Vec3::from)
    }

    /// 3 positive numbers, or one for all three (sizes, scales).
    pub fn positive3(&self) -> Result<Vec3, SceneError> {
        self.numbers::<3>("3 positive numbers", true, |x| x > 0.0)
            .map(Vec3::from)
    }

    /// 3 non-negative numbers (extents that may be zero).
    pub fn non_negative3(&self) -> Result<Vec3, SceneError> {
        self.numbers::<3>("3 non-negative numbers", false, |x| x >= 0.0)
            .map(Vec3::from)
    }

    /// 2 positive numbers, or one for both.
    pub fn positive2(&self) -> Result<Vec2, SceneError> {
        self.numbers::<2>("2 positive numbers", true, |x| x > 0.0)
            .map(Vec2::from)
    }

    /// A linear RGB colour: 3 non-negative numbers (or one, meaning grey).
    pub fn colour(&self) -> Result<Vec3, SceneError> {
        self.numbers::<3>("3 non-negative numbers", true, |x| x >= 0.0)
            .map(Vec3::from)
    }

    /// A reflectance-like colour: 3 numbers in [0, 1] (or one, meaning grey).
    pub fn unit_colour(&self) -> Result<Vec3, SceneError> {
        self.numbers::<3>("3 numbers in [0, 1]", true, |x| (0.0..=1.0).contains(&x))
            .map(Vec3::from)
    }

    /// A path relative to the scene's directory that must name an existing file. Returns the
    /// absolute path.
    pub fn existing_file(&self) -> Result<PathBuf, SceneError> {
        let raw = self.string()?;
        if raw.is_empty() {
            return Err(self.err("expected a file path, got an empty string"));
        }
        let joined = self.ctx.base_dir.join(raw);
        if !joined.is_file() {
            let why = if joined.exists() {
                "not a file"
            } else {
                "file not found"
            };
            return Err(self.err(format!("{why}: {raw} (looked for {})", joined.display())));
        }
        Ok(std::path::absolute(&joined).unwrap_or(joined))
    }

    /// [`Field::existing_file`] holding an image penumbra reads, judged by its header (format and
    /// size, see [`crate::util::image_io::image_header`]), so a file that is no image or claims an
    /// absurd size is an error here, with the field's line, before anything is decoded.
    pub fn existing_image(&self) -> Result<PathBuf, SceneError> {
        let path = self.existing_file()?;
        crate::util::image_io::image_header(&path).map_err(|m| self.err(format!("{}: {m}", path.display())))?;
        Ok(path)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn parse(text: &str) -> Node {
        let ctx = Ctx::new("t.toml", text, Path::new("."));
        ctx.parse().unwrap()
    }

    #[test]
    fn spans_cover_headers_keys_values_and_implicit_tables() {
        let text = "a = 1\n[camera]\npos = [1, 2.5, 3]\n[[l]]\nx = 1\n[[l]]\nd = 1979-05-27\n[t.u]\nk = { z = 'q' }\n";
        let root = parse(text);
        let ctx = Ctx::new("t.toml", text, Path::new("."));
        let t = Table::new(&ctx, String::new(), &root, None).unwrap();
        assert_eq!(t.get("a").unwrap().line, Some(1));
        let cam = t.get("camera").unwrap().table().unwrap();
        assert_eq!(cam.line, Some(2));
        assert_eq!(cam.get("pos").unwrap().vec3().unwrap(), Vec3::new(1.0, 2.5, 3.0));
        let l = t.get("l").unwrap().array().unwrap();
        assert_eq!(l.len(), 2);
        let l1 = l[1].table().unwrap();
        let d = l1.get("d").unwrap();
        assert_eq!(d.line, Some(7));
        assert!(d
            .number_where("a number", |_| true)
            .unwrap_err()
            .to_string()
            .contains("date-time 1979-05-27"));
        let tt = t.get("t").unwrap().table().unwrap();
        let u = tt.get("u").unwrap().table().unwrap();
        let k = u.get("k").unwrap();
        assert_eq!(k.line, Some(9));
        assert_eq!(describe(k.node), "a table");
    }

    #[test]
    fn unknown_keys_are_reported_in_file_order() {
        let text = "[c]\nb = 1\nzz = 2\naa = 3\n";
        let root = parse(text);
        let ctx = Ctx::new("t.toml", text, Path::new("."));
        let t = Table::new(&ctx, String::new(), &root, None).unwrap();
        let c = t.get("c").unwrap().table().unwrap();
        let e = c.allow(&["b", "q"]).unwrap_err();
        assert_eq!((e.line, e.field.as_str()), (Some(3), "c.zz"));
        assert!(e.message.contains("b, q"), "{e}");
    }

    #[test]
    fn describe_values() {
        let root = parse("a = [1, 2.0, 'x', nan, -inf, true]");
        let Val::Table(e) = &root.val else { panic!() };
        assert_eq!(describe(&e[0].1), "[1, 2.0, \"x\", nan, -inf, true]");
    }
}
