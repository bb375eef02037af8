//! `cachert experiment --pool`: a newcomer placement judged against the paper's five over the cells of several
//! finished sweeps at once. The stability map at each size and the 640×360 specs are separate sweeps, and a
//! claim such as issue 43's "mean RMSE over the cells" is over all of them; this module renders nothing and
//! reads only each sweep's `results.csv`.
//!
//! A cell is (resolution, scene, application, budget). A cell measured by a later sweep replaces the same cell
//! of an earlier one, so a sweep made again after a change of estimator (importance caching's learnt shares)
//! can stand in for part of an older one.
//!
//! Depends on [`super::beyond`] for the judgement, [`super::results`] to read a sweep, [`super::tables`]
//! for the output; nothing here depends on an application or a placement.

use std::collections::BTreeMap;
use std::path::PathBuf;

use super::beyond::{self, Cell};
use super::jobs::Record;
use super::summary::{is_cache_run, ok};
use super::tables::Table;
use crate::error::Result;

/// The key of a cell.
type Key = (Option<[u32; 2]>, String, String, usize);

/// Each pooled cell's sweep (its folder's name), by renamed scene, application and budget.
pub type Sources = BTreeMap<(String, String, usize), String>;

/// The sweeps' plain cache runs as one list, each record's scene named with its resolution ("sibenik
/// 160x90") so that cells of different sizes stay apart, and with every cell taken from the last sweep that
/// measured it; beside it, each cell's sweep (its folder's name), by the renamed scene, application and budget.
pub fn pool(sweeps: &[(String, Vec<Record>)]) -> (Vec<Record>, Sources) {
    let mut cells: BTreeMap<Key, (&str, Vec<&Record>)> = BTreeMap::new();
    for (name, records) in sweeps {
        let mut here: BTreeMap<Key, Vec<&Record>> = BTreeMap::new();
        for r in ok(records).filter(|r| is_cache_run(r) && r.varied.is_empty()) {
            here.entry((r.resolution, r.scene.clone(), r.application.clone(), r.caches)).or_default().push(r);
        }
        for (k, rs) in here {
            cells.insert(k, (name.as_str(), rs));
        }
    }
    let mut out = Vec::new();
    let mut from = Sources::new();
    for ((res, scene, app, caches), (name, rs)) in cells {
        let size = res.map_or("?".to_string(), |[w, h]| format!("{w}x{h}"));
        let scene = format!("{scene} {size}");
        from.insert((scene.clone(), app.clone(), caches), name.to_string());
        out.extend(rs.into_iter().map(|r| Record { scene: scene.clone(), ..r.clone() }));
    }
    (out, from)
}

/// Reads each folder's `results.csv` (named by the folder's last component).
pub fn read(dirs: &[PathBuf]) -> Result<Vec<(String, Vec<Record>)>> {
    dirs.iter()
        .map(|d| {
            let name = d.file_name().map_or_else(|| d.display().to_string(), |n| n.to_string_lossy().into_owned());
            Ok((name, super::results::read_csv(&d.join(super::results::CSV))?))
        })
        .collect()
}

/// The size of a renamed scene ("sibenik 160x90" → "160x90").
fn size_of(scene: &str) -> &str {
    scene.rsplit_once(' ').map_or("?", |(_, s)| s)
}

