//! The table that judges a placement beyond the paper's five (`refine`, issue 43) the way its issue asks:
//! per scene, application and budget, its mean RMSE against the best of IM, SD, SD+AS, VGC and VGC+DGS in
//! that cell and its mean HDR-FLIP against IM's, each marked when the difference is beyond two standard
//! errors; then the means over the cells (RMSE as a ratio to VGC+DGS's, HDR-FLIP to IM's) and the count of
//! cells it loses.
//!
//! Depends only on the records of `jobs`, [`super::summary`] and [`super::tables::Table`]; it reads no file.

use super::jobs::Record;
use super::summary::{self, Summary, errors, is_cache_run, ok, pairs};
use super::tables::Table;

/// The paper's five placements, against whose best a newcomer is judged.
pub const PAPER: [&str; 5] = ["im", "sd", "sd+as", "vgc", "vgc+dgs"];

/// `a / b` with three decimals, marked `+` (a clearly below b) or `-` (clearly above).
fn marked(a: &Summary, b: &Summary) -> String {
    let mark = if a.clearly_below(b) {
        "+"
    } else if b.clearly_below(a) {
        "-"
    } else {
        ""
    };
    format!("{:.3}{mark}", a.mean / b.mean)
}

/// One cell in which a newcomer and all five ran: its scores against the best of the five, VGC+DGS and IM.
#[derive(Clone, Debug, PartialEq)]
pub struct Cell {
    /// The scene.
    pub scene: String,
    /// The application.
    pub application: String,
    /// The budget.
    pub caches: usize,
    /// The one of the five with the lowest mean RMSE, and that mean.
    pub best: (String, f64),
    /// The newcomer's mean RMSE over the best's, marked as [`marked`] does.
    pub vs_best: String,
    /// The newcomer's mean RMSE over VGC+DGS's, marked.
    pub vs_dgs: String,
    /// The newcomer's mean HDR-FLIP over IM's, marked.
    pub flip_vs_im: String,
    /// The unmarked ratio to VGC+DGS's mean RMSE.
    pub rmse_ratio: f64,
    /// The unmarked ratio to IM's mean HDR-FLIP.
    pub flip_ratio: f64,
    /// Clearly worse than the best of the five in RMSE.
    pub loses_rmse: bool,
    /// Clearly better than the best of the five in RMSE.
    pub wins_rmse: bool,
    /// Clearly above IM in HDR-FLIP.
    pub loses_flip: bool,
}

impl Cell {
    /// The cell's row in a newcomer's table ([`header`]'s columns).
    pub fn row(&self) -> Vec<String> {
        vec![
            format!("{} {}", self.scene, self.application),
            self.caches.to_string(),
            format!("{} {:.5}", self.best.0, self.best.1),
            self.vs_best.clone(),
            self.vs_dgs.clone(),
            self.flip_vs_im.clone(),
        ]
    }
}

/// The plain cache methods that are not one of [`PAPER`], sorted.
pub fn newcomers(records: &[Record]) -> Vec<String> {
    let mut out: Vec<String> = Vec::new();
    for r in ok(records).filter(|r| is_cache_run(r) && r.varied.is_empty()) {
        if !PAPER.contains(&r.placement.as_str()) && !out.contains(&r.placement) {
            out.push(r.placement.clone());
        }
    }
    out.sort();
    out
}

/// Every cell (scene, application, budget) where `m` and all five ran, in scene, application and budget order.
pub fn cells(records: &[Record], m: &str) -> Vec<Cell> {
    let mut out = Vec::new();
    for (scene, app) in pairs(records) {
        for caches in summary::budgets(records, &scene, &app) {
            let at = summary::methods_at(records, &scene, &app, caches);
            let paper: Option<Vec<(&str, (Summary, Summary))>> =
                PAPER.iter().map(|p| at.get(*p).and_then(|rs| errors(rs)).map(|e| (*p, e))).collect();
            let (Some(paper), Some((r, f))) = (paper, at.get(m).and_then(|rs| errors(rs))) else { continue };
            let Some((best, (br, _))) = paper.iter().min_by(|a, b| a.1.0.mean.total_cmp(&b.1.0.mean)) else {
                continue;
            };
            let (_, (_, im_f)) = paper[0];
            let (_, (dgs_r, _)) = paper[4];
            out.push(Cell {
                scene: scene.clone(),
                application: app.clone(),
                caches,
                best: (best.to_string(), br.mean),
                vs_best: marked(&r, br),
                vs_dgs: marked(&r, &dgs_r),
                flip_vs_im: marked(&f, &im_f),
                rmse_ratio: r.mean / dgs_r.mean,
                flip_ratio: f.mean / im_f.mean,
                loses_rmse: br.clearly_below(&r),
                wins_rmse: r.clearly_below(br),
                loses_flip: im_f.clearly_below(&f),
            });
        }
    }
    out
}

