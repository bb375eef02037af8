//! STAGE 1 (parse): integrator parameters from two sources — the scene's `Integrator` directive and the
//! command line's `--set key=value` — read through one typed interface, and the documented parameter
//! tables every integrator and cache application declares. A `--set` value wins; a `--set` key the
//! integrator does not read is an error naming the valid keys.
//!
//! Each parameter is declared once, as a [`ParamDef`] (or a [`Choice`] among named values): its name,
//! type, default, valid range and meaning. The getters of [`IntegratorParams`] take that declaration, so
//! the default a render uses is the one the tables (`render --help`, docs/) show, and every range
//! check gives the same message: `file:line:col: INTEGRATOR: "NAME" must be …, got VALUE` (the location
//! when the scene wrote the parameter). A parameter whose default is computed when the render starts
//! (from the scene's size, the image or a flag) declares it in words and is read with
//! [`IntegratorParams::get_or`] or [`IntegratorParams::get_opt`].
//!
//! Depends on the parameter lists of this module's parent only; every integrator and application reads
//! its parameters through it.

use std::cell::RefCell;
use std::fmt;
use std::marker::PhantomData;

use crate::error::{Error, Result, Warnings};
use crate::parse::{Named, ParamList};

/// Largest `maxdepth` any integrator accepts (each level may double the rays of a glass path).
pub const MAX_DEPTH: i64 = 64;

/// A parameter's default as the tables show it: a value of its type, or words for one computed when the
/// render starts.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum DefaultValue {
    /// An `integer` parameter's default.
    Int(i64),
    /// A `float` parameter's default (∞ allowed).
    Float(f64),
    /// A `bool` parameter's default.
    Bool(bool),
    /// A `string` parameter's default.
    Text(&'static str),
    /// Computed when the render starts; the words say how (Markdown).
    Computed(&'static str),
}

impl fmt::Display for DefaultValue {
    /// Markdown: strings in backquotes, ∞ for an unbounded float.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match *self {
            DefaultValue::Int(v) => write!(f, "{v}"),
            DefaultValue::Float(v) if v == f64::INFINITY => f.write_str("∞"),
            DefaultValue::Float(v) => write!(f, "{v}"),
            DefaultValue::Bool(v) => write!(f, "{v}"),
            DefaultValue::Text(v) => write!(f, "`{v}`"),
            DefaultValue::Computed(words) => f.write_str(words),
        }
    }
}

/// One documented integrator parameter: the rows of `cachert render --help` and of the docs' tables
/// (made by a [`ParamDef`] or a [`Choice`], which also read it).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Parameter {
    /// The name as written in the scene file and in `--set`.
    pub name: &'static str,
    /// The pbrt type word (`integer`, `float`, `string`, `bool`).
    pub ty: &'static str,
    /// The default.
    pub default: DefaultValue,
    /// What it does (Markdown).
    pub meaning: &'static str,
}

/// The values a numeric parameter accepts (NaN never does). Ranges are closed unless said otherwise.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Valid {
    /// Any value of the type.
    Any,
    /// `lo ≤ v ≤ hi`; `unit` follows the bounds in the message (`degrees`).
    Between {
        /// Least value.
        lo: f64,
        /// Greatest value.
        hi: f64,
        /// Unit words after the bounds, or empty.
        unit: &'static str,
    },
    /// `lo ≤ v`, and finite when `finite`.
    AtLeast {
        /// Least value.
        lo: f64,
        /// Whether ∞ is refused.
        finite: bool,
    },
    /// `v > 0`, and finite when `finite`.
    Positive {
        /// Whether ∞ is refused.
        finite: bool,
    },
    /// `lo ≤ v < below`.
    Below {
        /// Least value.
        lo: f64,
        /// The bound it stays under.
        below: f64,
    },
}

