//! STAGE 2 (scene): the `Film` directive — resolution, crop window, output name — and the pixel and sample
//! bounds pbrt-v3 derives from it.

use std::path::PathBuf;

use crate::error::{Error, Result, SourceLoc};
use crate::parse::Named;

/// The film as described in the scene (pbrt-v3 `image` film).
#[derive(Clone, Debug, PartialEq)]
pub struct FilmSpec {
    /// Full resolution (x, y) in pixels.
    pub resolution: [u32; 2],
    /// Crop window as fractions: x0, x1, y0, y1 (pbrt-v3 `cropwindow`).
    pub crop: [f64; 4],
    /// `"string filename"`, if given.
    pub filename: Option<PathBuf>,
    /// `"float scale"`: multiplies every pixel.
    pub scale: f32,
    /// `"float maxsampleluminance"`: samples brighter than this are scaled down (infinite: off).
    pub max_sample_luminance: f32,
    /// `"float diagonal"` in millimetres (used only by the realistic camera in pbrt-v3; kept for fidelity).
    pub diagonal: f32,
}

impl Default for FilmSpec {
    fn default() -> Self {
        FilmSpec {
            resolution: [1280, 720],
            crop: [0.0, 1.0, 0.0, 1.0],
            filename: None,
            scale: 1.0,
            max_sample_luminance: f32::INFINITY,
            diagonal: 35.0,
        }
    }
}

/// Bytes of memory per film pixel that a render needs (accumulation buffers plus the output image).
pub const BYTES_PER_PIXEL: u64 = 48;

/// Largest film memory cachert agrees to allocate where the machine's available memory is unknown.
pub const MAX_FILM_BYTES: u64 = 16 << 30;

/// The most film memory cachert agrees to allocate: the memory available now (`MemAvailable`), or
/// [`MAX_FILM_BYTES`] where that is unknown.
pub fn film_memory_limit() -> u64 {
    crate::os::available_memory_bytes().unwrap_or(MAX_FILM_BYTES)
}

/// Half-open integer pixel bounds [x0, x1) × [y0, y1).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct PixelBounds {
    /// Inclusive minimum corner.
    pub min: [i32; 2],
    /// Exclusive maximum corner.
    pub max: [i32; 2],
}

impl PixelBounds {
    /// Width and height (0 when empty).
    pub fn size(&self) -> [usize; 2] {
        [(self.max[0] - self.min[0]).max(0) as usize, (self.max[1] - self.min[1]).max(0) as usize]
    }

    /// Number of pixels.
    pub fn area(&self) -> usize {
        let [w, h] = self.size();
        w * h
    }
}

impl FilmSpec {
    /// Reads a `Film` directive. Refuses zero, negative or absurd resolutions before anything is allocated
    /// (whether the film fits in memory is the scene builder's check: a `--resolution` may replace it).
    pub fn from_directive(d: &Named) -> Result<FilmSpec> {
        if d.name != "image" {
            return Err(Error::at(&d.name_loc, format!("unknown film \"{}\"; pbrt-v3 has only \"image\"", d.name)));
        }
        let p = &d.params;
        let mut f = FilmSpec::default();
        let loc = |name: &str| p.loc_of(name).unwrap_or(&d.name_loc).clone();
        let x = p.int_or("xresolution", 1280)?;
        let y = p.int_or("yresolution", 720)?;
        f.resolution =
            [check_res(x, &loc("xresolution"), "xresolution")?, check_res(y, &loc("yresolution"), "yresolution")?];
        if let Some(cw) = p.floats("cropwindow")? {
            if cw.len() != 4 || cw.iter().any(|v| !v.is_finite()) {
                return Err(Error::at(
                    &loc("cropwindow"),
                    format!("cropwindow needs 4 finite numbers, got {}", cw.len()),
                ));
            }
            let c = |v: f64| v.clamp(0.0, 1.0);
            f.crop = [c(cw[0].min(cw[1])), c(cw[0].max(cw[1])), c(cw[2].min(cw[3])), c(cw[2].max(cw[3]))];
        }
        f.filename = p.string("filename")?.map(PathBuf::from);
        f.scale = p.float_or("scale", 1.0)? as f32;
        f.diagonal = p.float_or("diagonal", 35.0)? as f32;
        f.max_sample_luminance = p.float_or("maxsampleluminance", f64::INFINITY)? as f32;
        Ok(f)
    }

