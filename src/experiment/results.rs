//! A sweep's `results.csv`, the one schema of every experiment (spec or flags): one row per run with its
//! settings, its errors against the reference (and the converged per-pixel image), its stage times and
//! counts. Written by `jobs::collect`; read back by [`read_csv`] so that the tables and charts of a
//! finished sweep can be rebuilt from it alone ([`rebuild`], `cachert experiment --replot DIR`), without
//! rendering.
//!
//! Depends on the records of `jobs`, the tables and the figures; it renders nothing.

use std::collections::BTreeMap;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::sync::Arc;

use super::jobs::{Record, TABLES};
use super::tables::Table;
use crate::error::{Error, Result, SourceLoc};
use crate::integrator::cache::stats::StageTimes;

/// The results file's name inside an experiment folder.
pub const CSV: &str = "results.csv";

/// The columns before the stage times.
const HEAD: [&str; 18] = [
    "id",
    "status",
    "error",
    "scene",
    "application",
    "placement",
    "method",
    "samples",
    "caches",
    "seed",
    "width",
    "height",
    "varied",
    "set",
    "rmse",
    "flip",
    "rmse_converged",
    "flip_converged",
];

/// The columns after the stage times.
const TAIL: [&str; 10] = [
    "stage1",
    "stage2",
    "cache_rays",
    "render_rays",
    "peak_memory_bytes",
    "record_bytes",
    "sigma_a_deg",
    "reference_s",
    "reference_mean",
    "estimate",
];

/// A CSV field: quoted when it holds a comma, a quote or a line break.
pub(super) fn field(s: &str) -> String {
    if s.contains([',', '"', '\n']) { format!("\"{}\"", s.replace('"', "\"\"")) } else { s.to_string() }
}

/// The stage names of the time columns (`NAME_s`): those of the `--stats` report, then any other a record
/// has, in name order.
fn steps(records: &[Record]) -> Vec<String> {
    let mut names: Vec<String> = serde_json::to_value(StageTimes::default())
        .ok()
        .and_then(|v| v.as_object().map(|o| o.keys().cloned().collect()))
        .unwrap_or_default();
    for r in records {
        for k in r.times.keys() {
            if !names.contains(k) {
                names.push(k.clone());
            }
        }
    }
    names.sort();
    names
}

/// Writes `records` to `path` in the one schema; numbers in full (shortest round-trip) precision, so the
/// tables rebuilt from the file are the tables of the sweep that wrote it.
pub fn write_csv(records: &[Record], path: &Path) -> Result<()> {
    let steps = steps(records);
    let mut csv = HEAD.join(",");
    for s in &steps {
        let _ = write!(csv, ",{s}_s");
    }
    let _ = writeln!(csv, ",{}", TAIL.join(","));
    let opt = |v: Option<f64>| v.map_or(String::new(), |x| format!("{x}"));
    for r in records {
        let [w, h] = r.resolution.map_or([String::new(), String::new()], |[w, h]| [w.to_string(), h.to_string()]);
        let _ = write!(
            csv,
            "{},{},{},{},{},{},{},{},{},{},{w},{h},{},{},{},{},{},{}",
            field(&r.id),
            r.status,
            field(&r.error),
            field(&r.scene),
            r.application,
            r.placement,
            field(&r.method),
            r.samples.map_or(String::new(), |n| n.to_string()),
            r.caches,
            r.seed,
            field(&r.varied),
            field(&r.set),
            r.rmse,
            r.flip,
            opt(r.rmse_converged),
            opt(r.flip_converged),
        );
        for s in &steps {
            let _ = write!(csv, ",{}", opt(r.times.get(s).copied()));
        }
        let _ = writeln!(
            csv,
            ",{},{},{},{},{},{},{},{},{},{}",
            r.caches_placed[0],
            r.caches_placed[1],
            r.rays[0],
            r.rays[1],
            r.peak_memory_bytes.map_or(String::new(), |b| b.to_string()),
            r.record_bytes,
            opt(r.sigma_a_deg),
            opt(Some(r.reference_s).filter(|s| s.is_finite())),
            opt(Some(r.reference_mean).filter(|s| s.is_finite())),
            opt(r.estimate)
        );
    }
    crate::image::write_bytes(path, csv.as_bytes())
}

