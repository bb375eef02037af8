//! STAGE 1 (parse): typed parameter lists (`"float fov" [45]`) and their checked lookups.
//!
//! The parser builds a [`ParamList`] per directive; the scene builder reads values out of it through typed
//! lookups that check type and arity and report problems at the parameter's own location. Every lookup
//! marks the parameter as used, so after a directive is handled [`ParamList::unused`] names the parameters
//! nobody read (pbrt-v3 warns about those too). Knows nothing about rendering.

use std::cell::{Cell, RefCell};

use crate::error::{Error, Result, SourceLoc};
use crate::parse::spectrum;

/// The declared type of a parameter, as written before its name (`"point3 P"`). Aliases are folded:
/// `point` = `point3`, `vector` = `vector3`, `normal` = `normal3`, `color` = `rgb`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ParamType {
    /// `integer`
    Integer,
    /// `float`
    Float,
    /// `point2`
    Point2,
    /// `vector2`
    Vector2,
    /// `point3` / `point`
    Point3,
    /// `vector3` / `vector`
    Vector3,
    /// `normal3` / `normal`
    Normal3,
    /// `rgb` / `color`
    Rgb,
    /// `xyz`
    Xyz,
    /// `blackbody` (pbrt-v3: pairs of temperature in kelvin and scale)
    Blackbody,
    /// `spectrum`: wavelength/value pairs, or the name of an .spd file
    Spectrum,
    /// `string`
    String,
    /// `bool`
    Bool,
    /// `texture`: the name of a texture
    Texture,
}

impl ParamType {
    /// Parses a type word as written in a scene file; `None` for an unknown word.
    pub fn from_word(word: &str) -> Option<ParamType> {
        use ParamType::*;
        Some(match word {
            "integer" => Integer,
            "float" => Float,
            "point2" => Point2,
            "vector2" => Vector2,
            "point3" | "point" => Point3,
            "vector3" | "vector" => Vector3,
            "normal3" | "normal" => Normal3,
            "rgb" | "color" => Rgb,
            "xyz" => Xyz,
            "blackbody" => Blackbody,
            "spectrum" => Spectrum,
            "string" => String,
            "bool" => Bool,
            "texture" => Texture,
            _ => return None,
        })
    }

    /// The canonical word for messages.
    pub fn word(self) -> &'static str {
        use ParamType::*;
        match self {
            Integer => "integer",
            Float => "float",
            Point2 => "point2",
            Vector2 => "vector2",
            Point3 => "point3",
            Vector3 => "vector3",
            Normal3 => "normal",
            Rgb => "rgb",
            Xyz => "xyz",
            Blackbody => "blackbody",
            Spectrum => "spectrum",
            String => "string",
            Bool => "bool",
            Texture => "texture",
        }
    }

    /// How many numbers make one value of this type (1 for scalars and non-numeric types).
    pub fn tuple_len(self) -> usize {
        use ParamType::*;
        match self {
            Point2 | Vector2 => 2,
            Point3 | Vector3 | Normal3 | Rgb | Xyz => 3,
            Blackbody | Spectrum => 2,
            _ => 1,
        }
    }
}

/// The values of a parameter, as parsed. Numeric types hold numbers; `string`/`texture` hold strings;
/// `spectrum` holds either numbers or one file name.
#[derive(Clone, Debug, PartialEq)]
pub enum ParamValue {
    /// Numbers, for every numeric type (integers are checked to be integral by the parser).
    Numbers(Vec<f64>),
    /// Quoted strings.
    Strings(Vec<String>),
    /// `true`/`false` values.
    Bools(Vec<bool>),
}

/// One `"type name" value(s)` entry.
#[derive(Debug)]
pub struct Param {
    /// Declared type.
    pub ty: ParamType,
    /// Parameter name.
    pub name: String,
    /// Values.
    pub value: ParamValue,
    /// Where the quoted `"type name"` starts.
    pub loc: SourceLoc,
    used: Cell<bool>,
}

impl Param {
    /// Makes a parameter (not yet used).
    pub fn new(ty: ParamType, name: impl Into<String>, value: ParamValue, loc: SourceLoc) -> Self {
        Param { ty, name: name.into(), value, loc, used: Cell::new(false) }
    }

    /// Whether a lookup has read this parameter.
    pub fn is_used(&self) -> bool {
        self.used.get()
    }

