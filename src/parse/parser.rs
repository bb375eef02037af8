//! STAGE 1 (parse): tokens of one file → [`Directive`]s with their parameter lists.
//!
//! Input is the text of one file and its name; output is appended to a directive list. `Include` is handed
//! to [`super::include`], which parses the included file into the same list. Every problem is an
//! [`Error::at`] the offending directive, parameter or token. Knows nothing about what directives mean.
#![cfg_attr(not(test), deny(clippy::indexing_slicing, clippy::panic))]

use std::path::Path;
use std::sync::Arc;

use crate::error::{Error, Result, SourceLoc};
use crate::parse::IncludeStack;
use crate::parse::directive::{ActiveTransform, Directive, DirectiveKind, Named};
use crate::parse::lexer::{Lexer, LineIndex, Tok, Token};
use crate::parse::params::{Param, ParamList, ParamType, ParamValue};

/// How the arguments of a directive are written.
#[derive(Clone, Copy)]
enum Syntax {
    /// No arguments.
    Bare(fn() -> DirectiveKind),
    /// A fixed count of numbers, bare or in one pair of brackets.
    Numbers(usize, fn(&[f64]) -> DirectiveKind),
    /// One quoted string.
    OneString(fn(String) -> DirectiveKind),
    /// A quoted type or name followed by parameters.
    NamedParams(fn(Named) -> DirectiveKind),
    /// `ActiveTransform StartTime|EndTime|All`
    ActiveTransform,
    /// `MediumInterface "inside" ["outside"]`
    MediumInterface,
    /// `Texture "name" "type" "class" params`
    Texture,
    /// `Include "file"`
    Include,
}

/// The first `N` numbers of `v` (the parser has checked there are exactly `N`).
fn arr<const N: usize>(v: &[f64]) -> [f64; N] {
    let mut a = [0.0; N];
    a.iter_mut().zip(v).for_each(|(a, v)| *a = *v);
    a
}

/// Every directive keyword and how its arguments are written.
const DIRECTIVES: &[(&str, Syntax)] = {
    use DirectiveKind as D;
    use Syntax::*;
    &[
        ("Identity", Bare(|| D::Identity)),
        ("Translate", Numbers(3, |v| D::Translate(arr(v)))),
        ("Scale", Numbers(3, |v| D::Scale(arr(v)))),
        ("Rotate", Numbers(4, |v| D::Rotate(arr(v)))),
        ("LookAt", Numbers(9, |v| D::LookAt(arr(v)))),
        ("CoordinateSystem", OneString(D::CoordinateSystem)),
        ("CoordSysTransform", OneString(D::CoordSysTransform)),
        ("Transform", Numbers(16, |v| D::Transform(arr(v)))),
        ("ConcatTransform", Numbers(16, |v| D::ConcatTransform(arr(v)))),
        (
            "TransformTimes",
            Numbers(2, |v| {
                let [start, end] = arr(v);
                D::TransformTimes(start, end)
            }),
        ),
        ("ActiveTransform", ActiveTransform),
        ("ReverseOrientation", Bare(|| D::ReverseOrientation)),
        ("Camera", NamedParams(D::Camera)),
        ("Sampler", NamedParams(D::Sampler)),
        ("Film", NamedParams(D::Film)),
        ("PixelFilter", NamedParams(D::PixelFilter)),
        ("Integrator", NamedParams(D::Integrator)),
        ("Accelerator", NamedParams(D::Accelerator)),
        ("MakeNamedMedium", NamedParams(D::MakeNamedMedium)),
        ("MediumInterface", MediumInterface),
        ("WorldBegin", Bare(|| D::WorldBegin)),
        ("WorldEnd", Bare(|| D::WorldEnd)),
        ("AttributeBegin", Bare(|| D::AttributeBegin)),
        ("AttributeEnd", Bare(|| D::AttributeEnd)),
        ("TransformBegin", Bare(|| D::TransformBegin)),
        ("TransformEnd", Bare(|| D::TransformEnd)),
        ("ObjectBegin", OneString(D::ObjectBegin)),
        ("ObjectEnd", Bare(|| D::ObjectEnd)),
        ("ObjectInstance", OneString(D::ObjectInstance)),
        ("LightSource", NamedParams(D::LightSource)),
        ("AreaLightSource", NamedParams(D::AreaLightSource)),
        ("Material", NamedParams(D::Material)),
        ("MakeNamedMaterial", NamedParams(D::MakeNamedMaterial)),
        ("NamedMaterial", OneString(D::NamedMaterial)),
        ("Texture", Texture),
        ("Shape", NamedParams(D::Shape)),
        ("Include", Include),
    ]
};

