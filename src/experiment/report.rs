//! `report.html`: one self-contained page (pictures embedded as data URIs, no network) that opens with
//! which method wins where ([`super::wins`]) and the sweep's charts, then its tables (a table that would be
//! all "—" is left out) and, per scene and application at the middle budget (seed 0), the images side by side —
//! the reference and each method, its HDR-FLIP map and its cache overlay — a slider to compare any two of
//! them, and crops of the regions with the largest error.
//!
//! The page checks itself when it loads: every picture decoded and no script error, written to the body's
//! `data-check` attribute (`ok …` or `fail …`), which the headless-browser test reads.
//!
//! Depends on `jobs` (records, run files), `summary`, `wins`, `tables`, `figures`, `image` and `metrics`.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use base64::Engine as _;

use super::figures::Figure;
use super::jobs::{OVERLAY, RUNS, Record};
use super::spec::Spec;
use super::summary::{self, middle_budget, pairs};
use super::tables::{Table, escape};
use crate::error::Result;
use crate::image::Image;
use crate::metrics::{Metric, evaluate};

/// The report's file name inside the experiment folder.
pub const REPORT: &str = "report.html";

/// A `data:` URI of some bytes.
fn data_uri(mime: &str, bytes: &[u8]) -> String {
    format!("data:{mime};base64,{}", base64::engine::general_purpose::STANDARD.encode(bytes))
}

/// The exposure that maps the reference's 99th-percentile luminance to 1 (1 for a black image).
fn exposure(reference: &Image) -> f32 {
    let mut lum: Vec<f32> = reference
        .pixels
        .iter()
        .map(|p| 0.2126 * p[0] + 0.7152 * p[1] + 0.0722 * p[2])
        .filter(|v| v.is_finite())
        .collect();
    if lum.is_empty() {
        return 1.0;
    }
    lum.sort_by(f32::total_cmp);
    let p99 = lum[(lum.len() - 1) * 99 / 100];
    if p99 > 0.0 { 1.0 / p99 } else { 1.0 }
}

/// `img` × `k`, cropped to `[x0, x0 + w) × [y0, y0 + h)`.
fn crop_scaled(img: &Image, k: f32, (x0, y0, w, h): (usize, usize, usize, usize)) -> Image {
    let mut out = Image::new(w, h);
    for y in 0..h {
        for x in 0..w {
            out.set(x, y, img.get(x0 + x, y0 + y).map(|v| v * k));
        }
    }
    out
}

/// The `count` windows of side `size` (stride size/2) with the largest summed `error`, not overlapping,
/// largest first.
fn worst_windows(error: &[f32], width: usize, height: usize, size: usize, count: usize) -> Vec<(usize, usize)> {
    if size == 0 || size > width || size > height {
        return Vec::new();
    }
    let step = (size / 2).max(1);
    let mut windows = Vec::new();
    let mut y = 0;
    while y + size <= height {
        let mut x = 0;
        while x + size <= width {
            let sum: f64 =
                (y..y + size).flat_map(|yy| (x..x + size).map(move |xx| error[yy * width + xx] as f64)).sum();
            windows.push((sum, x, y));
            x += step;
        }
        y += step;
    }
    windows.sort_by(|a, b| b.0.total_cmp(&a.0));
    let mut chosen: Vec<(usize, usize)> = Vec::new();
    for (_, x, y) in windows {
        if chosen.iter().all(|&(cx, cy)| x.abs_diff(cx) >= size || y.abs_diff(cy) >= size) {
            chosen.push((x, y));
            if chosen.len() == count {
                break;
            }
        }
    }
    chosen
}

/// One picture of a group: its element id, caption and PNG.
struct Picture {
    id: String,
    caption: String,
    png: Vec<u8>,
}

