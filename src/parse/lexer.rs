//! STAGE 1 (parse): the tokenizer, written with nom. Scene text → [`Token`]s with byte offsets.
//!
//! Tokens are quoted strings (with `\"`, `\\`, `\n`, `\t` and pbrt-v3's other escapes), `[`, `]`, numbers
//! (every form pbrt-v3 reads: `-.5`, `1e-3`, `+2`, `5.`, `1E+4`, `.5e2`) and bare words (directive keywords,
//! `true`/`false`). `#` starts a comment to the end of the line. A token keeps its byte offset; the
//! [`LineIndex`] turns offsets into line and column only when a location is needed. Knows nothing about
//! directives.
#![cfg_attr(not(test), deny(clippy::indexing_slicing, clippy::panic))]

use std::borrow::Cow;
use std::cell::Cell;

use nom::branch::alt;
use nom::bytes::complete::take_till;
use nom::character::complete::{char, digit0, digit1, multispace0, one_of};
use nom::combinator::{all_consuming, opt, recognize};
use nom::{IResult, Parser};

/// What a token is.
#[derive(Clone, Debug, PartialEq)]
pub(crate) enum Tok<'a> {
    /// A quoted string, escapes decoded (borrowed when it has none).
    Str(Cow<'a, str>),
    /// `[`
    Open,
    /// `]`
    Close,
    /// A number.
    Num(f64),
    /// A bare word: a directive keyword, `true`, `false`, `StartTime` …
    Word(&'a str),
}

/// One token, where it starts and its text as written.
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct Token<'a> {
    /// What it is.
    pub tok: Tok<'a>,
    /// Byte offset of its first character in the file.
    pub offset: usize,
    /// The token as written (strings with their quotes), for messages.
    pub src: &'a str,
}

/// A tokenizing error at a byte offset.
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct LexError {
    /// Where the bad token starts.
    pub offset: usize,
    /// What is wrong with it.
    pub msg: String,
}

/// Splits one file's text into tokens, front to back.
#[derive(Debug)]
pub(crate) struct Lexer<'a> {
    text: &'a str,
    rest: &'a str,
}

/// nom's result with the unit error: the lexer makes its own messages.
type Res<'a, T> = IResult<&'a str, T, ()>;

impl<'a> Lexer<'a> {
    /// A lexer at the start of `text` (a leading byte-order mark is skipped).
    pub fn new(text: &'a str) -> Self {
        let rest = text.strip_prefix('\u{feff}').unwrap_or(text);
        Lexer { text, rest }
    }

    /// Byte offset of `s`, a suffix of the text.
    fn offset_of(&self, s: &str) -> usize {
        self.text.len() - s.len()
    }

    /// The next token, `None` at the end of the text.
    pub fn next_token(&mut self) -> Result<Option<Token<'a>>, LexError> {
        self.rest = skip_blanks(self.rest);
        let start = self.rest;
        let offset = self.offset_of(start);
        let Some(first) = start.chars().next() else { return Ok(None) };
        let (rest, tok) = match first {
            '"' => quoted(start).map_err(|e| LexError { offset: self.offset_of(e.at), msg: e.msg })?,
            '[' => (start.get(1..).unwrap_or(""), Tok::Open),
            ']' => (start.get(1..).unwrap_or(""), Tok::Close),
            _ => bare(start).map_err(|msg| LexError { offset, msg })?,
        };
        self.rest = rest;
        let src = start.get(..start.len() - rest.len()).unwrap_or(start);
        Ok(Some(Token { tok, offset, src }))
    }
}

/// Skips white space and `#` comments.
fn skip_blanks(mut s: &str) -> &str {
    loop {
        let r: Res<&str> = multispace0(s);
        s = r.map_or(s, |(rest, _)| rest);
        match s.strip_prefix('#') {
            Some(comment) => s = till(comment, |c| c == '\n' || c == '\r').0,
            None => return s,
        }
    }
}

/// Splits `s` before the first character for which `stop` holds (all of `s` when none does).
fn till(s: &str, stop: impl Fn(char) -> bool) -> (&str, &str) {
    let r: Res<&str> = take_till(stop)(s);
    r.unwrap_or(("", s))
}

/// Characters that end a bare word or number.
fn ends_bare(c: char) -> bool {
    matches!(c, ' ' | '\t' | '\n' | '\r' | '"' | '[' | ']' | '#')
}

/// A bare token: a number when it starts like one, a word otherwise.
fn bare(s: &str) -> Result<(&str, Tok<'_>), String> {
    let (rest, word) = till(s, ends_bare);
    if !word.starts_with(|c: char| c.is_ascii_digit() || matches!(c, '+' | '-' | '.')) {
        return Ok((rest, Tok::Word(word)));
    }
    let valid: Res<&str> = all_consuming(number).parse_complete(word);
    match (valid, word.parse::<f64>()) {
        (Ok(_), Ok(x)) => Ok((rest, Tok::Num(x))),
        _ => Err(format!("malformed number \"{word}\"")),
    }
}

