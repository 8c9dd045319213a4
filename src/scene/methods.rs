//! Lighting-method declarations: read from the scene without knowing which methods exist, then
//! checked against the renderer's schemas with [`crate::scene::Scene::check_methods`].

use std::fmt;

use super::doc::{Field, Node, Val};
use super::error::SceneError;

/// A lighting method the scene asks for, with its raw parameters in file order.
#[derive(Debug, Clone, PartialEq)]
pub struct MethodDecl {
    pub name: String,
    /// 1-based line of the method's name; 0 for the implicit default (`forward`).
    pub line: usize,
    /// (parameter name, value, 1-based line of the key).
    pub params: Vec<(String, toml::Value, usize)>,
}

impl MethodDecl {
    /// The declaration used when a scene names no method.
    pub fn implicit_forward() -> MethodDecl {
        MethodDecl {
            name: "forward".into(),
            line: 0,
            params: Vec::new(),
        }
    }

    /// What `--method` and combinations call this declaration: its `id` if it has one, else the
    /// method's name.
    pub fn label(&self) -> &str {
        self.param(ID).and_then(|v| v.as_str()).unwrap_or(self.name.as_str())
    }

    /// The value of parameter `name`, if given.
    pub fn param(&self, name: &str) -> Option<&toml::Value> {
        self.params.iter().find(|(n, _, _)| n == name).map(|(_, v, _)| v)
    }

    /// A copy with parameter `name` set to `value`, replacing any the scene gave (a point of a
    /// chart's sweep).
    pub fn with(&self, name: &str, value: toml::Value) -> MethodDecl {
        let mut d = self.clone();
        d.params.retain(|(n, _, _)| n != name);
        d.params.push((name.to_string(), value, 0));
        d
    }

    /// This declaration without parameter `name` (its default applies).
    pub fn without(&self, name: &str) -> MethodDecl {
        let mut d = self.clone();
        d.params.retain(|(n, _, _)| n != name);
        d
    }
}

/// A `[[combinations]]` entry: a named frame whose terms come from the scene's methods.
#[derive(Debug, Clone, PartialEq)]
pub struct CombinationDecl {
    pub name: String,
    /// 1-based line of the name.
    pub line: usize,
    /// (term key: "base", "direct" or "indirect"; method name; 1-based line), in frame order.
    pub terms: Vec<(&'static str, String, usize)>,
}

/// What a renderer's method accepts: its name and parameters (all optional; the method supplies
/// defaults).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct MethodSchema {
    pub name: &'static str,
    pub params: &'static [ParamSchema],
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct ParamSchema {
    pub name: &'static str,
    pub kind: ParamKind,
}

/// Accepted TOML types. `Float` also accepts integers; `FloatArray` an array of numbers (any
/// length, integers allowed). Floats must be finite.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ParamKind {
    Int,
    Float,
    Bool,
    String,
    FloatArray,
}

impl fmt::Display for ParamKind {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            ParamKind::Int => "int",
            ParamKind::Float => "float",
            ParamKind::Bool => "bool",
            ParamKind::String => "string",
            ParamKind::FloatArray => "float array",
        })
    }
}

impl ParamKind {
    fn accepts(self, v: &toml::Value) -> bool {
        let finite = |v: &toml::Value| match v {
            toml::Value::Integer(_) => true,
            toml::Value::Float(x) => x.is_finite(),
            _ => false,
        };
        match self {
            ParamKind::Int => v.is_integer(),
            ParamKind::Float => finite(v),
            ParamKind::Bool => v.is_bool(),
            ParamKind::String => v.is_str(),
            ParamKind::FloatArray => v.as_array().is_some_and(|a| a.iter().all(finite)),
        }
    }

    fn expected(self) -> &'static str {
        match self {
            ParamKind::Int => "an integer",
            ParamKind::Float => "a finite number",
            ParamKind::Bool => "true or false",
            ParamKind::String => "a string",
            ParamKind::FloatArray => "an array of finite numbers",
        }
    }
}

/// The key every method takes besides its own parameters: the name `--method` and combinations
/// use for the declaration (so one method can be declared twice with different parameters).
pub const ID: &str = "id";