/// The last row of a newcomer's table: how many cells it loses and wins in RMSE, the mean of its ratios to
/// VGC+DGS's RMSE and to IM's HDR-FLIP, and the cells it loses there.
pub fn mean_row(label: String, cells: &[Cell]) -> Vec<String> {
    let n = cells.len().max(1) as f64;
    let count = |f: fn(&Cell) -> bool| cells.iter().filter(|c| f(c)).count();
    vec![
        label,
        String::new(),
        String::new(),
        format!("loses {}, wins {}", count(|c| c.loses_rmse), count(|c| c.wins_rmse)),
        format!("{:.3}", cells.iter().map(|c| c.rmse_ratio).sum::<f64>() / n),
        format!("{:.3} (loses {})", cells.iter().map(|c| c.flip_ratio).sum::<f64>() / n, count(|c| c.loses_flip)),
    ]
}

/// The columns of a newcomer's table.
pub fn header(m: &str) -> Vec<String> {
    vec![
        "scene, application".into(),
        "caches".into(),
        "best of the five (RMSE)".into(),
        format!("{m} / best"),
        format!("{m} / vgc+dgs"),
        format!("{m} FLIP / IM"),
    ]
}

/// One table per plain cache method that is not one of [`PAPER`], over every cell where it and all five ran.
pub fn against_the_paper(records: &[Record]) -> Vec<Table> {
    let mut out = Vec::new();
    for m in newcomers(records) {
        let cells = cells(records, &m);
        if cells.is_empty() {
            continue;
        }
        let mut rows: Vec<Vec<String>> = cells.iter().map(Cell::row).collect();
        rows.push(mean_row(format!("mean over {} cells", cells.len()), &cells));
        out.push(Table {
            title: format!("{m} against the paper's best"),
            note: format!(
                "Per cell, the lowest mean RMSE of IM, SD, SD+AS, VGC and VGC+DGS, and {m}'s mean RMSE as a ratio to \
                 it and to VGC+DGS's, and its mean HDR-FLIP as a ratio to IM's; `-`: {m} clearly higher, `+`: \
                 clearly lower (the difference of the means exceeds two standard errors of the difference). The \
                 last row: cells {m} loses and wins in RMSE against the best, the mean of the ratios to VGC+DGS's \
                 RMSE, and of the ratios to IM's HDR-FLIP (with the cells it loses there)."
            ),
            header: header(&m),
            rows,
        });
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn rec(placement: &str, seed: u64, rmse: f64, flip: f64) -> Record {
        Record {
            scene: "s".into(),
            application: "app".into(),
            placement: placement.into(),
            method: placement.into(),
            caches: 100,
            seed,
            rmse,
            flip,
            status: "ok".into(),
            ..Default::default()
        }
    }

    #[test]
    fn a_newcomer_is_judged_against_the_best_of_the_five() {
        let mut rs = Vec::new();
        for s in 0..4 {
            let j = s as f64 * 1e-4;
            for (p, r, f) in
                [("im", 1.0, 1.0), ("sd", 0.9, 1.1), ("sd+as", 0.95, 1.0), ("vgc", 1.1, 1.2), ("vgc+dgs", 0.92, 1.05)]
            {
                rs.push(rec(p, s, r + j, f + j));
            }
            rs.push(rec("refine", s, 0.99 + j, 0.9 + j));
        }
        let t = against_the_paper(&rs);
        assert_eq!(t.len(), 1);
        let row = &t[0].rows[0];
        assert_eq!(row[2], "sd 0.90015");
        assert_eq!(row[3], "1.100-");
        assert_eq!(row[5], "0.900+");
        assert_eq!(t[0].rows[1][3], "loses 1, wins 0");
    }
}
