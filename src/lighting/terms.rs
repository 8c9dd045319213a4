//! The terms of a frame and the configurations that assign them to methods.

use std::fmt;

use crate::scene::{MethodDecl, Scene, SceneError};

/// One of the three terms a frame is the sum of.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub enum Term {
    /// Depth, emission, ambient or light-map (the renderer draws the sky after it).
    Base,
    /// Light straight from the light sources.
    Direct,
    /// Light after further bounces.
    Indirect,
}

impl Term {
    pub const ALL: [Term; 3] = [Term::Base, Term::Direct, Term::Indirect];

    pub fn key(self) -> &'static str {
        match self {
            Term::Base => "base",
            Term::Direct => "direct",
            Term::Indirect => "indirect",
        }
    }

    fn bit(self) -> u8 {
        1 << self as u8
    }
}

/// A set of terms.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub struct Terms(u8);

impl Terms {
    pub const NONE: Terms = Terms(0);
    pub const BASE: Terms = Terms(1);
    pub const DIRECT: Terms = Terms(2);
    pub const INDIRECT: Terms = Terms(4);
    pub const BASE_DIRECT: Terms = Terms(3);

    pub fn of(terms: &[Term]) -> Terms {
        Terms(terms.iter().fold(0, |acc, t| acc | t.bit()))
    }
    pub fn has(self, t: Term) -> bool {
        self.0 & t.bit() != 0
    }
    pub fn contains(self, other: Terms) -> bool {
        self.0 & other.0 == other.0
    }
    pub fn union(self, other: Terms) -> Terms {
        Terms(self.0 | other.0)
    }
    pub fn is_empty(self) -> bool {
        self.0 == 0
    }
    pub fn iter(self) -> impl Iterator<Item = Term> {
        Term::ALL.into_iter().filter(move |t| self.has(*t))
    }
    /// The first term in frame order (base, direct, indirect).
    pub fn first(self) -> Option<Term> {
        self.iter().next()
    }
    /// Bits for shaders' specialization constants: 1 base, 2 direct, 4 indirect.
    pub fn bits(self) -> u32 {
        self.0 as u32
    }
}

impl fmt::Display for Terms {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let names: Vec<&str> = self.iter().map(Term::key).collect();
        f.write_str(if names.is_empty() { "nothing" } else { "" })?;
        f.write_str(&names.join(" + "))
    }
}

/// One method of a configuration and the terms it draws.
#[derive(Clone, Debug, PartialEq)]
pub struct Part {
    pub decl: MethodDecl,
    pub terms: Terms,
}

/// What one frame is drawn with: a method alone (every term it supplies) or a scene's
/// combination. Parts are in frame order: the base first.
#[derive(Clone, Debug, PartialEq)]
pub struct Configuration {
    pub name: String,
    pub parts: Vec<Part>,
}

impl Configuration {
    pub fn terms(&self) -> Terms {
        self.parts.iter().fold(Terms::NONE, |acc, p| acc.union(p.terms))
    }
}

/// What a method can supply: every term in `terms`, any subset of them when `separable`.
#[derive(Clone, Copy, Debug)]
pub struct Supply {
    pub name: &'static str,
    pub terms: Terms,
    pub separable: bool,
}

/// The configuration a scene's method declaration stands for alone.
pub fn alone(decl: &MethodDecl, supply: &[Supply]) -> Configuration {
    let terms = supply
        .iter()
        .find(|s| s.name == decl.name)
        .map_or(Terms::BASE_DIRECT, |s| s.terms);
    Configuration {
        name: decl.label().to_string(),
        parts: vec![Part {
            decl: decl.clone(),
            terms,
        }],
    }
}

/// Every configuration a scene declares: each method alone, then each combination, checked
/// against what the methods supply (one error line naming file, line and field).
pub fn configurations(scene: &Scene, supply: &[Supply]) -> Result<Vec<Configuration>, SceneError> {
    let mut out: Vec<Configuration> = scene.methods.iter().map(|d| alone(d, supply)).collect();
    for (i, c) in scene.combinations.iter().enumerate() {
        let err = |line: usize, field: String, msg: String| {
            SceneError::new(&scene.source, (line > 0).then_some(line), field, msg)
        };
        if out.iter().any(|o| o.name == c.name) {
            return Err(err(
                c.line,
                format!("combinations[{i}].name"),
                format!("{:?} is already the name of a method or combination", c.name),
            ));
        }
        let mut parts: Vec<Part> = Vec::new();
        for (term, method, line) in &c.terms {
            let term = match *term {
                "base" => Term::Base,
                "direct" => Term::Direct,
                _ => Term::Indirect,
            };
            let field = format!("combinations[{i}].{}", term.key());
            let decl = scene.methods.iter().find(|d| d.label() == *method).ok_or_else(|| {
                let names: Vec<&str> = scene.methods.iter().map(|d| d.label()).collect();
                err(
                    *line,
                    field.clone(),
                    format!("{method:?} is not one of the scene's methods ({})", names.join(", ")),
                )
            })?;
            let s = supply.iter().find(|s| s.name == decl.name).copied().unwrap_or(Supply {
                name: "",
                terms: Terms::NONE,
                separable: false,
            });
            if !s.terms.has(term) {
                return Err(err(
                    *line,
                    field,
                    format!(
                        "{} cannot supply the {} term (it supplies {})",
                        decl.name,
                        term.key(),
                        s.terms
                    ),
                ));
            }
            match parts.iter_mut().find(|p| p.decl.label() == *method) {
                Some(p) => p.terms = p.terms.union(Terms::of(&[term])),
                None => parts.push(Part {
                    decl: decl.clone(),
                    terms: Terms::of(&[term]),
                }),
            }
        }
        if parts.is_empty() {
            return Err(err(
                c.line,
                format!("combinations[{i}]"),
                "names no term: give at least one of base, direct, indirect".into(),
            ));
        }
        for p in &parts {
            let s = supply.iter().find(|s| s.name == p.decl.name).copied();
            if let Some(s) = s.filter(|s| !s.separable && p.terms != s.terms) {
                let (key, line) = c
                    .terms
                    .iter()
                    .find(|(_, m, _)| *m == p.decl.label())
                    .map_or(("name", c.line), |t| (t.0, t.2));
                return Err(err(
                    line,
                    format!("combinations[{i}].{key}"),
                    format!(
                        "{} draws its terms ({}) in one pass and cannot supply {} alone",
                        s.name, s.terms, p.terms
                    ),
                ));
            }
        }
        parts.sort_by_key(|p| p.terms.first());
        out.push(Configuration {
            name: c.name.clone(),
            parts,
        });
    }
    Ok(out)
}