/// pbrt-v3's number syntax: `[+-] (digits [. digits] | . digits) [(e|E) [+-] digits]`.
fn number(s: &str) -> Res<'_, &str> {
    let mantissa = alt((recognize((digit1, opt((char('.'), digit0)))), recognize((char('.'), digit1))));
    let exponent = (one_of("eE"), opt(one_of("+-")), digit1);
    recognize((opt(one_of("+-")), mantissa, opt(exponent))).parse_complete(s)
}

/// Where a quoted string went wrong: the suffix of the text at the fault, and the message.
struct StrError<'a> {
    at: &'a str,
    msg: String,
}

/// A quoted string starting at `s` (which begins with `"`). An end of line or of file before the closing
/// quote is "unterminated string" at the opening quote.
fn quoted(s: &str) -> Result<(&str, Tok<'_>), StrError<'_>> {
    let body = s.get(1..).unwrap_or("");
    let unterminated = || StrError { at: s, msg: "unterminated string".into() };
    let mut decoded: Option<String> = None;
    let mut rest = body;
    loop {
        let (after, run) = till(rest, |c| matches!(c, '"' | '\\' | '\n'));
        let mut chars = after.chars();
        match chars.next() {
            Some('"') => {
                let text = match decoded {
                    Some(mut d) => {
                        d.push_str(run);
                        Cow::Owned(d)
                    }
                    None => Cow::Borrowed(body.get(..body.len() - after.len()).unwrap_or("")),
                };
                return Ok((chars.as_str(), Tok::Str(text)));
            }
            Some('\\') => {
                match decoded.as_mut() {
                    Some(d) => d.push_str(run),
                    None => decoded = Some(body.get(..body.len() - after.len()).unwrap_or("").to_owned()),
                }
                let d = decoded.get_or_insert_with(String::new);
                let c = match chars.next() {
                    None | Some('\n') => return Err(unterminated()),
                    Some(c) => c,
                };
                d.push(
                    unescape(c)
                        .ok_or_else(|| StrError { at: after, msg: format!("unknown escape \"\\{c}\" in string") })?,
                );
                rest = chars.as_str();
            }
            _ => return Err(unterminated()),
        }
    }
}

/// The character an escape `\c` stands for (pbrt-v3's set), `None` for an unknown escape.
fn unescape(c: char) -> Option<char> {
    Some(match c {
        'n' => '\n',
        't' => '\t',
        'r' => '\r',
        'b' => '\u{8}',
        'f' => '\u{c}',
        '\\' | '"' | '\'' => c,
        _ => return None,
    })
}

/// Byte offsets of line starts of one file, for turning token offsets into 1-based line and column.
///
/// Lookups are a binary search for the line; the column counts characters from the line start, or from the
/// previous lookup when it was on the same line and earlier, so walking a file front to back costs time
/// linear in its length even when a single line holds megabytes of numbers.
#[derive(Debug)]
pub(crate) struct LineIndex {
    starts: Vec<usize>,
    /// The previous answer: (offset, 0-based line, column).
    last: Cell<(usize, usize, u32)>,
}

impl LineIndex {
    /// Indexes the lines of `text`.
    pub fn new(text: &str) -> Self {
        let newlines = text.bytes().enumerate().filter(|&(_, b)| b == b'\n').map(|(i, _)| i + 1);
        LineIndex { starts: std::iter::once(0).chain(newlines).collect(), last: Cell::new((0, 0, 1)) }
    }

    /// 1-based line and column (in characters) of byte `offset` of `text`, the text this index was made from.
    pub fn line_col(&self, text: &str, offset: usize) -> (u32, u32) {
        let offset = offset.min(text.len());
        let line = self.starts.partition_point(|&s| s <= offset).saturating_sub(1);
        let line_start = self.starts.get(line).copied().unwrap_or(0);
        let (last_offset, last_line, last_col) = self.last.get();
        let col = if last_line == line && (line_start..=offset).contains(&last_offset) {
            last_col.saturating_add(chars_between(text, last_offset, offset))
        } else {
            chars_between(text, line_start, offset).saturating_add(1)
        };
        self.last.set((offset, line, col));
        (u32::try_from(line + 1).unwrap_or(u32::MAX), col)
    }
}

/// How many characters start in bytes `a..b` of `text` (UTF-8 continuation bytes are not counted).
fn chars_between(text: &str, a: usize, b: usize) -> u32 {
    let bytes = text.as_bytes().get(a..b).unwrap_or(&[]);
    let n = bytes.iter().filter(|&&byte| byte & 0xC0 != 0x80).count();
    u32::try_from(n).unwrap_or(u32::MAX)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn all(text: &str) -> Result<Vec<Token<'_>>, LexError> {
        let mut lex = Lexer::new(text);
        let mut out = Vec::new();
        while let Some(t) = lex.next_token()? {
            out.push(t);
        }
        Ok(out)
    }

    fn kinds(text: &str) -> Vec<Tok<'_>> {
        all(text).unwrap().into_iter().map(|t| t.tok).collect()
    }

    fn err(text: &str) -> LexError {
        all(text).unwrap_err()
    }

    #[test]
    fn tokens_and_offsets() {
        let text = "Shape \"sphere\" # a comment \"not a string\"\n  \"float radius\" [ 2.5 ]true";
        let toks = all(text).unwrap();
        let got: Vec<(usize, &str)> = toks.iter().map(|t| (t.offset, t.src)).collect();
        assert_eq!(
            got,
            [
                (0, "Shape"),
                (6, "\"sphere\""),
                (44, "\"float radius\""),
                (59, "["),
                (61, "2.5"),
                (65, "]"),
                (66, "true")
            ]
        );
        assert_eq!(toks[0].tok, Tok::Word("Shape"));
        assert_eq!(toks[1].tok, Tok::Str(Cow::Borrowed("sphere")));
        assert_eq!(toks[3].tok, Tok::Open);
        assert_eq!(toks[4].tok, Tok::Num(2.5));
        assert_eq!(toks[5].tok, Tok::Close);
    }

    #[test]
    fn words_end_at_quotes_brackets_and_comments() {
        assert_eq!(
            kinds("Shape\"a\"x[1]#c\nWorldEnd"),
            [
                Tok::Word("Shape"),
                Tok::Str("a".into()),
                Tok::Word("x"),
                Tok::Open,
                Tok::Num(1.0),
                Tok::Close,
                Tok::Word("WorldEnd")
            ]
        );
        assert_eq!(kinds("\u{feff}# only a comment\r\n\t "), []);
    }

    #[test]
    fn every_number_form() {
        let cases = [
            ("-.5", -0.5),
            ("1e-3", 1e-3),
            ("+2", 2.0),
            ("5.", 5.0),
            ("1E+4", 1e4),
            (".5e2", 50.0),
            ("0", 0.0),
            ("-0.25", -0.25),
            ("12345678901234567890", 12345678901234567890.0),
            ("3.5E2", 350.0),
            ("-7e+0", -7.0),
            ("00012", 12.0),
        ];
        for (src, want) in cases {
            assert_eq!(kinds(src), [Tok::Num(want)], "{src}");
        }
    }

    #[test]
    fn malformed_numbers() {
        for bad in ["1.2.3", "1e", "--3", "3x", "-", ".", "+.", "1e+", ".e5", "5..", "1e5.0", "+-1", "0x10"] {
            let e = err(&format!("Translate 1 {bad} 3"));
            assert_eq!(e, LexError { offset: 12, msg: format!("malformed number \"{bad}\"") }, "{bad}");
        }
    }

    #[test]
    fn strings_and_escapes() {
        assert_eq!(
            kinds(r#""a\"b" "c\\d" "e\nf\tg" "#),
            [Tok::Str("a\"b".into()), Tok::Str("c\\d".into()), Tok::Str("e\nf\tg".into())]
        );
        assert_eq!(kinds(r#""x # not a comment""#), [Tok::Str("x # not a comment".into())]);
        assert_eq!(kinds("\"\""), [Tok::Str("".into())]);
        let e = err("Shape \"sph\\qere\"");
        assert_eq!(e, LexError { offset: 10, msg: "unknown escape \"\\q\" in string".into() });
    }

    #[test]
    fn unterminated_strings_point_at_the_opening_quote() {
        let unterminated = |offset| LexError { offset, msg: "unterminated string".into() };
        assert_eq!(err("Shape \"sphere\n\"x\""), unterminated(6));
        assert_eq!(err("Shape \"sphere"), unterminated(6));
        assert_eq!(err("  \"ab\\"), unterminated(2));
        assert_eq!(err("\"ab\\\n\""), unterminated(0));
    }

    #[test]
    fn line_index_counts_lines_and_characters() {
        let text = "ab\nçé \"x\"\n\nlast";
        let idx = LineIndex::new(text);
        let at = |o| idx.line_col(text, o);
        assert_eq!(at(0), (1, 1));
        assert_eq!(at(2), (1, 3));
        assert_eq!(at(3), (2, 1));
        assert_eq!(at(8), (2, 4)); // "ç" and "é" are two bytes each
        assert_eq!(at(7), (2, 3)); // going back on the same line
        assert_eq!(at(12), (3, 1));
        assert_eq!(at(14), (4, 2));
        assert_eq!(at(1000), (4, 5));
        for o in [0, 2, 3, 8, 12, 13, 14, 17] {
            let loc = crate::error::SourceLoc::from_offset(std::sync::Arc::from(std::path::Path::new("f")), text, o);
            assert_eq!(LineIndex::new(text).line_col(text, o), (loc.line, loc.col), "offset {o}");
        }
    }
}