    fn numbers(&self) -> &[f64] {
        match &self.value {
            ParamValue::Numbers(v) => v,
            _ => &[],
        }
    }

    fn strings(&self) -> &[String] {
        match &self.value {
            ParamValue::Strings(v) => v,
            _ => &[],
        }
    }

    fn err(&self, msg: impl std::fmt::Display) -> Error {
        Error::at(&self.loc, format!("parameter \"{}\": {msg}", self.name))
    }

    /// How many values the parameter holds (tuples count once).
    fn count(&self) -> usize {
        match &self.value {
            ParamValue::Numbers(v) => v.len() / self.ty.tuple_len(),
            ParamValue::Strings(v) => v.len(),
            ParamValue::Bools(v) => v.len(),
        }
    }
}

/// A constant value or the name of a texture, for material parameters such as `Kd`.
#[derive(Clone, Debug, PartialEq)]
pub enum TexOr<T> {
    /// A constant.
    Value(T),
    /// The name of a texture declared with `Texture`.
    Texture(String),
}

/// The parameters of one directive, in file order.
#[derive(Debug, Default)]
pub struct ParamList {
    params: Vec<Param>,
    /// The names looked up and not found: what an unused parameter may have been meant to be.
    missed: RefCell<Vec<Box<str>>>,
}

impl ParamList {
    /// Wraps parsed parameters. A name given twice keeps the later one (pbrt-v3 does the same).
    pub fn new(mut params: Vec<Param>) -> Self {
        let mut seen = std::collections::HashSet::new();
        let mut keep = vec![true; params.len()];
        for (i, p) in params.iter().enumerate().rev() {
            if !seen.insert(p.name.clone()) {
                keep[i] = false;
            }
        }
        let mut k = keep.into_iter();
        params.retain(|_| k.next().unwrap_or(true));
        ParamList { params, missed: RefCell::default() }
    }

    /// All parameters, in file order.
    pub fn iter(&self) -> impl Iterator<Item = &Param> {
        self.params.iter()
    }

    /// Whether there are no parameters.
    pub fn is_empty(&self) -> bool {
        self.params.is_empty()
    }

    /// The parameter called `name`, marked as used.
    pub fn get(&self, name: &str) -> Option<&Param> {
        let Some(p) = self.params.iter().find(|p| p.name == name) else {
            let mut missed = self.missed.borrow_mut();
            if !missed.iter().any(|m| &**m == name) {
                missed.push(name.into());
            }
            return None;
        };
        p.used.set(true);
        Some(p)
    }

    /// The warning for an unused parameter `p` of `directive`, with the nearest name a lookup asked for
    /// and did not find (`"float radus"`: did you mean "radius"?).
    pub fn unused_message(&self, directive: &str, p: &Param) -> String {
        let missed = self.missed.borrow();
        let hint = crate::parse::closest(&p.name, missed.iter().map(|m| &**m))
            .map(|m| format!(" (did you mean \"{m}\"?)"))
            .unwrap_or_default();
        format!("{directive}: unused parameter \"{} {}\"{hint}", p.ty.word(), p.name)
    }

    /// The location of parameter `name`, if present (does not mark it used).
    pub fn loc_of(&self, name: &str) -> Option<&SourceLoc> {
        self.params.iter().find(|p| p.name == name).map(|p| &p.loc)
    }

    /// Marks every parameter as used (for directives that are skipped as a whole with one warning).
    pub fn mark_all_used(&self) {
        self.params.iter().for_each(|p| p.used.set(true));
    }

    /// The parameters no lookup has read, in file order.
    pub fn unused(&self) -> impl Iterator<Item = &Param> {
        self.params.iter().filter(|p| !p.is_used())
    }

    /// The parameter `name` if it has one of the types `allowed`; an error naming the expected type if it
    /// has another.
    fn typed(&self, name: &str, allowed: &[ParamType]) -> Result<Option<&Param>> {
        let Some(p) = self.get(name) else { return Ok(None) };
        if allowed.contains(&p.ty) {
            return Ok(Some(p));
        }
        let want: Vec<&str> = allowed.iter().map(|t| t.word()).collect();
        Err(p.err(format!("expected type {}, found {}", want.join(" or "), p.ty.word())))
    }