impl Valid {
    /// `None` when `v` (written `shown`) is valid, else what it must be: `must be …, got shown`. `int` says
    /// whether the parameter is an integer (which has no ∞ to refuse and reads "at least").
    fn refuse(&self, v: f64, shown: &dyn fmt::Display, int: bool) -> Option<String> {
        let (ok, rule) = match *self {
            Valid::Any => return None,
            Valid::Between { lo, hi, unit } => {
                let unit = if unit.is_empty() { String::new() } else { format!(" {unit}") };
                (v >= lo && v <= hi, format!("between {lo} and {hi}{unit}"))
            }
            Valid::AtLeast { lo, .. } if int => (v >= lo, format!("at least {lo}")),
            Valid::AtLeast { lo, finite: true } => (v >= lo && v.is_finite(), format!("a finite number ≥ {lo}")),
            Valid::AtLeast { lo, finite: false } => (v >= lo, format!("≥ {lo}")),
            Valid::Positive { finite } => (v > 0.0 && (!finite || v.is_finite()), "positive".to_string()),
            Valid::Below { lo, below } => (v >= lo && v < below, format!("in [{lo}, {below})")),
        };
        (!ok).then(|| format!("must be {rule}, got {shown}"))
    }
}

/// A type a parameter can have: how it is read from `--set` text and from the scene, and checked.
pub trait Kind: Sized {
    /// The pbrt type word.
    const TY: &'static str;
    /// What a `--set` value must look like (`an integer`).
    const EXPECTED: &'static str;
    /// Parses a `--set` value.
    fn parse(text: &str) -> Option<Self>;
    /// The scene's value, if written (an error for a wrong type or arity).
    fn from_scene(list: &ParamList, name: &str) -> Result<Option<Self>>;
    /// The declared default, when it is a value of this type.
    fn from_default(d: DefaultValue) -> Option<Self>;
    /// `None` when `self` is in `valid`, else what it must be (see [`Valid`]).
    fn refuse(&self, valid: &Valid) -> Option<String>;
}

impl Kind for i64 {
    const TY: &'static str = "integer";
    const EXPECTED: &'static str = "an integer";
    fn parse(text: &str) -> Option<Self> {
        text.trim().parse().ok()
    }
    fn from_scene(list: &ParamList, name: &str) -> Result<Option<Self>> {
        list.int(name)
    }
    fn from_default(d: DefaultValue) -> Option<Self> {
        if let DefaultValue::Int(v) = d { Some(v) } else { None }
    }
    fn refuse(&self, valid: &Valid) -> Option<String> {
        valid.refuse(*self as f64, self, true)
    }
}

impl Kind for f64 {
    const TY: &'static str = "float";
    const EXPECTED: &'static str = "a number";
    fn parse(text: &str) -> Option<Self> {
        text.trim().parse().ok()
    }
    fn from_scene(list: &ParamList, name: &str) -> Result<Option<Self>> {
        list.float(name)
    }
    fn from_default(d: DefaultValue) -> Option<Self> {
        if let DefaultValue::Float(v) = d { Some(v) } else { None }
    }
    fn refuse(&self, valid: &Valid) -> Option<String> {
        valid.refuse(*self, self, false)
    }
}

impl Kind for bool {
    const TY: &'static str = "bool";
    const EXPECTED: &'static str = "true or false";
    fn parse(text: &str) -> Option<Self> {
        match text {
            "true" => Some(true),
            "false" => Some(false),
            _ => None,
        }
    }
    fn from_scene(list: &ParamList, name: &str) -> Result<Option<Self>> {
        list.bool(name)
    }
    fn from_default(d: DefaultValue) -> Option<Self> {
        if let DefaultValue::Bool(v) = d { Some(v) } else { None }
    }
    fn refuse(&self, _: &Valid) -> Option<String> {
        None
    }
}

impl Kind for String {
    const TY: &'static str = "string";
    const EXPECTED: &'static str = "a string";
    fn parse(text: &str) -> Option<Self> {
        Some(text.to_string())
    }
    fn from_scene(list: &ParamList, name: &str) -> Result<Option<Self>> {
        Ok(list.string(name)?.map(str::to_string))
    }
    fn from_default(d: DefaultValue) -> Option<Self> {
        if let DefaultValue::Text(v) = d { Some(v.to_string()) } else { None }
    }
    fn refuse(&self, _: &Valid) -> Option<String> {
        None
    }
}

/// One integrator parameter of type `T` (`i64`, `f64`, `bool` or `String`), declared once: its table row
/// (name, default, meaning) and the values it accepts. Read it with [`IntegratorParams::get`].
#[derive(Debug)]
pub struct ParamDef<T> {
    /// The documented row.
    pub row: Parameter,
    /// The values it accepts.
    pub valid: Valid,
    kind: PhantomData<fn() -> T>,
}

