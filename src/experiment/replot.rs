//! STAGE: experiments, after a sweep — redraws the error-against-time charts of a flag-form sweep
//! (`cachert experiment --scene …`) from the `results.csv` it wrote, so that a change to the charts reaches
//! results already measured without rendering them again.
//!
//! Depends on the columns `write_results` (in `super`) writes and on the chart writer; it renders nothing and
//! must not depend on any application or placement.

use std::path::{Path, PathBuf};
use std::sync::Arc;

use super::Row;
use super::chart;
use crate::error::{Error, Result, SourceLoc};
use crate::integrator::cache::stats::{CacheStats, StageTimes};

/// The columns a chart needs, by their names in the header of `results.csv`.
const NEEDED: [&str; 7] = ["scene", "placement", "caches", "seed", "rmse", "flip", "total_s"];

/// Reads the rows of `text` (the contents of `path`, a sweep's `results.csv`) that the charts draw.
pub fn read_rows(path: &Path, text: &str) -> Result<Vec<Row>> {
    let file: Arc<Path> = Arc::from(path);
    let at =
        |line: usize, col: usize, msg: String| Error::at(&SourceLoc::new(file.clone(), line as u32, col as u32), msg);
    let mut lines = text.lines().enumerate();
    let Some((_, header)) = lines.next() else {
        return Err(at(1, 1, "expected the header line of an experiment's results.csv, found an empty file".into()));
    };
    let names: Vec<&str> = header.split(',').collect();
    let mut index = [0usize; NEEDED.len()];
    for (slot, want) in index.iter_mut().zip(NEEDED) {
        *slot = names.iter().position(|n| *n == want).ok_or_else(|| {
            at(1, 1, format!("expected a column \"{want}\" in the header (written by `cachert experiment`)"))
        })?;
    }
    let mut rows = Vec::new();
    for (i, line) in lines {
        if line.trim().is_empty() {
            continue;
        }
        let fields: Vec<&str> = line.split(',').collect();
        if fields.len() != names.len() {
            return Err(at(
                i + 1,
                1,
                format!("expected {} fields as in the header, found {}", names.len(), fields.len()),
            ));
        }
        // The column of field k (1-based), for messages.
        let col = |k: usize| fields[..k].iter().map(|f| f.len() + 1).sum::<usize>() + 1;
        let [scene, placement, caches, seed, rmse, flip, total] = index;
        let number =
            |k: usize, what: &str| -> Result<f64> {
                fields[k].parse::<f64>().ok().filter(|v| v.is_finite()).ok_or_else(|| {
                    at(i + 1, col(k), format!("expected {what} (a finite number), found \"{}\"", fields[k]))
                })
            };
        let count = |k: usize, what: &str| -> Result<u64> {
            fields[k]
                .parse::<u64>()
                .map_err(|_| at(i + 1, col(k), format!("expected {what} (a whole number), found \"{}\"", fields[k])))
        };
        let total_s = number(total, "the total seconds")?;
        rows.push(Row {
            scene: fields[scene].to_string(),
            placement: fields[placement].to_string(),
            caches: usize::try_from(count(caches, "the cache budget")?).unwrap_or(usize::MAX),
            seed: count(seed, "the seed")?,
            rmse: number(rmse, "the RMSE")?,
            flip: number(flip, "the HDR-FLIP")?,
            converged: None,
            stats: CacheStats { times: StageTimes { total: total_s, ..Default::default() }, ..Default::default() },
        });
    }
    Ok(rows)
}

/// Redraws `dir`'s charts (`SCENE-error-vs-time.svg` and `.png` per scene, as the sweep draws them) from
/// `dir/results.csv`; returns the SVGs written. Without a font for their text it writes none and says why.
pub fn replot(dir: &Path) -> Result<Vec<PathBuf>> {
    let path = dir.join("results.csv");
    let text = std::fs::read_to_string(&path).map_err(|e| Error::file(&path, format!("cannot read: {e}")))?;
    let rows = read_rows(&path, &text)?;
    if rows.is_empty() {
        return Err(Error::file(&path, "no runs to draw (only a header)"));
    }
    chart::font()?;
    super::write_charts(&rows, dir)
}

#[cfg(test)]
mod tests {
    use super::*;

    const CSV: &str = "scene,placement,caches,seed,rmse,flip,rmse_converged,flip_converged,total_s,render_s,stage1,stage2\n\
                       box,none,0,0,0.000000,0.000000,,,90.5,0.1,0,0\n\
                       box,vgc,100,1,0.012500,0.250000,,,2.5000,0.1,85,15\n\
                       box,power:16,0,0,0.050000,0.400000,,,1.2500,1.2,0,0\n";

    #[test]
    fn rows_are_read_back_by_their_column_names() {
        let rows = read_rows(Path::new("results.csv"), CSV).unwrap();
        assert_eq!(rows.len(), 3);
        let r = &rows[1];
        assert_eq!((r.scene.as_str(), r.placement.as_str(), r.caches, r.seed), ("box", "vgc", 100, 1));
        assert_eq!((r.rmse, r.flip, r.stats.times.total), (0.0125, 0.25, 2.5));
        assert_eq!(rows[2].placement, "power:16");
    }

    #[test]
    fn bad_files_name_the_line_and_column() {
        let p = Path::new("r.csv");
        let err = |text: &str| read_rows(p, text).unwrap_err().to_string();
        assert!(err("").contains("r.csv:1:1: expected the header line"), "{}", err(""));
        let no_total = "scene,placement,caches,seed,rmse,flip\nbox,vgc,1,0,0.1,0.2\n";
        assert!(err(no_total).contains("r.csv:1:1: expected a column \"total_s\""), "{}", err(no_total));
        let bad_rmse = CSV.replace("0.012500", "oops");
        assert!(
            err(&bad_rmse).contains("r.csv:3:15: expected the RMSE (a finite number), found \"oops\""),
            "{}",
            err(&bad_rmse)
        );
        let short = format!("{CSV}box,vgc,100\n");
        assert!(err(&short).contains("r.csv:5:1: expected 12 fields as in the header, found 3"), "{}", err(&short));
        let nan = CSV.replace("2.5000", "NaN");
        assert!(err(&nan).contains("r.csv:3:"), "{}", err(&nan));
        let negative = CSV.replace("box,vgc,100,1", "box,vgc,-5,1");
        assert!(err(&negative).contains("r.csv:3:9: expected the cache budget"), "{}", err(&negative));
    }
}