    /// The single value of `p`, or an arity error.
    fn single<'a>(p: &'a Param, what: &str) -> Result<&'a Param> {
        match p.count() {
            1 => Ok(p),
            n => Err(p.err(format!("expected 1 {what}, got {n}"))),
        }
    }

    /// A single `float`.
    pub fn float(&self, name: &str) -> Result<Option<f64>> {
        let Some(p) = self.typed(name, &[ParamType::Float])? else { return Ok(None) };
        Ok(Some(Self::single(p, "float")?.numbers()[0]))
    }

    /// A single `float`, or `default` when absent.
    pub fn float_or(&self, name: &str, default: f64) -> Result<f64> {
        Ok(self.float(name)?.unwrap_or(default))
    }

    /// A single `integer`.
    pub fn int(&self, name: &str) -> Result<Option<i64>> {
        let Some(p) = self.typed(name, &[ParamType::Integer])? else { return Ok(None) };
        Ok(Some(Self::single(p, "integer")?.numbers()[0] as i64))
    }

    /// A single `integer`, or `default` when absent.
    pub fn int_or(&self, name: &str, default: i64) -> Result<i64> {
        Ok(self.int(name)?.unwrap_or(default))
    }

    /// A single `bool`.
    pub fn bool(&self, name: &str) -> Result<Option<bool>> {
        let Some(p) = self.typed(name, &[ParamType::Bool])? else { return Ok(None) };
        match &Self::single(p, "bool")?.value {
            ParamValue::Bools(v) => Ok(Some(v[0])),
            _ => Err(p.err("expected true or false")),
        }
    }

    /// A single `bool`, or `default` when absent.
    pub fn bool_or(&self, name: &str, default: bool) -> Result<bool> {
        Ok(self.bool(name)?.unwrap_or(default))
    }

    /// A single `string`.
    pub fn string(&self, name: &str) -> Result<Option<&str>> {
        let Some(p) = self.typed(name, &[ParamType::String])? else { return Ok(None) };
        Ok(Some(Self::single(p, "string")?.strings()[0].as_str()))
    }

    /// A single `string`, or `default` when absent.
    pub fn string_or<'a>(&'a self, name: &str, default: &'a str) -> Result<&'a str> {
        Ok(self.string(name)?.unwrap_or(default))
    }

    /// The name of a texture (`"texture name" "tex"`).
    pub fn texture(&self, name: &str) -> Result<Option<&str>> {
        let Some(p) = self.typed(name, &[ParamType::Texture])? else { return Ok(None) };
        Ok(Some(Self::single(p, "texture name")?.strings()[0].as_str()))
    }

    /// All numbers of a `float` parameter.
    pub fn floats(&self, name: &str) -> Result<Option<&[f64]>> {
        Ok(self.typed(name, &[ParamType::Float])?.map(|p| p.numbers()))
    }

    /// All numbers of an `integer` parameter.
    pub fn ints(&self, name: &str) -> Result<Option<&[f64]>> {
        Ok(self.typed(name, &[ParamType::Integer])?.map(|p| p.numbers()))
    }

    /// The triples of a `point3` parameter (the parser has checked the count is a multiple of 3).
    pub fn point3s(&self, name: &str) -> Result<Option<Vec<[f64; 3]>>> {
        Ok(self.typed(name, &[ParamType::Point3])?.map(|p| triples(p.numbers())))
    }

    /// The triples of a `normal` parameter.
    pub fn normals(&self, name: &str) -> Result<Option<Vec<[f64; 3]>>> {
        Ok(self.typed(name, &[ParamType::Normal3])?.map(|p| triples(p.numbers())))
    }

    /// The triples of a `vector3` parameter.
    pub fn vector3s(&self, name: &str) -> Result<Option<Vec<[f64; 3]>>> {
        Ok(self.typed(name, &[ParamType::Vector3])?.map(|p| triples(p.numbers())))
    }

    /// A single `point3`.
    pub fn point3(&self, name: &str) -> Result<Option<[f64; 3]>> {
        let Some(p) = self.typed(name, &[ParamType::Point3])? else { return Ok(None) };
        Ok(Some(triples(Self::single(p, "point3")?.numbers())[0]))
    }

    /// A single `vector3`.
    pub fn vector3(&self, name: &str) -> Result<Option<[f64; 3]>> {
        let Some(p) = self.typed(name, &[ParamType::Vector3])? else { return Ok(None) };
        Ok(Some(triples(Self::single(p, "vector3")?.numbers())[0]))
    }

    /// Pairs from a `point2` parameter or from a `float` parameter with an even count (pbrt-v3 accepts
    /// `"float uv"` for texture coordinates).
    pub fn point2s(&self, name: &str) -> Result<Option<Vec<[f64; 2]>>> {
        let Some(p) = self.typed(name, &[ParamType::Point2, ParamType::Float])? else {
            return Ok(None);
        };
        let v = p.numbers();
        if v.len() % 2 != 0 {
            return Err(p.err(format!("expected pairs of numbers, got {} numbers", v.len())));
        }
        Ok(Some(v.chunks_exact(2).map(|c| [c[0], c[1]]).collect()))
    }

    /// A colour given as `rgb`, `xyz`, `blackbody` or `spectrum` (samples or an .spd file), converted to
    /// linear sRGB.
    pub fn rgb(&self, name: &str) -> Result<Option<[f64; 3]>> {
        use ParamType::*;
        let Some(p) = self.typed(name, &[Rgb, Xyz, Blackbody, Spectrum])? else { return Ok(None) };
        spectrum::param_to_rgb(p).map(Some)
    }

    /// A colour or the name of a spectrum texture (`"rgb Kd" [..]` or `"texture Kd" "wood"`). A single
    /// `float` is accepted as a grey colour, as pbrt-v3 materials do for some parameters.
    pub fn rgb_or_texture(&self, name: &str) -> Result<Option<TexOr<[f64; 3]>>> {
        use ParamType::*;
        let Some(p) = self.typed(name, &[Rgb, Xyz, Blackbody, Spectrum, Texture, Float])? else {
            return Ok(None);
        };
        match p.ty {
            Texture => Ok(Some(TexOr::Texture(Self::single(p, "texture name")?.strings()[0].clone()))),
            Float => {
                let v = Self::single(p, "float")?.numbers()[0];
                Ok(Some(TexOr::Value([v; 3])))
            }
            _ => spectrum::param_to_rgb(p).map(|c| Some(TexOr::Value(c))),
        }
    }

    /// A float or the name of a float texture (`"float roughness" 0.1` or `"texture roughness" "r"`).
    pub fn float_or_texture(&self, name: &str) -> Result<Option<TexOr<f64>>> {
        use ParamType::*;
        let Some(p) = self.typed(name, &[Float, Texture])? else { return Ok(None) };
        let p = Self::single(p, if p.ty == Float { "float" } else { "texture name" })?;
        Ok(Some(match p.ty {
            Texture => TexOr::Texture(p.strings()[0].clone()),
            _ => TexOr::Value(p.numbers()[0]),
        }))
    }
}