/// The images section of one scene and application; `n` numbers the element ids.
fn group(spec: &Spec, records: &[Record], out: &Path, scene: &str, app: &str, n: usize) -> Result<Option<String>> {
    let runs = out.join(RUNS);
    let Some(caches) = middle_budget(records, scene, app) else { return Ok(None) };
    let methods = summary::methods_at(records, scene, app, caches);
    let firsts: Vec<&Record> = methods.values().filter_map(|rs| rs.iter().min_by_key(|r| r.seed).copied()).collect();
    let Some(reference_id) =
        firsts.first().and_then(|r| spec.jobs.iter().find(|j| j.id == r.id)).map(|j| j.reference.clone())
    else {
        return Ok(None);
    };
    let reference = crate::image::read(&runs.join(format!("{reference_id}.exr")))?;
    let k = exposure(&reference);
    let whole = (0, 0, reference.width, reference.height);
    let mut pictures = vec![Picture {
        id: format!("g{n}-reference"),
        caption: "reference".into(),
        png: crate::image::png_bytes(&crop_scaled(&reference, k, whole))?,
    }];
    let mut maps: Vec<Picture> = Vec::new();
    let mut overlays: Vec<Picture> = Vec::new();
    let mut images: Vec<(String, Image)> = Vec::new();
    let mut error_sum = vec![0.0f32; reference.pixels.len()];
    for (i, r) in firsts.iter().enumerate() {
        let img = crate::image::read(&runs.join(format!("{}.exr", r.id)))?;
        let eval = evaluate(&img, &reference, &[Metric::Flip])?;
        let caption = format!("{} (RMSE {:.5}, HDR-FLIP {:.5})", r.method, r.rmse, r.flip);
        if let Some(h) = &eval.hdr_flip {
            error_sum.iter_mut().zip(&h.map.values).for_each(|(s, v)| *s += v);
            let rgb = crate::metrics::colormap::magma_rgb8(&h.map.values);
            maps.push(Picture {
                id: format!("g{n}-m{i}-flip"),
                caption: format!("{}: HDR-FLIP map", r.method),
                png: crate::image::rgb8_png_bytes(h.map.width, h.map.height, &rgb)?,
            });
        }
        if let Ok(bytes) = std::fs::read(runs.join(format!("{}{OVERLAY}", r.id))) {
            overlays.push(Picture {
                id: format!("g{n}-m{i}-overlay"),
                caption: format!(
                    "{}: {} caches (stage 1 red, stage 2 cyan)",
                    r.method,
                    r.caches_placed[0] + r.caches_placed[1]
                ),
                png: bytes,
            });
        }
        pictures.push(Picture {
            id: format!("g{n}-m{i}"),
            caption,
            png: crate::image::png_bytes(&crop_scaled(&img, k, whole))?,
        });
        images.push((r.method.clone(), img));
    }
    let mut h = String::new();
    let _ = writeln!(
        h,
        "<section id=\"g{n}\"><h2>Images: {}, {}</h2>\n<p class=\"note\">{caches} caches, seed 0, exposure ×{k:.3} \
         (the reference's 99th percentile at white). Drag the slider to compare any two pictures.</p>",
        escape(scene),
        escape(app)
    );
    comparer_and_grids(&mut h, n, &pictures, &maps, &overlays);
    largest_error_crops(&mut h, &reference, k, &images, &error_sum)?;
    h.push_str("</section>\n");
    Ok(Some(h))
}

/// The group's picture comparer (two pictures, B over A up to a slider) and its grids of images, HDR-FLIP
/// maps and cache overlays.
fn comparer_and_grids(h: &mut String, n: usize, pictures: &[Picture], maps: &[Picture], overlays: &[Picture]) {
    let all: Vec<&Picture> = pictures.iter().chain(maps).chain(overlays).collect();
    let options: String =
        all.iter().map(|p| format!("<option value=\"{}\">{}</option>", p.id, escape(&p.caption))).collect();
    let second = all.get(1).map_or(String::new(), |p| p.id.clone());
    let _ = writeln!(
        h,
        "<div class=\"compare\" data-a=\"g{n}-reference\" data-b=\"{second}\">\n<label>A <select class=\"a\">{options}</select></label> \
         <label>B <select class=\"b\">{options}</select></label> <button type=\"button\" class=\"swap\">swap</button>\n\
         <div class=\"stage\"><img class=\"ia\" alt=\"A\"><img class=\"ib\" alt=\"B\"></div>\n\
         <input type=\"range\" min=\"0\" max=\"100\" value=\"50\" class=\"slider\" aria-label=\"A | B\"></div>"
    );
    for (title, list) in [("Images", pictures), ("HDR-FLIP maps", maps), ("Cache overlays", overlays)] {
        if list.is_empty() {
            continue;
        }
        let _ = writeln!(h, "<h3>{title}</h3>\n<div class=\"grid\">");
        for p in list.iter() {
            let _ = writeln!(
                h,
                "<figure><img id=\"{}\" src=\"{}\" alt=\"{}\"><figcaption>{}</figcaption></figure>",
                p.id,
                data_uri("image/png", &p.png),
                escape(&p.caption),
                escape(&p.caption)
            );
        }
        h.push_str("</div>\n");
    }
}