/// Checks `methods` against `known`; the first problem is returned.
pub(crate) fn check(file: &str, methods: &[MethodDecl], known: &[MethodSchema]) -> Result<(), SceneError> {
    let line = |l: usize| (l > 0).then_some(l);
    for (i, m) in methods.iter().enumerate() {
        if let Some((_, v, l)) = m.params.iter().find(|(n, _, _)| n == ID) {
            if v.as_str().is_none_or(|s| s.trim().is_empty()) {
                let msg = format!("expected a non-empty string, got {}", describe_value(v));
                return Err(SceneError::new(file, line(*l), format!("methods[{i}].{ID}"), msg));
            }
        }
        // One label for two different declarations: `--method` and combinations would silently
        // take the first.
        if let Some(j) = (0..i).find(|&j| methods[j].label() == m.label() && !same_params(&methods[j], m)) {
            let msg = format!(
                "{:?} names methods[{j}] (line {}) too, with other parameters: give one of them an `id = \"...\"` to tell them apart",
                m.label(),
                methods[j].line
            );
            return Err(SceneError::new(file, line(m.line), format!("methods[{i}]"), msg));
        }
        let Some(schema) = known.iter().find(|s| s.name == m.name) else {
            let names: Vec<&str> = known.iter().map(|s| s.name).collect();
            let msg = format!("unknown method {:?}; known methods: {}", m.name, names.join(", "));
            return Err(SceneError::new(file, line(m.line), format!("methods[{i}]"), msg));
        };
        for (pname, value, pline) in m.params.iter().filter(|(n, _, _)| n != ID) {
            let field = format!("methods[{i}].{pname}");
            let Some(p) = schema.params.iter().find(|p| p.name == pname) else {
                let msg = if schema.params.is_empty() {
                    format!("unknown parameter; method {:?} takes no parameters", m.name)
                } else {
                    let list: Vec<String> = schema
                        .params
                        .iter()
                        .map(|p| format!("{} ({})", p.name, p.kind))
                        .collect();
                    format!(
                        "unknown parameter of method {:?}; known parameters: {}",
                        m.name,
                        list.join(", ")
                    )
                };
                return Err(SceneError::new(file, line(*pline), field, msg));
            };
            if !p.kind.accepts(value) {
                let msg = format!("expected {}, got {}", p.kind.expected(), describe_value(value));
                return Err(SceneError::new(file, line(*pline), field, msg));
            }
        }
    }
    Ok(())
}

/// The same parameters with the same values, wherever they are written.
fn same_params(a: &MethodDecl, b: &MethodDecl) -> bool {
    a.params.len() == b.params.len() && a.params.iter().all(|(n, v, _)| b.param(n) == Some(v))
}

fn describe_value(v: &toml::Value) -> String {
    match v {
        toml::Value::String(s) => format!("{:?}", s.chars().take(40).collect::<String>()),
        toml::Value::Integer(i) => i.to_string(),
        toml::Value::Float(f) => format!("{f:?}"),
        toml::Value::Boolean(b) => b.to_string(),
        toml::Value::Datetime(d) => format!("the date-time {d}"),
        toml::Value::Array(a) => {
            let parts: Vec<String> = a.iter().take(6).map(describe_value).collect();
            format!("[{}{}]", parts.join(", "), if a.len() > 6 { ", …" } else { "" })
        }
        toml::Value::Table(_) => "a table".into(),
    }
}

fn to_value(node: &Node) -> toml::Value {
    match &node.val {
        Val::Str(s) => toml::Value::String(s.clone()),
        Val::Int(i) => toml::Value::Integer(*i),
        Val::Float(f) => toml::Value::Float(*f),
        Val::Bool(b) => toml::Value::Boolean(*b),
        Val::Datetime(d) => d
            .parse()
            .map_or_else(|_| toml::Value::String(d.clone()), toml::Value::Datetime),
        Val::Array(items) => toml::Value::Array(items.iter().map(to_value).collect()),
        Val::Table(entries) => toml::Value::Table(
            entries
                .iter()
                .filter_map(|(k, v)| match &k.val {
                    Val::Str(s) => Some((s.clone(), to_value(v))),
                    _ => None,
                })
                .collect(),
        ),
    }
}

/// Reads the top-level `methods` array: each element is a method name, or a table with `name`
/// and any other keys as parameters.
pub(crate) fn read(field: &Field) -> Result<Vec<MethodDecl>, SceneError> {
    let mut out = Vec::new();
    for item in field.array()? {
        let decl = match &item.node.val {
            Val::Str(_) => MethodDecl {
                name: method_name(&item)?,
                line: item.line.unwrap_or(0),
                params: Vec::new(),
            },
            Val::Table(_) => {
                let t = item.table()?;
                let name_field = t.require("name", "the method's name")?;
                let name = method_name(&name_field)?;
                let params = t
                    .keys()
                    .into_iter()
                    .filter(|(k, _)| *k != "name")
                    .filter_map(|(k, kline)| {
                        let f = t.get(k)?;
                        Some((k.to_owned(), to_value(f.node), kline.or(f.line).unwrap_or(0)))
                    })
                    .collect();
                MethodDecl {
                    name,
                    line: name_field.line.unwrap_or(0),
                    params,
                }
            }
            _ => {
                return Err(item.err(format!(
                    "expected a method name or a table with `name`, got {}",
                    super::doc::describe(item.node)
                )))
            }
        };
        out.push(decl);
    }
    Ok(out)
}

fn method_name(f: &Field) -> Result<String, SceneError> {
    let s = f.string()?;
    if s.trim().is_empty() {
        return Err(f.err("expected a method name, got an empty string"));
    }
    Ok(s.to_owned())
}

/// Reads the top-level `combinations` array of tables: `name` and any of `base`, `direct`,
/// `indirect`, each the name of one of the scene's methods.
pub(crate) fn read_combinations(field: &Field) -> Result<Vec<CombinationDecl>, SceneError> {
    let mut out = Vec::new();
    for item in field.array()? {
        let t = item.table()?;
        t.allow(&["name", "base", "direct", "indirect"])?;
        let name_field = t.require("name", "the combination's name")?;
        let name = method_name(&name_field)?;
        let mut terms = Vec::new();
        for key in ["base", "direct", "indirect"] {
            if let Some(f) = t.get(key) {
                terms.push((key, method_name(&f)?, f.line.unwrap_or(0)));
            }
        }
        out.push(CombinationDecl {
            name,
            line: name_field.line.unwrap_or(0),
            terms,
        });
    }
    Ok(out)
}