impl<T> Clone for ParamDef<T> {
    fn clone(&self) -> Self {
        *self
    }
}

impl<T> Copy for ParamDef<T> {}

impl<T: Kind> ParamDef<T> {
    const fn with(name: &'static str, ty: &'static str, default: DefaultValue, meaning: &'static str) -> Self {
        ParamDef { row: Parameter { name, ty, default, meaning }, valid: Valid::Any, kind: PhantomData }
    }

    /// A parameter whose default is computed when the render starts, described in `words` (Markdown); read
    /// it with [`IntegratorParams::get_or`] or [`IntegratorParams::get_opt`].
    pub const fn computed(name: &'static str, words: &'static str, meaning: &'static str) -> Self {
        Self::with(name, T::TY, DefaultValue::Computed(words), meaning)
    }

    /// The same parameter with another meaning (one integrator's use of a parameter another declares).
    pub const fn meaning(self, meaning: &'static str) -> Self {
        ParamDef { row: Parameter { meaning, ..self.row }, ..self }
    }

    /// Accepts `valid` only.
    pub const fn valid(self, valid: Valid) -> Self {
        ParamDef { valid, ..self }
    }
}

impl ParamDef<i64> {
    /// An `integer` parameter, any value.
    pub const fn int(name: &'static str, default: i64, meaning: &'static str) -> Self {
        Self::with(name, "integer", DefaultValue::Int(default), meaning)
    }

    /// Accepts `lo ≤ v ≤ hi` only.
    pub const fn between(self, lo: i64, hi: i64) -> Self {
        self.valid(Valid::Between { lo: lo as f64, hi: hi as f64, unit: "" })
    }

    /// Accepts `lo ≤ v` only.
    pub const fn at_least(self, lo: i64) -> Self {
        self.valid(Valid::AtLeast { lo: lo as f64, finite: true })
    }
}

impl ParamDef<f64> {
    /// A `float` parameter, any value.
    pub const fn float(name: &'static str, default: f64, meaning: &'static str) -> Self {
        Self::with(name, "float", DefaultValue::Float(default), meaning)
    }

    /// Accepts `lo ≤ v ≤ hi` only; `unit` follows the bounds in the message (`degrees`, or empty).
    pub const fn between(self, lo: f64, hi: f64, unit: &'static str) -> Self {
        self.valid(Valid::Between { lo, hi, unit })
    }
}

impl ParamDef<bool> {
    /// A `bool` parameter.
    pub const fn bool(name: &'static str, default: bool, meaning: &'static str) -> Self {
        Self::with(name, "bool", DefaultValue::Bool(default), meaning)
    }

    /// The declared default, for code that builds the value without reading a scene.
    pub const fn default(&self) -> bool {
        match self.row.default {
            DefaultValue::Bool(b) => b,
            _ => unreachable!(),
        }
    }
}

impl ParamDef<String> {
    /// A `string` parameter, any text (checked by its reader, or a [`Choice`]).
    pub const fn text(name: &'static str, default: &'static str, meaning: &'static str) -> Self {
        Self::with(name, "string", DefaultValue::Text(default), meaning)
    }
}

/// A `string` parameter naming one of a few values of `T`, declared once: its row (the default is the
/// name of one of `choices`) and the names with their values. Read it with [`IntegratorParams::choice`].
#[derive(Debug)]
pub struct Choice<T: 'static> {
    /// The documented row.
    pub row: Parameter,
    /// Each name and the value it selects.
    pub choices: &'static [(&'static str, T)],
}

impl<T> Clone for Choice<T> {
    fn clone(&self) -> Self {
        *self
    }
}

impl<T> Copy for Choice<T> {}

impl<T> Choice<T> {
    /// A choice among `choices` whose default is the one named `default`.
    pub const fn new(
        name: &'static str,
        default: &'static str,
        choices: &'static [(&'static str, T)],
        meaning: &'static str,
    ) -> Self {
        Choice { row: Parameter { name, ty: "string", default: DefaultValue::Text(default), meaning }, choices }
    }
}

/// Typed access to an integrator's parameters with command-line overrides.
#[derive(Debug)]
pub struct IntegratorParams<'a> {
    integrator: &'a str,
    scene: &'a ParamList,
    overrides: &'a [(String, String)],
    read: RefCell<Vec<&'static str>>,
}