/// Magnified crops of the windows where the methods' summed HDR-FLIP (`error_sum`) is largest: the
/// reference's and each method's.
fn largest_error_crops(
    h: &mut String,
    reference: &Image,
    k: f32,
    images: &[(String, Image)],
    error_sum: &[f32],
) -> Result<()> {
    let size = (reference.width.min(reference.height) / 5).max(8);
    let windows = worst_windows(error_sum, reference.width, reference.height, size, 2);
    if !windows.is_empty() {
        let _ = writeln!(
            h,
            "<h3>Largest errors</h3>\n<p class=\"note\">The {size}×{size} windows where the methods' summed HDR-FLIP is largest, magnified.</p>"
        );
    }
    for (x, y) in windows {
        let _ = writeln!(h, "<p>window at x {x}, y {y}</p>\n<div class=\"grid crops\">");
        let window = (x, y, size, size);
        let mut crops = vec![("reference".to_string(), crop_scaled(reference, k, window))];
        crops.extend(images.iter().map(|(m, img)| (m.clone(), crop_scaled(img, k, window))));
        for (m, c) in crops {
            let _ = writeln!(
                h,
                "<figure><img src=\"{}\" alt=\"{} crop\"><figcaption>{}</figcaption></figure>",
                data_uri("image/png", &crate::image::png_bytes(&c)?),
                escape(&m),
                escape(&m)
            );
        }
        h.push_str("</div>\n");
    }
    Ok(())
}

const STYLE: &str = "body{font-family:sans-serif;margin:1.5em;max-width:1500px;color:#222}\
table{border-collapse:collapse;margin:.5em 0 1.5em;font-size:13px}td,th{border:1px solid #ccc;padding:2px 6px;text-align:right}\
th{background:#f0f0f0}td:first-child,td:nth-child(2){text-align:left}.note{color:#555;font-size:13px;max-width:1100px}\
.grid{display:flex;flex-wrap:wrap;gap:8px}figure{margin:0}figure img{display:block;max-width:100%}\
.grid figure img{width:320px;image-rendering:pixelated}figcaption{font-size:12px;max-width:320px}.crops img{width:192px;image-rendering:pixelated}\
.charts img{width:100%;max-width:1200px}.stage{position:relative;display:inline-block;margin:6px 0}\
.stage img{display:block;width:800px;max-width:100%;image-rendering:pixelated}.stage .ib{position:absolute;left:0;top:0}\
.slider{width:100%;max-width:800px;display:block}nav a{margin-right:1em}";

/// Fills the comparers from their selects, moves the clip with the slider, and checks the page.
const SCRIPT: &str = r#"
function setup(c) {
  const a = c.querySelector('select.a'), b = c.querySelector('select.b');
  const ia = c.querySelector('img.ia'), ib = c.querySelector('img.ib');
  const s = c.querySelector('input.slider');
  a.value = c.dataset.a; b.value = c.dataset.b;
  const show = () => {
    ia.src = document.getElementById(a.value).src;
    ib.src = document.getElementById(b.value).src;
    ib.style.clipPath = 'inset(0 0 0 ' + s.value + '%)';
  };
  a.addEventListener('change', show); b.addEventListener('change', show);
  s.addEventListener('input', show);
  c.querySelector('button.swap').addEventListener('click', () => { const t = a.value; a.value = b.value; b.value = t; show(); });
  show();
  return show;
}
window.addEventListener('DOMContentLoaded', () => {
  for (const c of document.querySelectorAll('.compare')) {
    const show = setup(c);
    const s = c.querySelector('input.slider');
    s.value = 30; s.dispatchEvent(new Event('input'));
    c.querySelector('button.swap').click(); c.querySelector('button.swap').click();
    s.value = 50; show();
  }
});
window.addEventListener('load', () => {
  const imgs = Array.from(document.images);
  const broken = imgs.filter(i => !i.complete || i.naturalWidth === 0).map(i => i.alt);
  const ok = broken.length === 0 && window.__errors.length === 0;
  document.body.setAttribute('data-check', (ok ? 'ok' : 'fail') + ' images=' + imgs.length +
    ' broken=' + broken.join(',') + ' errors=' + window.__errors.join(' | '));
});
"#;