/// Parses `text`, the contents of `file`, appending its directives (and those of its includes) to `out`.
pub(crate) fn parse_text(
    text: &str,
    file: Arc<Path>,
    includes: &mut IncludeStack,
    out: &mut Vec<Directive>,
) -> Result<()> {
    let mut p = Parser { text, lex: Lexer::new(text), peeked: None, lines: LineIndex::new(text), file, includes, out };
    p.run()
}

/// The parsing state of one file.
struct Parser<'t, 's> {
    text: &'t str,
    lex: Lexer<'t>,
    peeked: Option<Token<'t>>,
    lines: LineIndex,
    file: Arc<Path>,
    includes: &'s mut IncludeStack,
    out: &'s mut Vec<Directive>,
}

/// How a token (or the end of the file) is shown after "found": as written, shortened when long.
fn describe(tok: Option<&Token>) -> String {
    const MAX: usize = 40;
    match tok {
        None => "end of file".into(),
        Some(t) if t.src.chars().count() > MAX => format!("{}...", t.src.chars().take(MAX - 3).collect::<String>()),
        Some(t) => t.src.to_owned(),
    }
}

impl<'t> Parser<'t, '_> {
    fn loc(&self, offset: usize) -> SourceLoc {
        let (line, col) = self.lines.line_col(self.text, offset);
        SourceLoc::new(self.file.clone(), line, col)
    }

    fn peek(&mut self) -> Result<Option<&Token<'t>>> {
        if self.peeked.is_none() {
            let next = self.lex.next_token();
            self.peeked = next.map_err(|e| Error::at(&self.loc(e.offset), e.msg))?;
        }
        Ok(self.peeked.as_ref())
    }

    fn next(&mut self) -> Result<Option<Token<'t>>> {
        self.peek()?;
        Ok(self.peeked.take())
    }

    fn run(&mut self) -> Result<()> {
        while let Some(tok) = self.next()? {
            let Tok::Word(word) = tok.tok else {
                return Err(Error::at(
                    &self.loc(tok.offset),
                    format!("expected a directive, found {}", describe(Some(&tok))),
                ));
            };
            let loc = self.loc(tok.offset);
            let Some(&(_, syntax)) = DIRECTIVES.iter().find(|(kw, _)| *kw == word) else {
                return Err(Error::at(&loc, unknown_directive(word)));
            };
            if let Some(kind) = self.directive(word, syntax, &loc)? {
                self.out.push(Directive { kind, loc });
            }
        }
        Ok(())
    }

    /// Reads the arguments of directive `kw` (at `loc`); `None` for `Include`, whose directives are already
    /// in the list.
    fn directive(&mut self, kw: &str, syntax: Syntax, loc: &SourceLoc) -> Result<Option<DirectiveKind>> {
        Ok(Some(match syntax {
            Syntax::Bare(make) => make(),
            Syntax::Numbers(n, make) => make(&self.numbers(kw, loc, n)?),
            Syntax::OneString(make) => make(self.string_arg(kw, loc)?.0),
            Syntax::NamedParams(make) => make(self.named(kw, loc)?),
            Syntax::ActiveTransform => DirectiveKind::ActiveTransform(self.active_transform(loc)?),
            Syntax::MediumInterface => self.medium_interface(loc)?,
            Syntax::Texture => self.texture(loc)?,
            Syntax::Include => {
                let (name, _) = self.string_arg(kw, loc)?;
                super::include(&name, &self.file, loc, self.includes, self.out)?;
                return Ok(None);
            }
        }))
    }

    /// Exactly `n` numbers, bare or in one pair of brackets; any other count is an error at the directive.
    fn numbers(&mut self, kw: &str, loc: &SourceLoc, n: usize) -> Result<Vec<f64>> {
        let bracketed = matches!(self.peek()?, Some(Token { tok: Tok::Open, .. }));
        if bracketed {
            self.next()?;
        }
        let mut v = Vec::with_capacity(n);
        while let Some(&Token { tok: Tok::Num(x), .. }) = self.peek()? {
            v.push(x);
            self.next()?;
        }
        let stop = self.peek()?;
        let closed = matches!(stop, Some(Token { tok: Tok::Close, .. }));
        if v.len() == n && bracketed == closed {
            if bracketed {
                self.next()?;
            }
            return Ok(v);
        }
        // A bare word that is no directive where a number belongs ("nan", "inf", "1e"): point at it.
        if let Some(Token { tok: Tok::Word(w), offset, .. }) = stop
            && v.len() < n
            && !DIRECTIVES.iter().any(|(d, _)| d == w)
        {
            let lower = w.to_ascii_lowercase();
            let hint = if ["nan", "inf", "infinity"].contains(&lower.trim_start_matches(['-', '+'])) {
                " (values must be finite numbers)"
            } else {
                ""
            };
            let msg = format!("{kw}: expected {n} numbers, found {w}{hint}");
            let offset = *offset;
            return Err(Error::at(&self.loc(offset), msg));
        }
        // Name the token that stopped the list when it is not simply the next directive.
        let odd_stop = match stop.map(|t| &t.tok) {
            None | Some(Tok::Word(_)) => bracketed,
            Some(Tok::Close) => !bracketed,
            Some(_) => true,
        };
        let msg = if v.len() == n {
            format!("{kw}: expected ] after {n} numbers, found {}", describe(stop))
        } else if v.len() < n && odd_stop {
            format!("{kw}: expected {n} numbers, found {}", describe(stop))
        } else {
            format!("{kw}: expected {n} numbers, found {}", v.len())
        };
        Err(Error::at(loc, msg))
    }

    /// One quoted string argument of directive `kw` and where it is.
    fn string_arg(&mut self, kw: &str, loc: &SourceLoc) -> Result<(String, SourceLoc)> {
        match self.next()? {
            Some(Token { tok: Tok::Str(s), offset, .. }) => Ok((s.into_owned(), self.loc(offset))),
            other => {
                Err(Error::at(loc, format!("expected a quoted string after {kw}, found {}", describe(other.as_ref()))))
            }
        }
    }

    /// A quoted type or name and the parameters after it.
    fn named(&mut self, kw: &str, loc: &SourceLoc) -> Result<Named> {
        let (name, name_loc) = self.string_arg(kw, loc)?;
        Ok(Named { name, name_loc, params: self.params()? })
    }

    fn active_transform(&mut self, loc: &SourceLoc) -> Result<ActiveTransform> {
        let tok = self.next()?;
        Ok(match tok.as_ref().map(|t| &t.tok) {
            Some(Tok::Word("StartTime")) => ActiveTransform::Start,
            Some(Tok::Word("EndTime")) => ActiveTransform::End,
            Some(Tok::Word("All")) => ActiveTransform::All,
            _ => {
                let msg =
                    format!("ActiveTransform: expected StartTime, EndTime or All, found {}", describe(tok.as_ref()));
                return Err(Error::at(loc, msg));
            }
        })
    }

    /// One or two medium names; one names both sides.
    fn medium_interface(&mut self, loc: &SourceLoc) -> Result<DirectiveKind> {
        let (inside, _) = self.string_arg("MediumInterface", loc)?;
        let outside = match self.peek()? {
            Some(Token { tok: Tok::Str(_), .. }) => self.string_arg("MediumInterface", loc)?.0,
            _ => inside.clone(),
        };
        Ok(DirectiveKind::MediumInterface(inside, outside))
    }

    fn texture(&mut self, loc: &SourceLoc) -> Result<DirectiveKind> {
        let (name, _) = self.string_arg("Texture", loc)?;
        let (value_type, _) = self.string_arg("Texture", loc)?;
        let class = self.named("Texture", loc)?;
        Ok(DirectiveKind::Texture { name, value_type, class })
    }

    /// `"type name" value` entries, as long as the next token is a quoted string.
    fn params(&mut self) -> Result<ParamList> {
        let mut params = Vec::new();
        while let Some(Token { tok: Tok::Str(_), .. }) = self.peek()? {
            if let Some(Token { tok: Tok::Str(decl), offset, .. }) = self.next()? {
                params.push(self.param(&decl, offset)?);
            }
        }
        Ok(ParamList::new(params))
    }

    /// One parameter whose declaration string `decl` starts at `offset`.
    fn param(&mut self, decl: &str, offset: usize) -> Result<Param> {
        let loc = self.loc(offset);
        let mut words = decl.split_whitespace();
        let (Some(ty_word), Some(name), None) = (words.next(), words.next(), words.next()) else {
            return Err(Error::at(&loc, format!("expected \"type name\" in parameter declaration, found \"{decl}\"")));
        };
        let ty = ParamType::from_word(ty_word)
            .ok_or_else(|| Error::at(&loc, format!("unknown parameter type \"{ty_word}\"")))?;
        let value = self.values(ty, name, offset)?;
        check_count(ty, name, &value, &loc)?;
        Ok(Param::new(ty, name, value, loc))
    }

    /// The value(s) of parameter `name` of type `ty`: one bare value or a bracketed list.
    fn values(&mut self, ty: ParamType, name: &str, decl_offset: usize) -> Result<ParamValue> {
        let mut acc = match ty {
            ParamType::String | ParamType::Texture => ParamValue::Strings(Vec::new()),
            ParamType::Bool => ParamValue::Bools(Vec::new()),
            _ => ParamValue::Numbers(Vec::new()),
        };
        let first = self.next()?;
        match first.as_ref().map(|t| &t.tok) {
            Some(Tok::Open) => {
                let open = first.as_ref().map_or(decl_offset, |t| t.offset);
                self.list(ty, name, open, &mut acc)?;
            }
            Some(Tok::Num(_) | Tok::Str(_) | Tok::Word("true" | "false")) => {
                if let Some(tok) = first {
                    self.add_value(ty, name, tok, &mut acc)?;
                }
                if let Some(&Token { tok: Tok::Num(_) | Tok::Word("true" | "false"), offset, src }) = self.peek()? {
                    let msg = format!("parameter \"{name}\": several values must be in brackets, found {src}");
                    return Err(Error::at(&self.loc(offset), msg));
                }
            }
            _ => {
                let at = first.as_ref().map_or(decl_offset, |t| t.offset);
                let msg = format!("parameter \"{name}\": expected a value, found {}", describe(first.as_ref()));
                return Err(Error::at(&self.loc(at), msg));
            }
        }
        Ok(acc)
    }

    /// The values of a bracketed list up to its `]`; the `[` was at `open`.
    fn list(&mut self, ty: ParamType, name: &str, open: usize, acc: &mut ParamValue) -> Result<()> {
        loop {
            let tok = self.next()?;
            match tok {
                Some(Token { tok: Tok::Close, .. }) => return Ok(()),
                Some(t @ Token { tok: Tok::Num(_) | Tok::Str(_) | Tok::Word("true" | "false"), .. }) => {
                    self.add_value(ty, name, t, acc)?;
                }
                None => {
                    let msg = format!("parameter \"{name}\": expected ] to close the list, found end of file");
                    return Err(Error::at(&self.loc(open), msg));
                }
                Some(t) => {
                    let msg = format!("parameter \"{name}\": expected a value or ], found {}", describe(Some(&t)));
                    return Err(Error::at(&self.loc(t.offset), msg));
                }
            }
        }
    }

    /// Adds one value token to `acc`, checking it suits type `ty`.
    fn add_value(&self, ty: ParamType, name: &str, tok: Token<'t>, acc: &mut ParamValue) -> Result<()> {
        let fail = |msg: String| Err(Error::at(&self.loc(tok.offset), format!("parameter \"{name}\": {msg}")));
        let wrong = |what: &str| fail(format!("expected {what}, found {}", describe(Some(&tok))));
        if ty == ParamType::Spectrum {
            // A spectrum is numbers or a file name; the first value decides which.
            match (&*acc, &tok.tok) {
                (ParamValue::Numbers(v), Tok::Str(_)) if v.is_empty() => *acc = ParamValue::Strings(Vec::new()),
                (ParamValue::Numbers(_), Tok::Str(_)) | (ParamValue::Strings(_), Tok::Num(_)) => {
                    return fail(format!("mixed strings and numbers, found {}", describe(Some(&tok))));
                }
                _ => {}
            }
        }
        match (acc, &tok.tok) {
            (ParamValue::Numbers(v), Tok::Num(x)) => {
                if ty == ParamType::Integer && x.fract() != 0.0 {
                    let msg = format!("integer parameter \"{name}\": {} is not an integer", tok.src);
                    return Err(Error::at(&self.loc(tok.offset), msg));
                }
                v.push(*x);
            }
            (ParamValue::Bools(v), Tok::Word(w)) => v.push(*w == "true"),
            (ParamValue::Bools(v), Tok::Str(s)) if s == "true" || s == "false" => v.push(s == "true"),
            (ParamValue::Bools(_), _) => return wrong("true or false"),
            (ParamValue::Strings(v), Tok::Str(s)) => v.push(s.clone().into_owned()),
            (ParamValue::Numbers(_), _) => return wrong("a number"),
            (ParamValue::Strings(_), _) => return wrong("a quoted string"),
        }
        Ok(())
    }
}