/// The fields of one CSV line with the 1-based column where each starts (quoted fields unquoted); `None`
/// for an unterminated quote.
fn split(line: &str) -> Option<Vec<(usize, String)>> {
    let mut out = Vec::new();
    let (mut field, mut start, mut quoted, mut fresh) = (String::new(), 1, false, true);
    let mut chars = line.char_indices().peekable();
    while let Some((i, c)) = chars.next() {
        if quoted {
            if c != '"' {
                field.push(c);
            } else if chars.peek().is_some_and(|&(_, next)| next == '"') {
                chars.next();
                field.push('"');
            } else {
                quoted = false;
            }
        } else if c == '"' && fresh {
            (quoted, fresh) = (true, false);
        } else if c == ',' {
            out.push((start, std::mem::take(&mut field)));
            (start, fresh) = (i + 2, true);
        } else {
            field.push(c);
            fresh = false;
        }
    }
    if quoted {
        return None;
    }
    out.push((start, field));
    Some(out)
}

/// Reads the records of `path`, a `results.csv` of the one schema (columns found by their names; the
/// optional ones may be missing, as in files written before they existed). Errors name the line and column.
pub fn read_csv(path: &Path) -> Result<Vec<Record>> {
    let text = std::fs::read_to_string(path).map_err(|e| Error::file(path, format!("cannot read: {e}")))?;
    parse_csv(path, &text)
}

/// Parses the text of a `results.csv` (`path` for messages).
pub fn parse_csv(path: &Path, text: &str) -> Result<Vec<Record>> {
    let file: Arc<Path> = Arc::from(path);
    let at =
        |line: usize, col: usize, msg: String| Error::at(&SourceLoc::new(file.clone(), line as u32, col as u32), msg);
    let mut lines = text.lines().enumerate();
    let Some((_, header)) = lines.next() else {
        return Err(at(1, 1, "expected the header line of an experiment's results.csv, found an empty file".into()));
    };
    let names: Vec<String> = split(header).unwrap_or_default().into_iter().map(|(_, n)| n).collect();
    let col = |name: &str| names.iter().position(|n| n == name);
    for want in ["id", "status", "scene", "application", "placement", "method", "caches", "seed", "rmse", "flip"] {
        if col(want).is_none() {
            return Err(at(
                1,
                1,
                format!("expected a column \"{want}\" in the header (the schema `cachert experiment` writes)"),
            ));
        }
    }
    let mut records = Vec::new();
    for (i, line) in lines {
        if line.trim().is_empty() {
            continue;
        }
        let n = i + 1;
        let fields = split(line).ok_or_else(|| at(n, 1, "a quoted field is not closed".into()))?;
        if fields.len() != names.len() {
            return Err(at(n, 1, format!("expected {} fields as in the header, found {}", names.len(), fields.len())));
        }
        records.push(CsvLine { names: &names, fields, line: n, at: &at }.record()?);
    }
    Ok(records)
}

/// One data line of a results.csv, read by column name (a column the file lacks reads as empty).
struct CsvLine<'a> {
    /// The header's column names.
    names: &'a [String],
    /// The line's fields with the column (1-based) each starts at.
    fields: Vec<(usize, String)>,
    /// The line's number (1-based).
    line: usize,
    /// Makes an error at a line and column of the file.
    at: &'a dyn Fn(usize, usize, String) -> Error,
}

