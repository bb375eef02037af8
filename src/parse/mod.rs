//! STAGE 1: pbrt-v3 scene text → a flat list of [`Directive`]s, each with its file:line:col.
//!
//! The tokenizer (`lexer`) is written with nom; the directive parser (`parser`) builds typed parameter
//! lists. `Include` is followed here (relative to the including file, cycles are an error) so later stages
//! see one list. Nothing in this module knows about rendering; it must not depend on `scene` or anything
//! after it. No input can make it panic: every problem is an [`Error`](crate::Error) with a location.
#![cfg_attr(not(test), deny(clippy::unwrap_used, clippy::expect_used))]

pub mod directive;
mod lexer;
pub mod params;
mod parser;
pub mod spectrum;

pub use directive::{ActiveTransform, Directive, DirectiveKind, Named};
pub use params::{Param, ParamList, ParamType, ParamValue, TexOr};

use std::path::{Path, PathBuf};
use std::sync::Arc;

use crate::error::{Error, Result, SourceLoc};

/// Includes deeper than this are refused (a chain of distinct files this long is surely a mistake).
const MAX_INCLUDE_DEPTH: usize = 100;

/// The files being parsed, outermost first: canonical path (for cycle checks) and the path as shown.
#[derive(Debug, Default)]
pub(crate) struct IncludeStack {
    files: Vec<(PathBuf, Arc<Path>)>,
}

/// Reads and parses the scene file at `path`, inlining every `Include`.
pub fn parse_file(path: &Path) -> Result<Vec<Directive>> {
    let bytes = std::fs::read(path).map_err(|e| Error::file(path, format!("cannot read scene file: {e}")))?;
    let file: Arc<Path> = Arc::from(path);
    let text = decode(bytes, &file)?;
    parse_top(&text, file)
}

/// Parses `text` as if it were the contents of the file `name` (Includes resolve against its folder).
pub fn parse_str(text: &str, name: &Path) -> Result<Vec<Directive>> {
    parse_top(text, Arc::from(name))
}

fn parse_top(text: &str, file: Arc<Path>) -> Result<Vec<Directive>> {
    let mut stack = IncludeStack::default();
    stack.files.push((canonical(&file), file.clone()));
    let mut out = Vec::new();
    parser::parse_text(text, file, &mut stack, &mut out)?;
    Ok(out)
}

/// The path used to recognise a file that includes itself: canonical when the file exists, as given
/// otherwise (text parsed with [`parse_str`] need not exist on disk).
fn canonical(path: &Path) -> PathBuf {
    std::fs::canonicalize(path).unwrap_or_else(|_| path.to_path_buf())
}

/// The text of a scene file; invalid UTF-8 is an error at the first bad byte.
fn decode(bytes: Vec<u8>, file: &Arc<Path>) -> Result<String> {
    String::from_utf8(bytes).map_err(|e| {
        let good = e.utf8_error().valid_up_to();
        let prefix = e.as_bytes().get(..good).and_then(|b| std::str::from_utf8(b).ok()).unwrap_or("");
        let loc = SourceLoc::from_offset(file.clone(), prefix, good);
        Error::at(&loc, "file is not valid UTF-8 text")
    })
}

/// Parses the file named `name` by an `Include` at `at` in `from`, appending its directives to `out`. The name
/// resolves against the folder of `from`; the included directives' locations keep the joined path.
pub(crate) fn include(
    name: &str,
    from: &Path,
    at: &SourceLoc,
    stack: &mut IncludeStack,
    out: &mut Vec<Directive>,
) -> Result<()> {
    let shown: Arc<Path> = Arc::from(from.parent().unwrap_or(Path::new("")).join(name));
    let bytes =
        std::fs::read(&shown).map_err(|e| Error::at(at, format!("cannot read included file \"{name}\": {e}")))?;
    let key = canonical(&shown);
    if let Some(first) = stack.files.iter().position(|(k, _)| *k == key) {
        let chain: Vec<String> = stack.files.iter().skip(first).map(|(_, s)| s.display().to_string()).collect();
        return Err(Error::at(at, format!("Include cycle: {} -> {}", chain.join(" -> "), shown.display())));
    }
    if stack.files.len() >= MAX_INCLUDE_DEPTH {
        return Err(Error::at(at, format!("Include nested more than {MAX_INCLUDE_DEPTH} files deep")));
    }
    let text = decode(bytes, &shown)?;
    stack.files.push((key, shown.clone()));
    let result = parser::parse_text(&text, shown, stack, out);
    stack.files.pop();
    result
}
