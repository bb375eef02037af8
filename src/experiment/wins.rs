//! The summary a report opens with: which method wins where. Per scene, application and budget, the plain
//! cache method (no varied parameter) with the lowest mean RMSE and the one with the lowest mean HDR-FLIP
//! over seeds, and per application how often each method is the winner. Generated from the records alone,
//! so it always says what the tables below it show.
//!
//! Depends only on the records of `jobs` and on [`super::summary`]; it reads no file.

use std::collections::BTreeMap;
use std::fmt::Write as _;

use super::jobs::Record;
use super::summary::{budgets, errors, methods_at, pairs};
use super::tables::escape;

/// The winners of one setting: scene, application and budget.
#[derive(Clone, Debug, PartialEq)]
pub struct Win {
    /// The scene.
    pub scene: String,
    /// The application.
    pub application: String,
    /// The budget.
    pub caches: usize,
    /// The method with the lowest mean RMSE, and that mean.
    pub rmse: (String, f64),
    /// The method with the lowest mean HDR-FLIP, and that mean.
    pub flip: (String, f64),
}

/// The winners of every setting with at least one measured cache method, in scene, application and
/// budget order. Ties go to the method whose name sorts first.
pub fn winners(records: &[Record]) -> Vec<Win> {
    let mut out = Vec::new();
    for (scene, app) in pairs(records) {
        for caches in budgets(records, &scene, &app) {
            let means: Vec<(String, f64, f64)> = methods_at(records, &scene, &app, caches)
                .into_iter()
                .filter_map(|(m, rs)| errors(&rs).map(|(r, f)| (m, r.mean, f.mean)))
                .collect();
            let best = |key: fn(&(String, f64, f64)) -> f64| {
                means.iter().min_by(|a, b| key(a).total_cmp(&key(b))).map(|m| (m.0.clone(), key(m)))
            };
            if let (Some(rmse), Some(flip)) = (best(|m| m.1), best(|m| m.2)) {
                out.push(Win { scene: scene.clone(), application: app.clone(), caches, rmse, flip });
            }
        }
    }
    out
}

/// How often each method wins among `wins` by `pick` (`rmse` or `flip`), as "vgc+dgs in 3 of 4 settings,
/// im in 1", most wins first.
fn tally(wins: &[&Win], pick: fn(&Win) -> &str) -> String {
    let mut count: BTreeMap<&str, usize> = BTreeMap::new();
    for w in wins {
        *count.entry(pick(w)).or_default() += 1;
    }
    let mut list: Vec<(&str, usize)> = count.into_iter().collect();
    list.sort_by(|a, b| b.1.cmp(&a.1).then(a.0.cmp(b.0)));
    list.iter()
        .enumerate()
        .map(
            |(i, (m, n))| {
                if i == 0 { format!("{m} in {n} of {} settings", wins.len()) } else { format!("{m} in {n}") }
            },
        )
        .collect::<Vec<_>>()
        .join(", ")
}

/// The summary as HTML: a section with one list item per application (its tally) and, under it, one per
/// setting; empty when no setting has a measured cache method.
pub fn html(wins: &[Win]) -> String {
    if wins.is_empty() {
        return String::new();
    }
    let mut apps: Vec<&str> = wins.iter().map(|w| w.application.as_str()).collect();
    apps.dedup();
    apps.sort();
    apps.dedup();
    let mut h = String::from(
        "<section id=\"summary\"><h2>Which method wins where</h2>\n<p class=\"note\">The plain cache method with \
         the lowest mean RMSE and the one with the lowest mean HDR-FLIP over seeds, per scene, application and \
         budget (whether the lead is clear is in the tables' \"Which method wins\").</p>\n<ul>\n",
    );
    for app in apps {
        let mine: Vec<&Win> = wins.iter().filter(|w| w.application == app).collect();
        let _ = writeln!(
            h,
            "<li><b>{}</b>: lowest RMSE: {}; lowest HDR-FLIP: {}.\n<ul>",
            escape(app),
            escape(&tally(&mine, |w| &w.rmse.0)),
            escape(&tally(&mine, |w| &w.flip.0))
        );
        for w in mine {
            let _ = writeln!(
                h,
                "<li>{}, {} caches: lowest RMSE <b>{}</b> ({:.5}), lowest HDR-FLIP <b>{}</b> ({:.5})</li>",
                escape(&w.scene),
                w.caches,
                escape(&w.rmse.0),
                w.rmse.1,
                escape(&w.flip.0),
                w.flip.1
            );
        }
        h.push_str("</ul></li>\n");
    }
    h.push_str("</ul></section>\n");
    h
}

#[cfg(test)]
mod tests {
    use super::*;

    fn run(scene: &str, placement: &str, caches: usize, seed: u64, rmse: f64, flip: f64) -> Record {
        Record {
            id: format!("{scene}-{placement}-{caches}-{seed}"),
            status: "ok".into(),
            scene: scene.into(),
            application: "app".into(),
            placement: placement.into(),
            method: placement.into(),
            caches,
            seed,
            rmse,
            flip,
            ..Record::default()
        }
    }

    #[test]
    fn the_lowest_means_win_per_setting_and_are_tallied_per_application() {
        let records = vec![
            run("a", "im", 10, 0, 0.3, 0.02),
            run("a", "im", 10, 1, 0.1, 0.02),
            run("a", "vgc", 10, 0, 0.25, 0.01),
            run("a", "vgc", 10, 1, 0.25, 0.01),
            run("a", "none", 0, 0, 0.0, 0.0),
            run("b", "im", 10, 0, 0.1, 0.05),
            run("b", "vgc", 10, 0, 0.2, 0.04),
        ];
        let w = winners(&records);
        assert_eq!(w.len(), 2);
        // im's mean RMSE 0.2 beats vgc's 0.25; vgc's FLIP is lower.
        assert_eq!((w[0].scene.as_str(), w[0].rmse.0.as_str(), w[0].flip.0.as_str()), ("a", "im", "vgc"));
        assert!((w[0].rmse.1 - 0.2).abs() < 1e-12);
        let h = html(&w);
        assert!(h.contains("lowest RMSE: im in 2 of 2 settings; lowest HDR-FLIP: vgc in 2 of 2 settings"), "{h}");
        assert!(h.contains("a, 10 caches: lowest RMSE <b>im</b> (0.20000)"), "{h}");
        assert_eq!(html(&[]), "");
    }
}