/// The charts section: each figure's SVG embedded, with its caption.
fn charts(body: &mut String, figures: &[Figure]) -> Result<()> {
    body.push_str("<section id=\"charts\" class=\"charts\"><h2>Charts</h2>\n");
    for f in figures {
        let svg = std::fs::read(&f.svg).map_err(|e| crate::error::Error::file(&f.svg, format!("cannot read: {e}")))?;
        let name = f.svg.file_stem().map(|s| s.to_string_lossy().into_owned()).unwrap_or_default();
        let _ = writeln!(
            body,
            "<figure><img src=\"{}\" alt=\"{}\"><figcaption>{} {}: {}</figcaption></figure>",
            data_uri("image/svg+xml", &svg),
            escape(&name),
            escape(&f.scene),
            escape(&f.application),
            escape(&f.caption)
        );
    }
    body.push_str("</section>\n");
    Ok(())
}

/// Writes `out/report.html` from the sweep's records, tables and charts; returns its path. The page opens
/// with the summary of which method wins where and the charts; the tables (those with data) and the
/// images of each scene and application follow.
pub fn write(spec: &Spec, records: &[Record], tables: &[Table], figures: &[Figure], out: &Path) -> Result<PathBuf> {
    let mut body = String::new();
    let ok = summary::ok(records).count();
    let _ = writeln!(
        body,
        "<h1>Experiment: {}</h1>\n<p class=\"note\">{} runs: {ok} measured, {} failed or missing (see the All runs tables). \
         Every error is against the per-sample reference of the same estimator.</p>",
        escape(&spec.path.display().to_string()),
        records.len(),
        records.len() - ok
    );
    let groups = pairs(records);
    let wins = super::wins::html(&super::wins::winners(records));
    body.push_str("<nav>");
    if !wins.is_empty() {
        body.push_str("<a href=\"#summary\">who wins</a>");
    }
    body.push_str("<a href=\"#charts\">charts</a><a href=\"#tables\">tables</a>");
    for (i, (s, a)) in groups.iter().enumerate() {
        let _ = write!(body, "<a href=\"#g{i}\">{} {}</a>", escape(s), escape(a));
    }
    body.push_str("</nav>\n");
    // What a reader wants first: who wins, then the charts; the tables and the images follow.
    body.push_str(&wins);
    charts(&mut body, figures)?;
    body.push_str("<section id=\"tables\"><h2>Tables</h2>\n");
    for t in tables.iter().filter(|t| t.has_data()) {
        body.push_str(&t.html());
    }
    body.push_str("</section>\n");
    for (i, (s, a)) in groups.iter().enumerate() {
        if let Some(h) = group(spec, records, out, s, a, i)? {
            body.push_str(&h);
        }
    }
    let page = format!(
        "<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\"><title>cachert experiment</title>\n\
         <script>window.__errors = []; window.addEventListener('error', e => window.__errors.push(String(e.message || \
         (e.target && e.target.alt) || e.type)), true);</script>\n<style>{STYLE}</style></head>\n<body>\n{body}\n\
         <script>{SCRIPT}</script>\n</body></html>\n"
    );
    let path = out.join(REPORT);
    crate::image::write_bytes(&path, page.as_bytes())?;
    Ok(path)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_worst_windows_are_found_and_do_not_overlap() {
        let (w, h) = (16, 8);
        let mut e = vec![0.0f32; w * h];
        e[3 * w + 12] = 5.0; // one hot pixel, right half
        e[5 * w + 2] = 1.0; // a weaker one, left half
        let got = worst_windows(&e, w, h, 4, 2);
        assert_eq!(got.len(), 2);
        let (x, y) = got[0];
        assert!((x..x + 4).contains(&12) && (y..y + 4).contains(&3), "{got:?}");
        let (x, y) = got[1];
        assert!((x..x + 4).contains(&2) && (y..y + 4).contains(&5), "{got:?}");
        assert!(worst_windows(&e, w, h, 9, 1).is_empty());
    }

    #[test]
    fn exposure_puts_the_99th_percentile_at_one() {
        let mut img = Image::new(100, 1);
        for x in 0..100 {
            img.set(x, 0, [x as f32; 3]);
        }
        assert!((exposure(&img) - 1.0 / 98.0).abs() < 1e-6);
        assert_eq!(exposure(&Image::new(4, 4)), 1.0);
    }
}
