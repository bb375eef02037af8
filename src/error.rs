//! Errors, warnings and source locations shared by every pipeline stage.
//!
//! Every problem that comes from user input (a scene file, an included file, a mesh, a flag) becomes an
//! [`Error`]; those that come from a scene file carry a [`SourceLoc`] and print as
//! `file:line:col: message`. [`Error::excerpt`] re-reads the offending line and puts a caret under the
//! column, so the location costs nothing until a message is actually printed.
//!
//! This module depends on nothing else in the crate.

use std::fmt;
use std::path::{Path, PathBuf};
use std::sync::Arc;

/// A position in a scene file: the file, a 1-based line and a 1-based column (in characters).
#[derive(Clone, Debug, PartialEq, Eq, Hash)]
pub struct SourceLoc {
    /// The file as it was named (relative paths stay relative, so messages stay short).
    pub file: Arc<Path>,
    /// 1-based line number.
    pub line: u32,
    /// 1-based column, counted in characters.
    pub col: u32,
}

impl SourceLoc {
    /// Makes a location from its parts.
    pub fn new(file: Arc<Path>, line: u32, col: u32) -> Self {
        SourceLoc { file, line, col }
    }

    /// Computes line and column of byte `offset` in `text` (the whole file), lazily, for reporting.
    pub fn from_offset(file: Arc<Path>, text: &str, offset: usize) -> Self {
        let offset = offset.min(text.len());
        let before = &text.as_bytes()[..offset];
        let line = before.iter().filter(|&&b| b == b'\n').count() as u32 + 1;
        let line_start = before.iter().rposition(|&b| b == b'\n').map_or(0, |i| i + 1);
        let col = String::from_utf8_lossy(&before[line_start..]).chars().count() as u32 + 1;
        SourceLoc { file, line, col }
    }
}

impl fmt::Display for SourceLoc {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}:{}:{}", self.file.display(), self.line, self.col)
    }
}

/// Everything that can go wrong in the library. Every variant names the thing at fault.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum Error {
    /// A mistake in scene input at a known place: `file:line:col: what was expected, what was found`.
    #[error("{loc}: {msg}")]
    Scene {
        /// Where the offending token, parameter or directive starts.
        loc: SourceLoc,
        /// What was expected and what was found.
        msg: String,
    },
    /// A file that could not be read, decoded or written (a mesh, an image, an output).
    #[error("{}: {msg}", path.display())]
    File {
        /// The file at fault.
        path: PathBuf,
        /// What went wrong with it.
        msg: String,
    },
    /// A bad command-line flag or option value, or an invalid combination of settings.
    #[error("{0}")]
    Usage(String),
}

/// The library's result type.
pub type Result<T, E = Error> = std::result::Result<T, E>;

impl Error {
    /// An error in scene input at `loc`.
    pub fn at(loc: &SourceLoc, msg: impl Into<String>) -> Self {
        Error::Scene { loc: loc.clone(), msg: msg.into() }
    }

    /// An error about a whole file.
    pub fn file(path: impl Into<PathBuf>, msg: impl Into<String>) -> Self {
        Error::File { path: path.into(), msg: msg.into() }
    }

    /// An error about a flag or setting.
    pub fn usage(msg: impl Into<String>) -> Self {
        Error::Usage(msg.into())
    }

    /// The scene location of the error, when it has one.
    pub fn loc(&self) -> Option<&SourceLoc> {
        match self {
            Error::Scene { loc, .. } => Some(loc),
            _ => None,
        }
    }

    /// The offending source line followed by a caret under the column, when the error has a location and
    /// the file can still be read. Long lines are cropped around the column.
    pub fn excerpt(&self) -> Option<String> {
        let loc = self.loc()?;
        let text = std::fs::read(&*loc.file).ok()?;
        let text = String::from_utf8_lossy(&text);
        let line = text.lines().nth(loc.line.checked_sub(1)? as usize)?;
        Some(caret_excerpt(line, loc.col as usize))
    }
}

/// Formats `line` with a caret under 1-based column `col`, cropped to about 100 characters around it.
fn caret_excerpt(line: &str, col: usize) -> String {
    const WIDTH: usize = 100;
    let chars: Vec<char> = line.chars().map(|c| if c == '\t' { ' ' } else { c }).collect();
    let col0 = col.saturating_sub(1).min(chars.len());
    let start = col0.saturating_sub(WIDTH / 2);
    let end = (start + WIDTH).min(chars.len());
    let shown: String = chars[start..end].iter().collect();
    let prefix = if start > 0 { "..." } else { "" };
    let suffix = if end < chars.len() { "..." } else { "" };
    let caret_at = prefix.len() + (col0 - start);
    format!("  {prefix}{shown}{suffix}\n  {}^", " ".repeat(caret_at))
}

/// How much a [`Warning`] matters to the image.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Severity {
    /// A routine fact about how the scene is rendered that leaves the image the user asked for as it is
    /// (a Sampler a cache-based integrator does not read, an `Integrator` line replaced on purpose by
    /// `--integrator`); printed as `note:`.
    Note,
    /// Something that changes the image against what the scene or the flags ask for (an unused parameter,
    /// a missing texture, an unsupported feature); printed as `warning:`.
    Warning,
}