/// Per newcomer: its cells with the sweep each came from, and its means by size and application and over
/// every cell.
pub fn tables(sweeps: &[(String, Vec<Record>)]) -> Vec<Table> {
    let (records, from) = pool(sweeps);
    let mut out = Vec::new();
    for m in beyond::newcomers(&records) {
        let cells = beyond::cells(&records, &m);
        if cells.is_empty() {
            continue;
        }
        let mut header = beyond::header(&m);
        header.insert(0, "sweep".into());
        let rows = cells
            .iter()
            .map(|c| {
                let sweep = from.get(&(c.scene.clone(), c.application.clone(), c.caches)).cloned().unwrap_or_default();
                let mut row = c.row();
                row.insert(0, sweep);
                row
            })
            .collect();
        out.push(Table {
            title: format!("{m} against the paper's best, cell by cell"),
            note: format!(
                "Every cell of the pooled sweeps where {m} and all five ran (a cell measured again by a later sweep \
                 is taken from it), with the sweep it comes from; columns as in each sweep's own table: the lowest \
                 mean RMSE of the five, {m}'s mean RMSE over it and over VGC+DGS's, its mean HDR-FLIP over IM's; \
                 `-`/`+`: clearly higher/lower (two standard errors of the difference)."
            ),
            header,
            rows,
        });
        let mut groups: BTreeMap<(String, String), Vec<Cell>> = BTreeMap::new();
        for c in &cells {
            groups.entry((size_of(&c.scene).to_string(), c.application.clone())).or_default().push(c.clone());
        }
        let mut sizes: BTreeMap<String, Vec<Cell>> = BTreeMap::new();
        for c in &cells {
            sizes.entry(size_of(&c.scene).to_string()).or_default().push(c.clone());
        }
        let mut rows: Vec<Vec<String>> = Vec::new();
        for ((size, app), cs) in &groups {
            rows.push(beyond::mean_row(format!("{size} {app}: {} cells", cs.len()), cs));
        }
        for (size, cs) in &sizes {
            rows.push(beyond::mean_row(format!("{size}, every application: {} cells", cs.len()), cs));
        }
        rows.push(beyond::mean_row(format!("**every cell: {}**", cells.len()), &cells));
        for r in &mut rows {
            r.drain(1..3);
        }
        out.push(Table {
            title: format!("{m} against the paper's best, means"),
            note: format!(
                "The cells above by size and application, by size, and all together: the cells {m} loses and wins \
                 in RMSE against the best of the five, the mean of its ratios to VGC+DGS's mean RMSE, and the mean \
                 of its ratios to IM's mean HDR-FLIP (with the cells where it is clearly above IM)."
            ),
            header: vec![
                "cells".into(),
                "RMSE against the best".into(),
                format!("{m} / vgc+dgs (mean)"),
                format!("{m} FLIP / IM (mean)"),
            ],
            rows,
        });
    }
    out
}

/// `cachert experiment --pool DIR --pool DIR …`: the tables as Markdown, under a line naming the command.
pub fn markdown(dirs: &[PathBuf]) -> Result<String> {
    let sweeps = read(dirs)?;
    let args: Vec<String> = dirs.iter().map(|d| format!("--pool {}", d.display())).collect();
    let mut md = format!(
        "_Generated from the sweeps' `results.csv` by `cachert experiment {}`; do not edit: run the command \
         again._\n\n",
        args.join(" ")
    );
    let tables = tables(&sweeps);
    if tables.is_empty() {
        return Err(crate::error::Error::usage(
            "experiment --pool: no cell where a placement beyond the paper's five and all five ran".to_string(),
        ));
    }
    md.extend(tables.iter().map(|t| t.markdown()));
    Ok(md)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn rec(res: [u32; 2], app: &str, placement: &str, seed: u64, rmse: f64) -> Record {
        Record {
            scene: "s".into(),
            application: app.into(),
            placement: placement.into(),
            method: placement.into(),
            caches: 100,
            seed,
            rmse,
            flip: rmse,
            resolution: Some(res),
            status: "ok".into(),
            ..Default::default()
        }
    }

    fn sweep(res: [u32; 2], app: &str, refine: f64) -> Vec<Record> {
        let mut rs = Vec::new();
        for s in 0..4 {
            let j = s as f64 * 1e-4;
            for (p, r) in [("im", 1.0), ("sd", 1.0), ("sd+as", 1.0), ("vgc", 1.0), ("vgc+dgs", 1.0)] {
                rs.push(rec(res, app, p, s, r + j));
            }
            rs.push(rec(res, app, "refine", s, refine + j));
        }
        rs
    }

    #[test]
    fn cells_of_different_sizes_stay_apart_and_a_later_sweep_replaces_a_cell() {
        let sweeps = vec![
            ("a".to_string(), [sweep([160, 90], "ao", 0.8), sweep([160, 90], "ic", 1.0)].concat()),
            ("b".to_string(), sweep([320, 180], "ao", 0.7)),
            ("c".to_string(), sweep([160, 90], "ic", 0.9)),
        ];
        let t = tables(&sweeps);
        assert_eq!(t.len(), 2);
        let cells = &t[0].rows;
        assert_eq!(cells.len(), 3);
        let ic = cells.iter().find(|r| r[1] == "s 160x90 ic").unwrap();
        assert_eq!(ic[0], "c");
        assert_eq!(ic[5], "0.900+");
        let every = t[1].rows.last().unwrap();
        assert_eq!(every[0], "**every cell: 3**");
        assert_eq!(every[1], "loses 0, wins 3");
        assert_eq!(every[2], format!("{:.3}", (0.8 + 0.7 + 0.9) / 3.0));
        assert!(t[1].rows.iter().any(|r| r[0] == "160x90, every application: 2 cells" && r[2] == "0.850"));
    }
}