impl<'a> IntegratorParams<'a> {
    /// Wraps the scene's parameters of `integrator` (the name messages give) and the `--set` pairs.
    pub fn new(integrator: &'a str, scene: &'a ParamList, overrides: &'a [(String, String)]) -> Self {
        IntegratorParams { integrator, scene, overrides, read: RefCell::new(Vec::new()) }
    }

    /// The integrator's name, as messages give it.
    pub fn integrator(&self) -> &str {
        self.integrator
    }

    fn cli(&self, name: &'static str) -> Option<&str> {
        self.read.borrow_mut().push(name);
        self.overrides.iter().rev().find(|(k, _)| k == name).map(|(_, v)| v.as_str())
    }

    /// The written value (`--set` first, then the scene), unchecked.
    fn written<T: Kind>(&self, name: &'static str) -> Result<Option<T>> {
        match self.cli(name) {
            Some(v) => {
                T::parse(v).map(Some).ok_or_else(|| Error::usage(format!("--set {name}={v}: expected {}", T::EXPECTED)))
            }
            None => T::from_scene(self.scene, name),
        }
    }

    /// The parameter, or `default`, unchecked: for a value another source may still replace (check the
    /// one kept with [`IntegratorParams::check`]).
    pub fn written_or<T: Kind>(&self, def: &ParamDef<T>, default: T) -> Result<T> {
        Ok(self.written(def.row.name)?.unwrap_or(default))
    }

    /// `v` if `def` accepts it, else the error naming the parameter.
    pub fn check<T: Kind>(&self, def: &ParamDef<T>, v: T) -> Result<T> {
        match v.refuse(&def.valid) {
            None => Ok(v),
            Some(what) => Err(self.invalid(&def.row, what)),
        }
    }

    /// The parameter, or its declared default, unchecked: for an integrator's own check (then
    /// [`IntegratorParams::check`] or [`IntegratorParams::invalid`]).
    pub fn get_unchecked<T: Kind>(&self, def: &ParamDef<T>) -> Result<T> {
        match self.written(def.row.name)? {
            Some(v) => Ok(v),
            None => T::from_default(def.row.default).ok_or_else(|| {
                // A declaration read with the wrong getter: a mistake in the integrator, not in the input.
                self.invalid(&def.row, "has no fixed default: its reader must give one (get_or)")
            }),
        }
    }

    /// The parameter, or its declared default; checked.
    pub fn get<T: Kind>(&self, def: &ParamDef<T>) -> Result<T> {
        let v = self.get_unchecked(def)?;
        self.check(def, v)
    }

    /// The parameter, or `default` (computed by the caller, as its row's words say); checked.
    pub fn get_or<T: Kind>(&self, def: &ParamDef<T>, default: T) -> Result<T> {
        let v = self.written(def.row.name)?.unwrap_or(default);
        self.check(def, v)
    }

    /// The parameter if written (checked); `None` leaves its computed default to the caller.
    pub fn get_opt<T: Kind>(&self, def: &ParamDef<T>) -> Result<Option<T>> {
        self.written(def.row.name)?.map(|v| self.check(def, v)).transpose()
    }

    /// The value that the parameter (or its default) names.
    pub fn choice<T: Copy>(&self, def: &Choice<T>) -> Result<T> {
        let name = def.row.name;
        let written = self.written::<String>(name)?;
        let text = match (&written, def.row.default) {
            (Some(w), _) => w.as_str(),
            (None, DefaultValue::Text(d)) => d,
            (None, _) => "",
        };
        if let Some(&(_, v)) = def.choices.iter().find(|(n, _)| *n == text) {
            return Ok(v);
        }
        let names: Vec<String> = def.choices.iter().map(|(n, _)| format!("\"{n}\"")).collect();
        let list = match names.split_last() {
            Some((last, rest)) if !rest.is_empty() => format!("{} or {last}", rest.join(", ")),
            _ => names.join(""),
        };
        Err(self.invalid(&def.row, format!("must be {list}, got \"{text}\"")))
    }

    /// The error for a bad value of `row` found by the integrator's own check: `what` says what it must be
    /// and what it is.
    pub fn invalid(&self, row: &Parameter, what: impl fmt::Display) -> Error {
        Error::usage(format!("{}{}: \"{}\" {what}", self.at(row.name), self.integrator, row.name))
    }