/// Checks that tuple types have whole tuples and a spectrum file is named once.
fn check_count(ty: ParamType, name: &str, value: &ParamValue, loc: &SourceLoc) -> Result<()> {
    match value {
        ParamValue::Numbers(v) if v.len() % ty.tuple_len() != 0 => {
            let msg =
                format!("parameter \"{name}\": expected a multiple of {} numbers, got {}", ty.tuple_len(), v.len());
            Err(Error::at(loc, msg))
        }
        ParamValue::Strings(v) if ty == ParamType::Spectrum && v.len() != 1 => {
            Err(Error::at(loc, format!("parameter \"{name}\": expected one spectrum file name, got {}", v.len())))
        }
        _ => Ok(()),
    }
}

/// pbrt-v2 directives that pbrt-v3 dropped, with what a pbrt-v3 scene writes instead.
const PBRT_V2_DIRECTIVES: [(&str, &str); 3] = [
    ("SurfaceIntegrator", "pbrt-v3 scenes name their integrator with \"Integrator\""),
    ("VolumeIntegrator", "pbrt-v3 has no volume integrator directive"),
    ("Renderer", "pbrt-v3 has no renderer directive"),
];

/// "unknown directive" with the closest keyword, when one is close (or what replaced a pbrt-v2 directive).
fn unknown_directive(word: &str) -> String {
    if let Some((_, instead)) = PBRT_V2_DIRECTIVES.iter().find(|(kw, _)| *kw == word) {
        return format!("\"{word}\" is a pbrt-v2 directive, not pbrt-v3's: {instead}");
    }
    let keywords = DIRECTIVES.iter().map(|(kw, _)| *kw);
    match closest(word, keywords) {
        Some(kw) => format!("unknown directive \"{word}\" (did you mean \"{kw}\"?)"),
        None => format!("unknown directive \"{word}\""),
    }
}