fn triples(v: &[f64]) -> Vec<[f64; 3]> {
    v.chunks_exact(3).map(|c| [c[0], c[1], c[2]]).collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::path::Path;
    use std::sync::Arc;

    fn loc(col: u32) -> SourceLoc {
        SourceLoc::new(Arc::from(Path::new("t.pbrt")), 1, col)
    }

    fn list() -> ParamList {
        ParamList::new(vec![
            Param::new(ParamType::Float, "fov", ParamValue::Numbers(vec![45.0]), loc(1)),
            Param::new(ParamType::Integer, "n", ParamValue::Numbers(vec![1.0, 2.0]), loc(20)),
            Param::new(ParamType::Float, "uv", ParamValue::Numbers(vec![0.0, 1.0, 2.0]), loc(30)),
            Param::new(ParamType::Float, "fov", ParamValue::Numbers(vec![30.0]), loc(40)),
        ])
    }

    #[test]
    fn later_duplicates_win_and_lookups_mark_use() {
        let l = list();
        assert_eq!(l.float("fov").unwrap(), Some(30.0));
        assert_eq!(l.float_or("absent", 7.0).unwrap(), 7.0);
        let unused: Vec<&str> = l.unused().map(|p| p.name.as_str()).collect();
        assert_eq!(unused, ["n", "uv"]);
    }

    #[test]
    fn wrong_type_and_arity_are_errors_at_the_parameter() {
        let l = list();
        let e = l.float("n").unwrap_err().to_string();
        assert_eq!(e, "t.pbrt:1:20: parameter \"n\": expected type float, found integer");
        let e = l.int("n").unwrap_err().to_string();
        assert_eq!(e, "t.pbrt:1:20: parameter \"n\": expected 1 integer, got 2");
        let e = l.point2s("uv").unwrap_err().to_string();
        assert!(e.contains("expected pairs of numbers, got 3 numbers"), "{e}");
    }
}