    /// Where a scene parameter was written, as a `file:line:col: ` prefix for messages (empty if not).
    pub fn at(&self, name: &str) -> String {
        self.scene.loc_of(name).map(|l| format!("{l}: ")).unwrap_or_default()
    }

    /// Errors on a `--set` key that no lookup asked for.
    pub fn check_overrides(&self) -> Result<()> {
        let read = self.read.borrow();
        for (k, v) in self.overrides {
            if !read.iter().any(|r| r == k) {
                let mut known: Vec<&str> = read.clone();
                known.sort();
                known.dedup();
                return Err(Error::usage(format!(
                    "--set {k}={v}: integrator \"{}\" has no parameter \"{k}\" (it reads: {})",
                    self.integrator,
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
                warnings.at(&p.loc, n.params.unused_message("Integrator", p));
            }
        }
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
            p.default.to_string().replace('`', "")
        ));
    }
    out
}

/// A parameter table as docs/ writes it: header, rule and one Markdown row per parameter.
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

#[cfg(test)]
mod tests {
    use super::*;

    const N: ParamDef<i64> = ParamDef::int("n", 4, "count").between(1, 8);
    const ANGLE: ParamDef<f64> = ParamDef::float("angle", 10.0, "degrees").between(0.0, 90.0, "degrees");
    const LEN: ParamDef<f64> = ParamDef::computed("len", "0.1 · L", "length").valid(Valid::Positive { finite: true });
    const MODE: Choice<u8> = Choice::new("mode", "b", &[("a", 1), ("b", 2), ("c", 3)], "mode");

    fn set(pairs: &[(&str, &str)]) -> Vec<(String, String)> {
        pairs.iter().map(|(k, v)| (k.to_string(), v.to_string())).collect()
    }

    #[test]
    fn defaults_come_from_the_declaration_and_values_are_checked() {
        let empty = ParamList::default();
        let none = set(&[]);
        let p = IntegratorParams::new("toy", &empty, &none);
        assert_eq!(p.get(&N).unwrap(), 4);
        assert_eq!(p.get(&ANGLE).unwrap(), 10.0);
        assert_eq!(p.get_opt(&LEN).unwrap(), None);
        assert_eq!(p.choice(&MODE).unwrap(), 2);
        assert!(p.get(&LEN).is_err(), "a computed default has no value to fall back on");
        let bad = set(&[("n", "9"), ("angle", "nan"), ("len", "inf"), ("mode", "d")]);
        let p = IntegratorParams::new("toy", &empty, &bad);
        assert_eq!(p.get(&N).unwrap_err().to_string(), "toy: \"n\" must be between 1 and 8, got 9");
        assert_eq!(p.get(&ANGLE).unwrap_err().to_string(), "toy: \"angle\" must be between 0 and 90 degrees, got NaN");
        assert_eq!(p.get_opt(&LEN).unwrap_err().to_string(), "toy: \"len\" must be positive, got inf");
        assert_eq!(p.choice(&MODE).unwrap_err().to_string(), "toy: \"mode\" must be \"a\", \"b\" or \"c\", got \"d\"");
        let p = IntegratorParams::new("toy", &empty, &bad[..1]);
        assert!(p.get(&N).is_err());
        assert!(p.check_overrides().is_ok(), "a --set key read is known, whatever its value");
        let typo = set(&[("nn", "1")]);
        let p = IntegratorParams::new("toy", &empty, &typo);
        p.get(&N).unwrap();
        assert_eq!(
            p.check_overrides().unwrap_err().to_string(),
            "--set nn=1: integrator \"toy\" has no parameter \"nn\" (it reads: n)"
        );
    }

    #[test]
    fn rows_show_typed_defaults() {
        let rows = [N.row, ANGLE.row, LEN.row, MODE.row, ParamDef::float("d", f64::INFINITY, "x").row];
        let shown: Vec<String> = rows.iter().map(|r| r.default.to_string()).collect();
        assert_eq!(shown, ["4", "10", "0.1 · L", "`b`", "∞"]);
        assert_eq!(rows.map(|r| r.ty), ["integer", "float", "float", "string", "float"]);
    }
}