    /// The pixels that are written out: the crop window applied to the full resolution (pbrt-v3 rounds up).
    pub fn cropped_bounds(&self) -> PixelBounds {
        let [rx, ry] = self.resolution.map(|r| r as f64);
        let [x0, x1, y0, y1] = self.crop;
        PixelBounds {
            min: [(rx * x0).ceil() as i32, (ry * y0).ceil() as i32],
            max: [(rx * x1).ceil() as i32, (ry * y1).ceil() as i32],
        }
    }

    /// The pixels whose samples can reach the cropped image through a filter of `radius`.
    pub fn sample_bounds(&self, radius: [f32; 2]) -> PixelBounds {
        let c = self.cropped_bounds();
        PixelBounds {
            min: [0, 1].map(|i| (c.min[i] as f32 + 0.5 - radius[i]).floor() as i32),
            max: [0, 1].map(|i| (c.max[i] as f32 - 0.5 + radius[i]).ceil() as i32),
        }
    }
}

fn check_res(v: i64, loc: &SourceLoc, name: &str) -> Result<u32> {
    if v <= 0 {
        return Err(Error::at(loc, format!("{name} must be at least 1, got {v}")));
    }
    u32::try_from(v).map_err(|_| Error::at(loc, format!("{name} {v} is too large")))
}

/// Why a film of `res` pixels cannot be rendered here: its buffers would need more than
/// [`film_memory_limit`] (`None` when they fit).
pub fn memory_problem(res: [u32; 2]) -> Option<String> {
    let bytes = res[0] as u64 * res[1] as u64 * BYTES_PER_PIXEL;
    let limit = film_memory_limit();
    (bytes > limit).then(|| {
        format!(
            "film resolution {}x{} would need {} of memory; {} is available",
            res[0],
            res[1],
            human_bytes(bytes),
            human_bytes(limit)
        )
    })
}

/// [`memory_problem`] as an error at the Film directive `loc`.
pub fn check_memory(res: [u32; 2], loc: &SourceLoc) -> Result<()> {
    memory_problem(res).map_or(Ok(()), |m| Err(Error::at(loc, m)))
}

/// Formats a byte count with a binary unit (`1.5 GiB`).
pub fn human_bytes(b: u64) -> String {
    const UNITS: [&str; 6] = ["B", "KiB", "MiB", "GiB", "TiB", "PiB"];
    let mut v = b as f64;
    let mut u = 0;
    while v >= 1024.0 && u + 1 < UNITS.len() {
        v /= 1024.0;
        u += 1;
    }
    if u == 0 { format!("{b} B") } else { format!("{v:.1} {}", UNITS[u]) }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn crop_and_sample_bounds_follow_pbrt_v3() {
        let f = FilmSpec { resolution: [100, 50], crop: [0.25, 0.5, 0.0, 1.0], ..Default::default() };
        assert_eq!(f.cropped_bounds(), PixelBounds { min: [25, 0], max: [50, 50] });
        assert_eq!(f.sample_bounds([0.5, 0.5]), f.cropped_bounds());
        assert_eq!(f.sample_bounds([2.0, 2.0]), PixelBounds { min: [23, -2], max: [52, 52] });
    }

    #[test]
    fn human_sizes() {
        assert_eq!(human_bytes(512), "512 B");
        assert_eq!(human_bytes(3 << 30), "3.0 GiB");
    }
}