impl CsvLine<'_> {
    fn get(&self, name: &str) -> Option<(usize, &str)> {
        let k = self.names.iter().position(|n| n == name)?;
        Some((self.fields[k].0, self.fields[k].1.as_str()))
    }

    fn text(&self, name: &str) -> String {
        self.get(name).map_or(String::new(), |(_, v)| v.to_string())
    }

    /// A number; `None` for an empty field or a missing column (a run that measured nothing).
    fn number(&self, name: &str) -> Result<Option<f64>> {
        self.parsed(name, "a number")
    }

    /// A whole number; `None` as for [`CsvLine::number`].
    fn count(&self, name: &str) -> Result<Option<u64>> {
        self.parsed(name, "a whole number")
    }

    /// The field parsed as `T` (`what` names it in the error); `None` as for [`CsvLine::number`].
    fn parsed<T: std::str::FromStr>(&self, name: &str, what: &str) -> Result<Option<T>> {
        match self.get(name) {
            None | Some((_, "")) => Ok(None),
            Some((c, v)) => v
                .parse::<T>()
                .map(Some)
                .map_err(|_| (self.at)(self.line, c, format!("expected {name} ({what}), found \"{v}\""))),
        }
    }

    /// The line as a [`Record`] (NaN errors and times for what it left empty).
    fn record(&self) -> Result<Record> {
        let mut times = BTreeMap::new();
        for name in self.names.iter().filter_map(|h| h.strip_suffix("_s")).filter(|h| *h != "reference") {
            if let Some(v) = self.number(&format!("{name}_s"))? {
                times.insert(name.to_string(), v);
            }
        }
        let resolution = match (self.count("width")?, self.count("height")?) {
            (Some(w), Some(h)) => Some([w as u32, h as u32]),
            _ => None,
        };
        Ok(Record {
            id: self.text("id"),
            status: self.text("status"),
            error: self.text("error"),
            scene: self.text("scene"),
            application: self.text("application"),
            placement: self.text("placement"),
            method: self.text("method"),
            samples: self.count("samples")?.map(|s| s.min(u32::MAX as u64) as u32),
            caches: self.count("caches")?.unwrap_or(0) as usize,
            seed: self.count("seed")?.unwrap_or(0),
            resolution,
            varied: self.text("varied"),
            set: self.text("set"),
            rmse: self.number("rmse")?.unwrap_or(f64::NAN),
            flip: self.number("flip")?.unwrap_or(f64::NAN),
            rmse_converged: self.number("rmse_converged")?,
            flip_converged: self.number("flip_converged")?,
            times,
            caches_placed: [self.count("stage1")?.unwrap_or(0), self.count("stage2")?.unwrap_or(0)],
            rays: [self.count("cache_rays")?.unwrap_or(0), self.count("render_rays")?.unwrap_or(0)],
            peak_memory_bytes: self.count("peak_memory_bytes")?,
            record_bytes: self.count("record_bytes")?.unwrap_or(0),
            sigma_a_deg: self.number("sigma_a_deg")?,
            reference_s: self.number("reference_s")?.unwrap_or(f64::NAN),
            reference_mean: self.number("reference_mean")?.unwrap_or(f64::NAN),
            estimate: self.number("estimate")?,
        })
    }
}

/// The line at the top of a generated `tables.md`: what wrote it and the command that writes it again.
pub fn generated_note(dir_hint: &str) -> String {
    format!(
        "_Generated from `{CSV}` by `cachert experiment --replot {dir_hint}` (or by the sweep that wrote it); \
         do not edit: run the command again._\n\n"
    )
}

/// Writes `tables` as Markdown to `path`, under the generated-file note; a table that would be all "—"
/// ([`Table::has_data`]) is left out.
pub fn write_tables(tables: &[Table], path: &Path) -> Result<()> {
    let dir = path.parent().map_or(".".to_string(), |d| d.display().to_string());
    let mut markdown = generated_note(if dir.is_empty() { "." } else { &dir });
    markdown.extend(tables.iter().filter(|t| t.has_data()).map(|t| t.markdown()));
    crate::image::write_bytes(path, markdown.as_bytes())
}

