//! `cachert convert IN OUT [--exposure STOPS]`: pbrt's `imgtool convert` for the formats cachert knows.
//! Reads an EXR, PFM or PNG image, multiplies it by 2^STOPS and writes it in the format of OUT's
//! extension (PNG: 8-bit sRGB; EXR and PFM: float); an EXR's display/data windows and text attributes go
//! on to an EXR output. OUT is checked (extension, folder) before IN is read, and a failure writes nothing.
//!
//! A command over the image stage only: it must not depend on scenes or rendering.

use std::path::{Path, PathBuf};

use crate::error::{Error, Result};
use crate::image::{self, Format, Metadata};

/// Flags of `cachert convert`.
#[derive(clap::Args, Debug, Clone)]
pub struct ConvertArgs {
    /// The image to read (.exr, .pfm or .png).
    pub input: PathBuf,
    /// The image to write; its extension (.exr, .pfm or .png) picks the format.
    pub output: PathBuf,
    /// Scale every value by 2^STOPS before writing (negative darkens).
    #[arg(long, value_name = "STOPS", default_value_t = 0.0, allow_negative_numbers = true)]
    pub exposure: f64,
}

/// Runs `cachert convert` and returns the line to print.
pub fn run(args: &ConvertArgs) -> Result<String> {
    let scale = 2f64.powf(args.exposure) as f32;
    if !(scale.is_finite() && scale > 0.0) {
        return Err(Error::usage(format!(
            "--exposure {}: 2^STOPS must be a positive finite number (STOPS between about -126 and 127)",
            args.exposure
        )));
    }
    image::check_output("OUT", &args.output, true)?;
    let mut picture = image::read(&args.input)?;
    let is_exr = |p: &Path| Format::from_path(p).ok() == Some(Format::Exr);
    let meta = if is_exr(&args.input) && is_exr(&args.output) {
        image::read_metadata(&args.input)?
    } else {
        Metadata::default()
    };
    if scale != 1.0 {
        for v in picture.pixels.iter_mut().flatten() {
            *v *= scale;
        }
    }
    image::write_with(&picture, &args.output, &meta)?;
    Ok(format!(
        "wrote {} ({}x{}, exposure {:+} stops)",
        args.output.display(),
        picture.width,
        picture.height,
        args.exposure
    ))
}