/// A problem that does not stop the run (an unused parameter, a missing texture, an unsupported feature),
/// or a note about how the scene is rendered.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Warning {
    /// Where it comes from, when it comes from a scene file.
    pub loc: Option<SourceLoc>,
    /// What was found and what cachert does about it.
    pub msg: String,
    /// `note:` or `warning:`.
    pub severity: Severity,
}

impl Warning {
    /// Whether this is a note, not a warning.
    pub fn is_note(&self) -> bool {
        self.severity == Severity::Note
    }
}

impl fmt::Display for Warning {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let word = match self.severity {
            Severity::Note => "note",
            Severity::Warning => "warning",
        };
        match &self.loc {
            Some(loc) => write!(f, "{loc}: {word}: {}", self.msg),
            None => write!(f, "{word}: {}", self.msg),
        }
    }
}

/// An ordered collection of warnings and notes; an identical one is kept once. A collection made with
/// [`Warnings::printing`] also hands each new one to its sink the moment it is recorded, so a command line
/// shows them as they are found, before a long render rather than after it.
#[derive(Clone, Debug, Default)]
pub struct Warnings {
    list: Vec<Warning>,
    sink: Option<fn(&Warning)>,
}

impl Warnings {
    /// An empty collection that calls `sink` with each warning or note as it is first recorded.
    pub fn printing(sink: fn(&Warning)) -> Self {
        Warnings { list: Vec::new(), sink: Some(sink) }
    }

    /// Records a warning at `loc`.
    pub fn at(&mut self, loc: &SourceLoc, msg: impl Into<String>) {
        self.push(Warning { loc: Some(loc.clone()), msg: msg.into(), severity: Severity::Warning });
    }

    /// Records a warning without a location.
    pub fn general(&mut self, msg: impl Into<String>) {
        self.push(Warning { loc: None, msg: msg.into(), severity: Severity::Warning });
    }

    /// Records a note at `loc` (a routine fact that leaves the image as asked for).
    pub fn note_at(&mut self, loc: &SourceLoc, msg: impl Into<String>) {
        self.push(Warning { loc: Some(loc.clone()), msg: msg.into(), severity: Severity::Note });
    }

    /// Records a note without a location.
    pub fn note(&mut self, msg: impl Into<String>) {
        self.push(Warning { loc: None, msg: msg.into(), severity: Severity::Note });
    }

    /// Records `w` unless the same warning is already there.
    pub fn push(&mut self, w: Warning) {
        if !self.list.contains(&w) {
            if let Some(sink) = self.sink {
                sink(&w);
            }
            self.list.push(w);
        }
    }

    /// Appends all of `other`, in order.
    pub fn extend(&mut self, other: Warnings) {
        for w in other.list {
            self.push(w);
        }
    }

    /// The warnings and notes in the order they were recorded.
    pub fn iter(&self) -> impl Iterator<Item = &Warning> {
        self.list.iter()
    }

    /// How many distinct warnings and notes there are.
    pub fn len(&self) -> usize {
        self.list.len()
    }

    /// Whether there are none.
    pub fn is_empty(&self) -> bool {
        self.list.is_empty()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn offsets_become_lines_and_columns() {
        let text = "Shape \"sphere\"\n  Translate 1 2\n";
        let f: Arc<Path> = Arc::from(Path::new("a.pbrt"));
        let at = |o| SourceLoc::from_offset(f.clone(), text, o);
        assert_eq!((at(0).line, at(0).col), (1, 1));
        assert_eq!((at(6).line, at(6).col), (1, 7));
        assert_eq!((at(17).line, at(17).col), (2, 3));
        assert_eq!(at(17).to_string(), "a.pbrt:2:3");
    }

    #[test]
    fn caret_sits_under_the_column() {
        let e = caret_excerpt("Shape \"spher\"", 7);
        assert_eq!(e, "  Shape \"spher\"\n        ^");
        let long = "x".repeat(300);
        let e = caret_excerpt(&long, 200);
        let lines: Vec<&str> = e.lines().collect();
        assert!(lines[0].starts_with("  ...") && lines[0].ends_with("..."));
        assert_eq!(lines[1].find('^'), Some(2 + 3 + 50));
    }

    #[test]
    fn identical_warnings_are_kept_once() {
        let mut w = Warnings::default();
        w.general("a");
        w.general("a");
        w.general("b");
        assert_eq!(w.len(), 2);
    }

    #[test]
    fn notes_and_warnings_say_which_they_are() {
        let mut w = Warnings::default();
        w.note("a");
        w.general("a");
        let shown: Vec<String> = w.iter().map(|w| w.to_string()).collect();
        assert_eq!(shown, ["note: a", "warning: a"]);
    }

    #[test]
    fn a_printing_collection_hands_each_new_warning_over_once() {
        use std::sync::atomic::{AtomicUsize, Ordering};
        static SEEN: AtomicUsize = AtomicUsize::new(0);
        let mut w = Warnings::printing(|_| {
            SEEN.fetch_add(1, Ordering::Relaxed);
        });
        w.general("a");
        w.general("a");
        let mut later = Warnings::default();
        later.note("b");
        w.extend(later);
        assert_eq!(SEEN.load(Ordering::Relaxed), 2);
    }
}