/// Rebuilds `dir`'s `tables.md` and charts from `dir/results.csv` alone (no rendering; the report, which
/// needs the run images, is not rewritten); returns the files written.
pub fn rebuild(dir: &Path, log: &mut dyn FnMut(&str)) -> Result<Vec<PathBuf>> {
    let path = dir.join(CSV);
    let records = read_csv(&path)?;
    if records.is_empty() {
        return Err(Error::file(&path, "no runs to draw (only a header)"));
    }
    let tables = super::tables::all(&records);
    let md = dir.join(TABLES);
    write_tables(&tables, &md)?;
    let mut written = vec![md];
    written.extend(super::figures::write(&records, dir, log)?.into_iter().map(|f| f.svg));
    Ok(written)
}

/// Writes `dir/equal-time-vs-<name of baselines>.md`: the equal-time tables of `dir/results.csv` with the
/// per-pixel runs taken from `baselines/results.csv` instead (`cachert experiment --replot DIR --baselines
/// DIR2`); returns the file written.
pub fn rebuild_against(dir: &Path, baselines: &Path) -> Result<PathBuf> {
    let records = read_csv(&dir.join(CSV))?;
    let others = read_csv(&baselines.join(CSV))?;
    let name = baselines.file_name().map_or("baselines".to_string(), |n| n.to_string_lossy().into_owned());
    let tables = super::ratios::equal_time_against(&records, &others, &format!("`{}`", baselines.display()));
    if tables.is_empty() {
        return Err(Error::file(baselines.join(CSV), "no per-pixel runs for the scenes of the sweep"));
    }
    let path = dir.join(format!("equal-time-vs-{name}.md"));
    let mut markdown = format!(
        "_Generated from `{CSV}` and `{}/{CSV}` by `cachert experiment --replot {} --baselines {}`; do not edit: \
         run the command again._\n\n",
        baselines.display(),
        dir.display(),
        baselines.display()
    );
    markdown.extend(tables.iter().map(|t| t.markdown()));
    crate::image::write_bytes(&path, markdown.as_bytes())?;
    Ok(path)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fields_split_with_quotes_and_their_columns() {
        let f = split("a,\"b,c\",,\"say \"\"x\"\"\",").unwrap();
        let v: Vec<(usize, &str)> = f.iter().map(|(c, s)| (*c, s.as_str())).collect();
        assert_eq!(v, [(1, "a"), (3, "b,c"), (9, ""), (10, "say \"x\""), (22, "")]);
        assert_eq!(split("x").unwrap(), [(1, "x".to_string())]);
        assert!(split("\"open").is_none());
        assert_eq!(field("a,b"), "\"a,b\"");
        assert_eq!(field("say \"x\""), "\"say \"\"x\"\"\"");
    }

    #[test]
    fn bad_files_name_the_line_and_column() {
        let p = Path::new("r.csv");
        let err = |text: &str| parse_csv(p, text).unwrap_err().to_string();
        assert!(err("").contains("r.csv:1:1: expected the header line"), "{}", err(""));
        let head = "id,status,scene,application,placement,method,caches,seed,rmse,flip,total_s\n";
        assert!(err("id,status\n").contains("r.csv:1:1: expected a column \"scene\""), "{}", err("id,status\n"));
        let bad = format!("{head}a,ok,s,someapp,im,im,10,0,0.1,zero,2\n");
        assert!(err(&bad).contains("r.csv:2:31: expected flip (a number), found \"zero\""), "{}", err(&bad));
        let short = format!("{head}a,ok\n");
        assert!(err(&short).contains("r.csv:2:1: expected 11 fields"), "{}", err(&short));
        let good = parse_csv(p, &format!("{head}a,ok,s,someapp,im,im,10,1,0.1,0.2,2.5\n")).unwrap();
        assert_eq!((good[0].caches, good[0].seed, good[0].times["total"]), (10, 1, 2.5));
    }
}
