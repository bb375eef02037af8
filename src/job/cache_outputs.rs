//! Outputs of a cache-based render beside the image: the cache overlay (stage-1 caches in red, stage-2 in
//! cyan, on the image), the DGS discontinuity map (EXR, plus a PNG next to it) and the statistics as JSON.

use std::path::Path;

use crate::error::{Error, Result};
use crate::image::{Image, write};
use crate::integrator::cache::CachedOutput;

const STAGE1: [f32; 3] = [1.0, 0.1, 0.05];
const STAGE2: [f32; 3] = [0.0, 0.9, 1.0];

/// The image with a dot on every cache pixel (stage 1 red, stage 2 cyan).
pub fn overlay(out: &CachedOutput) -> Image {
    let mut img = out.image.clone();
    let w = img.width;
    for (sites, colour) in [(&out.stage1, STAGE1), (&out.stage2, STAGE2)] {
        for &id in sites {
            let (x, y) = (id as usize % w.max(1), id as usize / w.max(1));
            if x < img.width && y < img.height {
                img.set(x, y, colour);
            }
        }
    }
    img
}

/// Writes the overlay PNG (or any format by extension).
pub fn write_overlay(out: &CachedOutput, path: &Path) -> Result<()> {
    write(&overlay(out), path)
}

/// Writes the discontinuity map to `path` (by extension) and, unless `path` is already a PNG, a PNG preview
/// with the same stem. Fails when the strategy made no map.
pub fn write_dmap(out: &CachedOutput, path: &Path) -> Result<()> {
    let Some(d) = &out.discontinuity else {
        return Err(Error::usage(
            "--dmap: this placement has no discontinuity map (use vgc+dgs or one of its ablations)",
        ));
    };
    let (w, h) = (out.image.width, out.image.height);
    let mut img = Image::new(w, h);
    let max = d.iter().cloned().fold(0.0f32, f32::max);
    for (i, &v) in d.iter().enumerate().take(w * h) {
        img.set(i % w, i / w, [v; 3]);
    }
    write(&img, path)?;
    if path.extension().and_then(|e| e.to_str()) != Some("png") {
        let mut preview = img.clone();
        if max > 0.0 {
            preview.pixels.iter_mut().for_each(|p| *p = p.map(|v| v / max));
        }
        write(&preview, &path.with_extension("png"))?;
    }
    Ok(())
}

/// Writes the statistics as JSON (atomically, like every output), or to standard output when `path` is `-`.
pub fn write_stats(out: &CachedOutput, settings: &serde_json::Value, path: &Path) -> Result<()> {
    let v = serde_json::json!({ "settings": settings, "stats": &out.stats });
    let text =
        serde_json::to_string_pretty(&v).map_err(|e| Error::file(path, format!("cannot encode statistics: {e}")))?;
    if path == Path::new("-") {
        println!("{text}");
        return Ok(());
    }
    crate::image::write_bytes(path, text.as_bytes())
}
