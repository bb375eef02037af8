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

/// One table per plain cache method that is not one of [`PAPER`], over every cell where it and all five ran.
pub fn against_the_paper(records: &[Record]) -> Vec<Table> {
    let mut newcomers: Vec<String> = Vec::new();
    for r in ok(records).filter(|r| is_cache_run(r) && r.varied.is_empty()) {
        if !PAPER.contains(&r.placement.as_str()) && !newcomers.contains(&r.placement) {
            newcomers.push(r.placement.clone());
        }
    }
    newcomers.sort();
    let mut out = Vec::new();
    for m in newcomers {
        let (mut rows, mut rmse_vs_dgs, mut flip_vs_im) = (Vec::new(), Vec::new(), Vec::new());
        let (mut cells, mut lose_rmse, mut lose_flip, mut win_rmse) = (0, 0, 0, 0);
        for (scene, app) in pairs(records) {
            for caches in summary::budgets(records, &scene, &app) {
                let at = summary::methods_at(records, &scene, &app, caches);
                let paper: Option<Vec<(&str, (Summary, Summary))>> =
                    PAPER.iter().map(|p| at.get(*p).and_then(|rs| errors(rs)).map(|e| (*p, e))).collect();
                let (Some(paper), Some((r, f))) = (paper, at.get(&m).and_then(|rs| errors(rs))) else { continue };
                let Some((best, (br, _))) = paper.iter().min_by(|a, b| a.1.0.mean.total_cmp(&b.1.0.mean)) else {
                    continue;
                };
                let (_, (_, im_f)) = paper[0];
                let (_, (dgs_r, _)) = paper[4];
                cells += 1;
                lose_rmse += usize::from(br.clearly_below(&r));
                win_rmse += usize::from(r.clearly_below(br));
                lose_flip += usize::from(im_f.clearly_below(&f));
                rmse_vs_dgs.push(r.mean / dgs_r.mean);
                flip_vs_im.push(f.mean / im_f.mean);
                rows.push(vec![
                    format!("{scene} {app}"),
                    caches.to_string(),
                    format!("{best} {:.5}", br.mean),
                    marked(&r, br),
                    marked(&r, &dgs_r),
                    marked(&f, &im_f),
                ]);
            }
        }
        if rows.is_empty() {
            continue;
        }
        let mean = |v: &[f64]| v.iter().sum::<f64>() / v.len() as f64;
        rows.push(vec![
            format!("mean over {cells} cells"),
            String::new(),
            String::new(),
            format!("loses {lose_rmse}, wins {win_rmse}"),
            format!("{:.3}", mean(&rmse_vs_dgs)),
            format!("{:.3} (loses {lose_flip})", mean(&flip_vs_im)),
        ]);
        out.push(Table {
            title: format!("{m} against the paper's best"),
            note: format!(
                "Per cell, the lowest mean RMSE of IM, SD, SD+AS, VGC and VGC+DGS, and {m}'s mean RMSE as a ratio to \
                 it and to VGC+DGS's, and its mean HDR-FLIP as a ratio to IM's; `-`: {m} clearly higher, `+`: \
                 clearly lower (the difference of the means exceeds two standard errors of the difference). The \
                 last row: cells {m} loses and wins in RMSE against the best, the mean of the ratios to VGC+DGS's \
                 RMSE, and of the ratios to IM's HDR-FLIP (with the cells it loses there)."
            ),
            header: vec![
                "scene, application".into(),
                "caches".into(),
                "best of the five (RMSE)".into(),
                format!("{m} / best"),
                format!("{m} / vgc+dgs"),
                format!("{m} FLIP / IM"),
            ],
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