/// The candidate nearest to `word` by edit distance (ignoring case), if it is within two edits or a third of
/// its length.
pub(crate) fn closest<'a>(word: &str, candidates: impl Iterator<Item = &'a str>) -> Option<&'a str> {
    let lower = word.to_lowercase();
    let (dist, best) = candidates.map(|c| (edit_distance(&lower, &c.to_lowercase()), c)).min_by_key(|&(d, _)| d)?;
    (dist <= (best.len() / 3).max(2) && dist < best.len()).then_some(best)
}

/// Levenshtein distance between two strings, by characters.
fn edit_distance(a: &str, b: &str) -> usize {
    let b: Vec<char> = b.chars().collect();
    let mut row: Vec<usize> = (0..=b.len()).collect();
    for (i, ca) in a.chars().enumerate() {
        let mut diag = i;
        let mut prev = i + 1;
        for (cb, up) in b.iter().zip(row.iter_mut().skip(1)) {
            let cost = diag + usize::from(ca != *cb);
            diag = *up;
            prev = cost.min(diag + 1).min(prev + 1);
            *up = prev;
        }
        if let Some(first) = row.first_mut() {
            *first = i + 1;
        }
    }
    row.last().copied().unwrap_or(0)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::parse::parse_str;

    fn parse(text: &str) -> Vec<Directive> {
        parse_str(text, Path::new("t.pbrt")).unwrap()
    }

    /// The full message of the error `text` gives, with its `file:line:col`.
    fn err(text: &str) -> String {
        parse_str(text, Path::new("t.pbrt")).unwrap_err().to_string()
    }

    fn named(d: &Directive) -> &Named {
        match &d.kind {
            DirectiveKind::Shape(n) | DirectiveKind::Camera(n) | DirectiveKind::Material(n) => n,
            DirectiveKind::Texture { class, .. } => class,
            other => panic!("not a named directive: {other:?}"),
        }
    }

    #[test]
    fn every_directive() {
        let text = r#"
            Identity Translate 1 2 3 Scale [2 2 2] Rotate 90 0 0 1 LookAt 0 0 5  0 0 0  0 1 0
            CoordinateSystem "cam" CoordSysTransform "cam"
            Transform [1 0 0 0 0 1 0 0 0 0 1 0 0 0 0 1]
            ConcatTransform 1 0 0 0 0 1 0 0 0 0 1 0 4 5 6 1
            TransformTimes 0 1 ActiveTransform StartTime ActiveTransform EndTime ActiveTransform All
            ReverseOrientation
            Camera "perspective" "float fov" 45 Sampler "halton" Film "image" PixelFilter "box"
            Integrator "path" Accelerator "bvh" MakeNamedMedium "fog" "string type" "homogeneous"
            MediumInterface "fog" MediumInterface "in" "out"
            WorldBegin AttributeBegin AttributeEnd TransformBegin TransformEnd
            ObjectBegin "o" ObjectEnd ObjectInstance "o"
            LightSource "point" AreaLightSource "diffuse" Material "matte" MakeNamedMaterial "m"
            NamedMaterial "m" Texture "t" "spectrum" "checkerboard" Shape "sphere"
            WorldEnd
        "#;
        let ds = parse(text);
        let kws: Vec<&str> = ds.iter().map(|d| d.kind.keyword()).collect();
        assert_eq!(kws.len(), 39);
        for (kw, _) in DIRECTIVES.iter().filter(|(kw, _)| *kw != "Include") {
            assert!(kws.contains(kw), "{kw} missing");
        }
        use DirectiveKind as D;
        assert!(matches!(ds[1].kind, D::Translate([1.0, 2.0, 3.0])));
        assert!(matches!(ds[2].kind, D::Scale([2.0, 2.0, 2.0])));
        assert!(matches!(ds[3].kind, D::Rotate([90.0, 0.0, 0.0, 1.0])));
        assert!(matches!(ds[4].kind, D::LookAt(v) if v == [0.0, 0.0, 5.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0]));
        assert!(matches!(&ds[8].kind, D::ConcatTransform(m) if m[12..15] == [4.0, 5.0, 6.0]));
        assert!(matches!(ds[9].kind, D::TransformTimes(0.0, 1.0)));
        assert!(matches!(ds[10].kind, D::ActiveTransform(ActiveTransform::Start)));
        assert!(matches!(ds[11].kind, D::ActiveTransform(ActiveTransform::End)));
        assert!(matches!(ds[12].kind, D::ActiveTransform(ActiveTransform::All)));
        assert!(matches!(&ds[21].kind, D::MediumInterface(a, b) if a == "fog" && b == "fog"));
        assert!(matches!(&ds[22].kind, D::MediumInterface(a, b) if a == "in" && b == "out"));
        assert!(matches!(&ds[35].kind, D::NamedMaterial(m) if m == "m"));
        match &ds[36].kind {
            D::Texture { name, value_type, class } => {
                assert_eq!(
                    (name.as_str(), value_type.as_str(), class.name.as_str()),
                    ("t", "spectrum", "checkerboard")
                );
                assert_eq!(class.name_loc.to_string(), "t.pbrt:14:54");
            }
            other => panic!("{other:?}"),
        }
    }

    #[test]
    fn locations_of_directives_names_and_params() {
        let ds = parse("# header\nWorldBegin\n  Shape \"sphere\"\n     \"float radius\" 2\n");
        assert_eq!(ds[1].loc.to_string(), "t.pbrt:3:3");
        let shape = named(&ds[1]);
        assert_eq!(shape.name_loc.to_string(), "t.pbrt:3:9");
        let p = shape.params.iter().next().unwrap();
        assert_eq!(p.loc.to_string(), "t.pbrt:4:6");
        assert_eq!((p.ty, p.name.as_str(), &p.value), (ParamType::Float, "radius", &ParamValue::Numbers(vec![2.0])));
    }

    #[test]
    fn parameter_values_of_every_kind() {
        let ds = parse(
            r#"Shape "trianglemesh" "integer indices" [0 1 2] "point P" [0 0 0 1 0 0 0 1 0]
            "float uv" [] "bool a" "true" "bool b" [false "false" true] "string s" ["x" "y"]
            "texture t" "wood" "spectrum eta" "Au.eta.spd" "spectrum k" [400 1 500 2] "rgb Kd" [.5 .5 .5]
            "blackbody L" [3000 1.5] "color c" [1 1 1] "normal N" [0 0 1 0 0 1 0 0 1] "point2 st" [0 0 1 1]"#,
        );
        let values: Vec<(&str, &ParamValue)> =
            named(&ds[0]).params.iter().map(|p| (p.name.as_str(), &p.value)).collect();
        use ParamValue::*;
        assert_eq!(values[0], ("indices", &Numbers(vec![0.0, 1.0, 2.0])));
        assert_eq!(values[2], ("uv", &Numbers(vec![])));
        assert_eq!(values[3], ("a", &Bools(vec![true])));
        assert_eq!(values[4], ("b", &Bools(vec![false, false, true])));
        assert_eq!(values[5], ("s", &Strings(vec!["x".into(), "y".into()])));
        assert_eq!(values[6], ("t", &Strings(vec!["wood".into()])));
        assert_eq!(values[7], ("eta", &Strings(vec!["Au.eta.spd".into()])));
        assert_eq!(values[8], ("k", &Numbers(vec![400.0, 1.0, 500.0, 2.0])));
        assert_eq!(values[9], ("Kd", &Numbers(vec![0.5; 3])));
        assert_eq!(values.len(), 14);
        let color = named(&ds[0]).params.get("c").unwrap();
        assert_eq!(color.ty, ParamType::Rgb);
    }

    #[test]
    fn a_parameter_given_twice_keeps_the_later_value() {
        let ds = parse(r#"Camera "perspective" "float fov" 30 "float fov" [60]"#);
        assert_eq!(named(&ds[0]).params.float("fov").unwrap(), Some(60.0));
    }

    #[test]
    fn medium_interface_with_an_empty_outside() {
        let ds = parse(r#"MediumInterface "green" "" Shape "sphere""#);
        assert!(matches!(&ds[0].kind, DirectiveKind::MediumInterface(a, b) if a == "green" && b.is_empty()));
        assert_eq!(ds.len(), 2);
    }

    #[test]
    fn transform_numbers_bare_or_bracketed() {
        let m = "1 0 0 0 0 1 0 0 0 0 1 0 0 0 0 1";
        for text in [format!("Transform [{m}]"), format!("Transform {m}"), format!("Transform [ {m} ]\n")] {
            assert!(matches!(parse(&text)[0].kind, DirectiveKind::Transform(t) if t[15] == 1.0), "{text}");
        }
        assert!(matches!(parse("Translate [1 2 3]")[0].kind, DirectiveKind::Translate([1.0, 2.0, 3.0])));
    }

    #[test]
    fn argument_errors_are_at_the_directive() {
        assert_eq!(err("Translate 1 2\nShape \"sphere\""), "t.pbrt:1:1: Translate: expected 3 numbers, found 2");
        assert_eq!(err("  Translate 1 2 \"foo\""), "t.pbrt:1:3: Translate: expected 3 numbers, found \"foo\"");
        assert_eq!(err("Translate 1 2 3 4"), "t.pbrt:1:1: Translate: expected 3 numbers, found 4");
        assert_eq!(err("Rotate 1 2 3"), "t.pbrt:1:1: Rotate: expected 4 numbers, found 3");
        assert_eq!(err("Translate [1 2]"), "t.pbrt:1:1: Translate: expected 3 numbers, found 2");
        assert_eq!(err("Translate [1 2 Shape"), "t.pbrt:1:1: Translate: expected 3 numbers, found Shape");
        assert_eq!(err("Translate 1 2 ]"), "t.pbrt:1:1: Translate: expected 3 numbers, found ]");
        assert_eq!(err("\nTransform [1 2 3]"), "t.pbrt:2:1: Transform: expected 16 numbers, found 3");
        let m = "1 0 0 0 0 1 0 0 0 0 1 0 0 0 0 1";
        assert_eq!(
            err(&format!("Transform [{m}")),
            "t.pbrt:1:1: Transform: expected ] after 16 numbers, found end of file"
        );
        assert_eq!(err(&format!("Transform [{m} 2]")), "t.pbrt:1:1: Transform: expected 16 numbers, found 17");
        assert_eq!(err("Shape 3"), "t.pbrt:1:1: expected a quoted string after Shape, found 3");
        assert_eq!(err("WorldBegin\nShape"), "t.pbrt:2:1: expected a quoted string after Shape, found end of file");
        assert_eq!(err("Texture \"t\" \"float\" 2"), "t.pbrt:1:1: expected a quoted string after Texture, found 2");
        assert_eq!(
            err("ActiveTransform Start"),
            "t.pbrt:1:1: ActiveTransform: expected StartTime, EndTime or All, found Start"
        );
    }

    #[test]
    fn unknown_and_stray_tokens() {
        assert_eq!(
            err("WorldBegin\n Shpae \"sphere\""),
            "t.pbrt:2:2: unknown directive \"Shpae\" (did you mean \"Shape\"?)"
        );
        assert_eq!(
            err("attributebegin"),
            "t.pbrt:1:1: unknown directive \"attributebegin\" (did you mean \"AttributeBegin\"?)"
        );
        assert_eq!(err("Frobnicate"), "t.pbrt:1:1: unknown directive \"Frobnicate\"");
        assert_eq!(
            err("SurfaceIntegrator \"path\""),
            "t.pbrt:1:1: \"SurfaceIntegrator\" is a pbrt-v2 directive, not pbrt-v3's: pbrt-v3 scenes name their integrator with \"Integrator\""
        );
        assert_eq!(err("WorldBegin 3"), "t.pbrt:1:12: expected a directive, found 3");
        assert_eq!(err("Shape \"sphere\" \"float radius\" [1] [2]"), "t.pbrt:1:35: expected a directive, found [");
        let long = format!("\"{}\"", "x".repeat(60));
        assert_eq!(err(&long), format!("t.pbrt:1:1: expected a directive, found \"{}...", "x".repeat(36)));
    }

    #[test]
    fn token_errors_carry_their_location() {
        assert_eq!(err("Shape \"sphere\n\"float radius\" 1"), "t.pbrt:1:7: unterminated string");
        assert_eq!(err("WorldBegin\nTranslate 1 1.2.3 3"), "t.pbrt:2:13: malformed number \"1.2.3\"");
        assert_eq!(err("Shape \"sphere\" \"float radius\" 3x"), "t.pbrt:1:31: malformed number \"3x\"");
    }

    #[test]
    fn parameter_errors() {
        let cases = [
            (r#"Shape "x" "float3 P" [1]"#, r#"t.pbrt:1:11: unknown parameter type "float3""#),
            (
                r#"Shape "x" "floatradius" 1"#,
                r#"t.pbrt:1:11: expected "type name" in parameter declaration, found "floatradius""#,
            ),
            (
                r#"Shape "x" "float a b" 1"#,
                r#"t.pbrt:1:11: expected "type name" in parameter declaration, found "float a b""#,
            ),
            (r#"Shape "x" "integer n" [1 1.5]"#, r#"t.pbrt:1:26: integer parameter "n": 1.5 is not an integer"#),
            (
                "Shape \"x\"\n  \"point3 P\" [1 2 3 4 5 6 7]",
                r#"t.pbrt:2:3: parameter "P": expected a multiple of 3 numbers, got 7"#,
            ),
            (
                r#"Shape "x" "point2 uv" [1 2 3]"#,
                r#"t.pbrt:1:11: parameter "uv": expected a multiple of 2 numbers, got 3"#,
            ),
            (r#"Shape "x" "float r" [1 "a"]"#, r#"t.pbrt:1:24: parameter "r": expected a number, found "a""#),
            (r#"Shape "x" "float r" true"#, r#"t.pbrt:1:21: parameter "r": expected a number, found true"#),
            (r#"Shape "x" "string s" ["a" 1]"#, r#"t.pbrt:1:27: parameter "s": expected a quoted string, found 1"#),
            (r#"Shape "x" "texture t" 1"#, r#"t.pbrt:1:23: parameter "t": expected a quoted string, found 1"#),
            (r#"Shape "x" "bool b" "yes""#, r#"t.pbrt:1:20: parameter "b": expected true or false, found "yes""#),
            (r#"Shape "x" "bool b" [1]"#, r#"t.pbrt:1:21: parameter "b": expected true or false, found 1"#),
            (
                r#"Shape "x" "spectrum s" [400 "a"]"#,
                r#"t.pbrt:1:29: parameter "s": mixed strings and numbers, found "a""#,
            ),
            (
                r#"Shape "x" "spectrum s" ["a" 400]"#,
                r#"t.pbrt:1:29: parameter "s": mixed strings and numbers, found 400"#,
            ),
            (
                r#"Shape "x" "spectrum s" ["a" "b"]"#,
                r#"t.pbrt:1:11: parameter "s": expected one spectrum file name, got 2"#,
            ),
            (
                r#"Shape "x" "spectrum s" [400 1 500]"#,
                r#"t.pbrt:1:11: parameter "s": expected a multiple of 2 numbers, got 3"#,
            ),
            (r#"Shape "x" "float r" Shape "y""#, r#"t.pbrt:1:21: parameter "r": expected a value, found Shape"#),
            (r#"Shape "x" "float r" ]"#, r#"t.pbrt:1:21: parameter "r": expected a value, found ]"#),
            (r#"Shape "x" "float r""#, r#"t.pbrt:1:11: parameter "r": expected a value, found end of file"#),
            (
                "Shape \"x\" \"float r\" [1\n2",
                r#"t.pbrt:1:21: parameter "r": expected ] to close the list, found end of file"#,
            ),
            (r#"Shape "x" "float r" [1 Shape"#, r#"t.pbrt:1:24: parameter "r": expected a value or ], found Shape"#),
            (r#"Shape "x" "float r" [1 [2]]"#, r#"t.pbrt:1:24: parameter "r": expected a value or ], found ["#),
            (
                r#"Shape "x" "float r" 1 2"#,
                r#"t.pbrt:1:23: parameter "r": several values must be in brackets, found 2"#,
            ),
        ];
        for (text, want) in cases {
            assert_eq!(err(text), want, "{text}");
        }
    }

    #[test]
    fn mangled_scenes_never_panic() {
        let base = r#"LookAt 0 0 5 0 0 0 0 1 0 Camera "perspective" "float fov" [45]
WorldBegin AttributeBegin Material "matte" "rgb Kd" [.5 .5 .5] "bool b" "true" "spectrum s" "x.spd"
Shape "trianglemesh" "point P" [0 0 0 1 0 0 0 1 0] "integer indices" [0 1 2] # comment
Texture "t" "spectrum" "imagemap" "string filename" "a\"b.png" AttributeEnd TransformTimes 0 1
MediumInterface "a" "" ActiveTransform All Transform [1 0 0 0 0 1 0 0 0 0 1 0 0 0 0 1] WorldEnd"#;
        let pieces = ["\"", "[", "]", "#", "\\", "\n", "-", ".", "e", "1", " ", "é", "Shape", "\"float x\"", "true"];
        let mut state = 0x2545_f491_4f6c_dd1d_u64;
        let mut rand = |n: usize| {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            (state % n as u64) as usize
        };
        for _ in 0..5000 {
            let mut chars: Vec<char> = base.chars().collect();
            for _ in 0..1 + rand(4) {
                let at = rand(chars.len() + 1);
                match rand(3) {
                    0 if at < chars.len() => {
                        chars.remove(at);
                    }
                    1 => chars.truncate(at),
                    _ => chars.splice(at..at, pieces[rand(pieces.len())].chars()).for_each(drop),
                }
            }
            let text: String = chars.into_iter().collect();
            if let Err(e) = parse_str(&text, Path::new("t.pbrt")) {
                let loc = e.loc().expect("scene errors have a location");
                assert!(loc.line as usize <= text.lines().count() + 1, "{e} in {text:?}");
            }
        }
    }

    #[test]
    fn suggestions_only_for_near_misses() {
        assert_eq!(closest("Shpae", DIRECTIVES.iter().map(|d| d.0)), Some("Shape"));
        assert_eq!(closest("WorldBgin", DIRECTIVES.iter().map(|d| d.0)), Some("WorldBegin"));
        assert_eq!(closest("xyz", DIRECTIVES.iter().map(|d| d.0)), None);
        assert_eq!(edit_distance("kitten", "sitting"), 3);
        assert_eq!(edit_distance("", "abc"), 3);
        assert_eq!(edit_distance("abc", "abc"), 0);
    }
}
