//! STAGE 1 (parse): integrator parameters from two sources — the scene's `Integrator` directive and the
//! command line's `--set key=value` — read through one typed interface, and the documented parameter
//! tables every integrator and cache application declares. A `--set` value wins; a `--set` key the
//! integrator does not read is an error naming the valid keys.
//!
//! Depends on the parameter lists of this module's parent only; every integrator and application reads
//! its parameters through it.

use std::cell::RefCell;

use crate::error::{Error, Result, Warnings};
use crate::parse::{Named, ParamList};

/// Largest `maxdepth` any integrator accepts (each level may double the rays of a glass path).
pub const MAX_DEPTH: i64 = 64;

/// Typed access to an integrator's parameters with command-line overrides.
#[derive(Debug)]
pub struct IntegratorParams<'a> {
    scene: &'a ParamList,
    overrides: &'a [(String, String)],
    read: RefCell<Vec<&'static str>>,
}

impl<'a> IntegratorParams<'a> {
    /// Wraps the scene's parameters and the `--set` pairs.
    pub fn new(scene: &'a ParamList, overrides: &'a [(String, String)]) -> Self {
        IntegratorParams { scene, overrides, read: RefCell::new(Vec::new()) }
    }

    fn cli(&self, name: &'static str) -> Option<&str> {
        self.read.borrow_mut().push(name);
        self.overrides.iter().rev().find(|(k, _)| k == name).map(|(_, v)| v.as_str())
    }

    fn bad(name: &str, v: &str, what: &str) -> Error {
        Error::usage(format!("--set {name}={v}: expected {what}"))
    }

    /// An integer parameter.
    pub fn int_or(&self, name: &'static str, default: i64) -> Result<i64> {
        match self.cli(name) {
            Some(v) => v.trim().parse().map_err(|_| Self::bad(name, v, "an integer")),
            None => self.scene.int_or(name, default),
        }
    }

    /// A float parameter.
    pub fn float_or(&self, name: &'static str, default: f64) -> Result<f64> {
        match self.cli(name) {
            Some(v) => v.trim().parse().map_err(|_| Self::bad(name, v, "a number")),
            None => self.scene.float_or(name, default),
        }
    }

    /// An optional float parameter.
    pub fn float(&self, name: &'static str) -> Result<Option<f64>> {
        match self.cli(name) {
            Some(v) => v.trim().parse().map(Some).map_err(|_| Self::bad(name, v, "a number")),
            None => self.scene.float(name),
        }
    }

    /// A bool parameter.
    pub fn bool_or(&self, name: &'static str, default: bool) -> Result<bool> {
        match self.cli(name) {
            Some("true") => Ok(true),
            Some("false") => Ok(false),
            Some(v) => Err(Self::bad(name, v, "true or false")),
            None => self.scene.bool_or(name, default),
        }
    }

    /// A string parameter.
    pub fn string_or(&self, name: &'static str, default: &str) -> Result<String> {
        match self.cli(name) {
            Some(v) => Ok(v.to_string()),
            None => Ok(self.scene.string_or(name, default)?.to_string()),
        }
    }

    /// Where a scene parameter was written, as a `file:line:col: ` prefix for messages (empty if not).
    pub fn at(&self, name: &str) -> String {
        self.scene.loc_of(name).map(|l| format!("{l}: ")).unwrap_or_default()
    }

    /// Errors on a `--set` key that no lookup asked for.
    pub fn check_overrides(&self, integrator: &str) -> Result<()> {
        let read = self.read.borrow();
        for (k, v) in self.overrides {
            if !read.iter().any(|r| r == k) {
                let mut known: Vec<&str> = read.clone();
                known.sort();
                known.dedup();
                return Err(Error::usage(format!(
                    "--set {k}={v}: integrator \"{integrator}\" has no parameter \"{k}\" (it reads: {})",
                    known.join(", ")
                )));
            }
        }
        Ok(())
    }
}

/// Warns about Integrator parameters that the integrator did not read.
pub fn report_unused(integrator: Option<&Named>, name: &str, set: &[(String, String)], warnings: &mut Warnings) {
    if let Some(n) = integrator.filter(|n| n.name == name) {
        for p in n.params.unused() {
            // A parameter replaced by --set was not read because the command line won, not because it is unknown.
            if p.name == "pixelbounds" {
                warnings.at(
                    &p.loc,
                    "Integrator: \"pixelbounds\" is not supported; the whole film is rendered (Film \"cropwindow\" restricts it)",
                );
            } else if !set.iter().any(|(k, _)| *k == p.name) {
                warnings.at(&p.loc, format!("Integrator: unused parameter \"{} {}\"", p.ty.word(), p.name));
            }
        }
    }
}

/// One documented integrator parameter: the rows of `cachert render --help` and of the README's tables.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Parameter {
    /// The name as written in the scene file and in `--set`.
    pub name: &'static str,
    /// The pbrt type word (`integer`, `float`, `string`, `bool`).
    pub ty: &'static str,
    /// The default, in words (Markdown: `code` in backquotes).
    pub default: &'static str,
    /// What it does (Markdown).
    pub meaning: &'static str,
}

impl Parameter {
    /// A table row.
    pub const fn new(name: &'static str, ty: &'static str, default: &'static str, meaning: &'static str) -> Self {
        Parameter { name, ty, default, meaning }
    }
}

/// A parameter table as plain text: a `title` line, then one indented line per parameter.
pub fn help_text(title: &str, params: &[Parameter]) -> String {
    let mut out = format!("{title}\n");
    let width = params.iter().map(|p| p.name.len() + p.ty.len() + 3).max().unwrap_or(0);
    for p in params {
        let head = format!("{} ({})", p.name, p.ty);
        out.push_str(&format!(
            "  {head:<width$}  {}; default {}\n",
            p.meaning.replace('`', ""),
            p.default.replace('`', "")
        ));
    }
    out
}

/// A parameter table as the README writes it: header, rule and one Markdown row per parameter.
pub fn markdown_table(params: &[Parameter]) -> String {
    let mut out = String::from("| parameter | type | default | meaning |\n|---|---|---|---|\n");
    for p in params {
        out.push_str(&format!("| `{}` | {} | {} | {} |\n", p.name, p.ty, p.default, p.meaning));
    }
    out
}

/// An `f32` setting as JSON, written with its shortest decimal form (0.2, not 0.20000000298023224);
/// `null` when not finite.
pub fn json_f32(v: f32) -> serde_json::Value {
    v.to_string().parse::<f64>().ok().filter(|x| x.is_finite()).map_or(serde_json::Value::Null, Into::into)
}
