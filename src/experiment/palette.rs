//! The colour of each method in the experiment's charts: a function of the method's name, so that a method
//! keeps its colour in every chart of a report whatever other lines a chart has (a colour taken from a
//! series' index made IM orange in one chart and black, the per-pixel colour, in the next).
//!
//! Known names (the placements, the per-pixel estimator and baselines, the references) have fixed colours
//! from a table ([`KNOWN`]); any other name gets one of [`OTHERS`] chosen by a stable hash of the name, so
//! it too is the same in every chart and every run. Depends on nothing of the crate; plotters' colour type only.

use plotters::style::RGBColor;

/// The fixed colours of known methods (Okabe–Ito first, for the placements readers compare most).
pub const KNOWN: [(&str, RGBColor); 15] = [
    ("per-pixel", RGBColor(0, 0, 0)),
    ("im", RGBColor(213, 94, 0)),
    ("sd", RGBColor(0, 114, 178)),
    ("sd+as", RGBColor(0, 158, 115)),
    ("vgc", RGBColor(204, 121, 167)),
    ("vgc+dgs", RGBColor(230, 159, 0)),
    ("refine", RGBColor(0, 90, 90)),
    ("vgc+as", RGBColor(86, 180, 233)),
    ("vgc+dgs:diff", RGBColor(160, 40, 40)),
    ("vgc+dgs:geom", RGBColor(40, 40, 160)),
    ("none", RGBColor(120, 120, 120)),
    ("converged", RGBColor(60, 60, 60)),
    ("ao", RGBColor(140, 86, 75)),
    ("power", RGBColor(148, 103, 189)),
    ("uniform", RGBColor(128, 128, 0)),
];

/// The colours of names [`KNOWN`] lacks, picked by a hash of the name.
pub const OTHERS: [RGBColor; 8] = [
    RGBColor(23, 190, 207),
    RGBColor(214, 39, 40),
    RGBColor(44, 160, 44),
    RGBColor(31, 119, 180),
    RGBColor(227, 119, 194),
    RGBColor(188, 189, 34),
    RGBColor(255, 127, 14),
    RGBColor(90, 60, 30),
];

/// The method a series name stands for: lower case, without a per-pixel count (`per-pixel:4`, `power:16`)
/// and without the varied parameters a label may carry after a space (`vgc ratio=0.2`).
pub fn method_of(name: &str) -> String {
    let name = name.trim().to_lowercase();
    let first = name.split_whitespace().next().unwrap_or("").to_string();
    match first.rsplit_once(':') {
        Some((label, n)) if n.parse::<u64>().is_ok() => label.to_string(),
        _ => first,
    }
}

/// The colour of the series `name` in every chart: [`KNOWN`]'s for a known method, else one of [`OTHERS`]
/// by the name's FNV-1a hash.
pub fn colour_of(name: &str) -> RGBColor {
    let method = method_of(name);
    if let Some((_, c)) = KNOWN.iter().find(|(n, _)| *n == method) {
        return *c;
    }
    let h = method.bytes().fold(0xcbf2_9ce4_8422_2325u64, |h, b| (h ^ b as u64).wrapping_mul(0x0100_0000_01b3));
    OTHERS[(h % OTHERS.len() as u64) as usize]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_method_has_one_colour_whatever_the_chart_holds() {
        // The colour depends on the name only: IM is IM's colour, never the per-pixel black.
        assert_eq!(colour_of("im"), RGBColor(213, 94, 0));
        assert_eq!(colour_of("IM"), colour_of("im"));
        assert_eq!(colour_of("per-pixel"), RGBColor(0, 0, 0));
        assert_eq!(colour_of("per-pixel:16"), colour_of("per-pixel"));
        assert_eq!(colour_of("power:4"), colour_of("power"));
        assert_eq!(colour_of("vgc+dgs ratio=0.2"), colour_of("vgc+dgs"));
        assert_ne!(colour_of("im"), colour_of("per-pixel"));
        // Every known method has its own colour, and no fallback repeats one of them.
        for (i, (a, ca)) in KNOWN.iter().enumerate() {
            assert_eq!(colour_of(a), *ca);
            for (b, cb) in &KNOWN[i + 1..] {
                assert_ne!(ca, cb, "{a} and {b}");
            }
            assert!(!OTHERS.contains(ca), "{a}");
        }
        // An unknown name gets a fallback colour, the same every time.
        let c = colour_of("my-new-placement");
        assert!(OTHERS.contains(&c));
        assert_eq!(colour_of("my-new-placement"), c);
        assert_eq!(method_of(" Vgc+DGS:diff "), "vgc+dgs:diff");
    }
}
