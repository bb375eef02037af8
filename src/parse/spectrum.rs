//! STAGE 1 (parse): colour parameters (`rgb`, `xyz`, `blackbody`, `spectrum`) → linear sRGB, the way
//! pbrt-v3 does in its RGB mode.
//!
//! Input is one parsed [`Param`]; output is an RGB triple or an error at the parameter. Sampled spectra (given
//! inline, read from an `.spd` file, or a blackbody) are integrated against the CIE 1931 colour matching
//! functions at 1 nm steps over 360–830 nm, scaled like pbrt-v3's `RGBSpectrum::FromSampled` and converted
//! with pbrt-v3's `XYZToRGB` matrix. The matching functions are not tabulated here: we use the multi-lobe
//! Gaussian fit of Wyman, Sloan and Shirley, "Simple Analytic Approximations to the CIE XYZ Color Matching
//! Functions", JCGT 2(2), 2013, eq. 2–4 (within about 1 % of pbrt-v3's tables for smooth spectra).
//! Knows nothing about rendering.
#![cfg_attr(not(test), deny(clippy::indexing_slicing, clippy::panic))]

use std::path::Path;

use crate::error::{Error, Result};
use crate::parse::params::{Param, ParamType, ParamValue};

/// Shortest wavelength pbrt-v3 integrates over, in nm.
const LAMBDA_MIN: f64 = 360.0;
/// Longest wavelength pbrt-v3 integrates over, in nm.
const LAMBDA_MAX: f64 = 830.0;
/// Samples at 1 nm steps from `LAMBDA_MIN` to `LAMBDA_MAX` (pbrt-v3's `nCIESamples`).
const CIE_SAMPLES: usize = 471;

/// Converts a colour parameter of type rgb, xyz, blackbody or spectrum to linear sRGB (pbrt-v3's RGB mode).
///
/// | type | value | result |
/// |---|---|---|
/// | `rgb` | one triple | as given |
/// | `xyz` | one triple | [`xyz_to_rgb`] |
/// | `blackbody` | one pair: temperature (K), scale | scale × RGB of the Planck spectrum normalised to its peak |
/// | `spectrum` | (wavelength nm, value) pairs, or one `.spd` file name | RGB of the sampled spectrum |
///
/// An `.spd` file holds whitespace-separated wavelength/value pairs (`#` starts a comment) and is found
/// relative to the folder of the file the parameter is written in.
pub fn param_to_rgb(p: &Param) -> Result<[f64; 3]> {
    match p.ty {
        ParamType::Rgb => triple(p),
        ParamType::Xyz => triple(p).map(xyz_to_rgb),
        ParamType::Blackbody => blackbody_param(p),
        ParamType::Spectrum => spectrum_param(p),
        other => {
            Err(param_err(p, format!("expected an rgb, xyz, blackbody or spectrum value, found type {}", other.word())))
        }
    }
}

/// pbrt-v3's `XYZToRGB`: CIE XYZ to linear sRGB (D65 white).
pub fn xyz_to_rgb([x, y, z]: [f64; 3]) -> [f64; 3] {
    [
        3.240479 * x - 1.537150 * y - 0.498535 * z,
        -0.969256 * x + 1.875991 * y + 0.041556 * z,
        0.055648 * x - 0.204043 * y + 1.057311 * z,
    ]
}

/// Linear sRGB of a spectrum given as (wavelength nm, value) samples in any order, interpolated linearly
/// and held constant beyond the first and last sample (pbrt-v3's `RGBSpectrum::FromSampled`). No samples
/// give black.
pub fn sampled_to_rgb(samples: &[(f64, f64)]) -> [f64; 3] {
    let mut sorted = samples.to_vec();
    sorted.sort_by(|a, b| a.0.total_cmp(&b.0));
    xyz_to_rgb(spectrum_to_xyz(|l| interpolate(&sorted, l)))
}

/// Linear sRGB of a blackbody at `kelvin`, its spectrum divided by its value at the peak wavelength
/// (pbrt-v3's `BlackbodyNormalized`), so the brightest colour component is near 1 for any temperature.
pub fn blackbody_to_rgb(kelvin: f64) -> [f64; 3] {
    let peak_nm = 2.8977721e-3 / kelvin * 1e9; // Wien's displacement law
    let peak = planck(peak_nm, kelvin);
    xyz_to_rgb(spectrum_to_xyz(|l| planck(l, kelvin) / peak))
}

/// Spectral radiance of a blackbody at wavelength `nm` and temperature `kelvin` (Planck's law, W/(m²·sr·m)).
fn planck(nm: f64, kelvin: f64) -> f64 {
    const C: f64 = 299_792_458.0;
    const H: f64 = 6.626_069_57e-34;
    const KB: f64 = 1.380_648_8e-23;
    let l = nm * 1e-9;
    2.0 * H * C * C / (l.powi(5) * (((H * C) / (l * KB * kelvin)).exp() - 1.0))
}

/// The CIE 1931 2° matching functions x̄, ȳ, z̄ at wavelength `nm`: Wyman, Sloan and Shirley 2013, eq. 2–4
/// (piecewise Gaussians with a different width on each side of the mean).
fn cie_xyz(nm: f64) -> [f64; 3] {
    let g = |mu: f64, below: f64, above: f64| {
        let t = (nm - mu) / if nm < mu { below } else { above };
        (-0.5 * t * t).exp()
    };
    [
        1.056 * g(599.8, 37.9, 31.0) + 0.362 * g(442.0, 16.0, 26.7) - 0.065 * g(501.1, 20.4, 26.2),
        0.821 * g(568.8, 46.9, 40.5) + 0.286 * g(530.9, 16.3, 31.1),
        1.217 * g(437.0, 11.8, 36.0) + 0.681 * g(459.0, 26.0, 13.8),
    ]
}

/// XYZ of spectrum `f` (a function of wavelength in nm), summed at 1 nm steps and scaled as pbrt-v3 does:
/// by (λmax − λmin) / (∫ȳ · n), where ∫ȳ is the same 1 nm sum of ȳ, so a constant 1 has Y = 470/471.
fn spectrum_to_xyz(f: impl Fn(f64) -> f64) -> [f64; 3] {
    let mut xyz = [0.0; 3];
    let mut y_integral = 0.0;
    for i in 0..CIE_SAMPLES {
        let nm = LAMBDA_MIN + i as f64;
        let cmf = cie_xyz(nm);
        let v = f(nm);
        xyz.iter_mut().zip(cmf).for_each(|(acc, c)| *acc += v * c);
        y_integral += cmf[1];
    }
    let scale = (LAMBDA_MAX - LAMBDA_MIN) / (y_integral * CIE_SAMPLES as f64);
    xyz.map(|c| c * scale)
}

/// Linear interpolation in samples sorted by wavelength, constant beyond the ends.
fn interpolate(sorted: &[(f64, f64)], nm: f64) -> f64 {
    let (Some(&(l0, v0)), Some(&(l1, v1))) = (sorted.first(), sorted.last()) else { return 0.0 };
    if nm <= l0 {
        return v0;
    }
    if nm >= l1 {
        return v1;
    }
    let i = sorted.partition_point(|s| s.0 <= nm);
    match (sorted.get(i.saturating_sub(1)), sorted.get(i)) {
        (Some(&(la, va)), Some(&(lb, vb))) if lb > la => va + (vb - va) * (nm - la) / (lb - la),
        (Some(&(_, va)), _) => va,
        _ => 0.0,
    }
}

fn param_err(p: &Param, msg: impl std::fmt::Display) -> Error {
    Error::at(&p.loc, format!("parameter \"{}\": {msg}", p.name))
}

fn numbers(p: &Param) -> &[f64] {
    match &p.value {
        ParamValue::Numbers(v) => v,
        _ => &[],
    }
}

/// The single triple of an `rgb` or `xyz` parameter.
fn triple(p: &Param) -> Result<[f64; 3]> {
    match numbers(p) {
        &[a, b, c] => Ok([a, b, c]),
        v => Err(param_err(p, format!("expected 1 {} value (3 numbers), got {} numbers", p.ty.word(), v.len()))),
    }
}

/// pbrt-v3's blackbody: one (temperature K, scale) pair.
fn blackbody_param(p: &Param) -> Result<[f64; 3]> {
    let &[kelvin, scale] = numbers(p) else {
        let n = numbers(p).len();
        return Err(param_err(p, format!("expected 1 blackbody value (temperature and scale), got {n} numbers")));
    };
    if !(kelvin.is_finite() && kelvin > 0.0) {
        return Err(param_err(p, format!("blackbody temperature must be a positive number of kelvin, got {kelvin}")));
    }
    Ok(blackbody_to_rgb(kelvin).map(|c| c * scale))
}

/// A sampled spectrum written inline or in an `.spd` file.
fn spectrum_param(p: &Param) -> Result<[f64; 3]> {
    let samples = match &p.value {
        ParamValue::Strings(names) => match names.as_slice() {
            [name] => {
                let path = p.loc.file.parent().unwrap_or(Path::new("")).join(name);
                let values = read_spd(p, &path)?;
                pairs(p, &values, &format!("spectrum file \"{}\": ", path.display()))?
            }
            _ => return Err(param_err(p, format!("expected one spectrum file name, got {}", names.len()))),
        },
        _ => pairs(p, numbers(p), "")?,
    };
    Ok(sampled_to_rgb(&samples))
}

/// (wavelength, value) pairs from a flat list; an odd count, no samples or a non-finite wavelength is an
/// error (its message starts with `context`).
fn pairs(p: &Param, values: &[f64], context: &str) -> Result<Vec<(f64, f64)>> {
    if values.is_empty() || !values.len().is_multiple_of(2) {
        let msg = format!("{context}expected wavelength and value pairs, got {} numbers", values.len());
        return Err(param_err(p, msg));
    }
    let samples: Vec<(f64, f64)> = values
        .chunks_exact(2)
        .filter_map(|c| match *c {
            [l, v] => Some((l, v)),
            _ => None,
        })
        .collect();
    if let Some((l, _)) = samples.iter().find(|(l, _)| !l.is_finite()) {
        return Err(param_err(p, format!("{context}wavelength {l} is not a finite number")));
    }
    Ok(samples)
}

/// The numbers of the `.spd` file at `path` (`#` starts a comment); errors are reported at parameter `p`.
fn read_spd(p: &Param, path: &Path) -> Result<Vec<f64>> {
    let text = std::fs::read_to_string(path)
        .map_err(|e| param_err(p, format!("cannot read spectrum file \"{}\": {e}", path.display())))?;
    let mut values = Vec::new();
    for (n, line) in text.lines().enumerate() {
        let data = line.split('#').next().unwrap_or("");
        for word in data.split_whitespace() {
            let x = word.parse::<f64>().map_err(|_| {
                param_err(
                    p,
                    format!("spectrum file \"{}\" line {}: malformed number \"{word}\"", path.display(), n + 1),
                )
            })?;
            values.push(x);
        }
    }
    Ok(values)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::error::SourceLoc;
    use std::path::PathBuf;
    use std::sync::Arc;

    fn param_in(file: &Path, ty: ParamType, value: ParamValue) -> Param {
        Param::new(ty, "c", value, SourceLoc::new(Arc::from(file), 3, 5))
    }

    fn param(ty: ParamType, value: ParamValue) -> Param {
        param_in(Path::new("t.pbrt"), ty, value)
    }

    fn nums(v: &[f64]) -> ParamValue {
        ParamValue::Numbers(v.to_vec())
    }

    fn close(a: [f64; 3], b: [f64; 3], rel: f64) -> bool {
        a.iter().zip(b).all(|(x, y)| (x - y).abs() <= rel * y.abs().max(1e-3))
    }

    fn err(p: &Param) -> String {
        param_to_rgb(p).unwrap_err().to_string()
    }

    #[test]
    fn rgb_and_xyz() {
        assert_eq!(param_to_rgb(&param(ParamType::Rgb, nums(&[0.1, 0.2, 0.3]))).unwrap(), [0.1, 0.2, 0.3]);
        let white = param_to_rgb(&param(ParamType::Xyz, nums(&[1.0, 1.0, 1.0]))).unwrap();
        assert!(close(white, [1.204794, 0.948291, 0.908916], 1e-9), "{white:?}");
        let two = param(ParamType::Rgb, nums(&[1.0, 1.0, 1.0, 0.0, 0.0, 0.0]));
        assert_eq!(err(&two), "t.pbrt:3:5: parameter \"c\": expected 1 rgb value (3 numbers), got 6 numbers");
        let words = param(ParamType::Xyz, ParamValue::Strings(vec!["x".into()]));
        assert_eq!(err(&words), "t.pbrt:3:5: parameter \"c\": expected 1 xyz value (3 numbers), got 0 numbers");
        let float = param(ParamType::Float, nums(&[1.0]));
        assert_eq!(
            err(&float),
            "t.pbrt:3:5: parameter \"c\": expected an rgb, xyz, blackbody or spectrum value, found type float"
        );
    }

    #[test]
    fn a_constant_spectrum_is_white() {
        let flat = param(ParamType::Spectrum, nums(&[300.0, 1.0, 900.0, 1.0]));
        let rgb = param_to_rgb(&flat).unwrap();
        assert!(close(rgb, xyz_to_rgb([1.0; 3]), 0.01), "{rgb:?}");
        // pbrt-v3 with its CIE tables gives (1.20233, 0.94622, 0.90734).
        assert!(close(rgb, [1.20233, 0.94622, 0.90734], 0.01), "{rgb:?}");
    }

    #[test]
    fn sample_order_does_not_matter_and_values_are_interpolated() {
        let sorted = [(400.0, 0.0), (500.0, 1.0), (700.0, 0.5)];
        let shuffled = [(700.0, 0.5), (400.0, 0.0), (500.0, 1.0)];
        assert_eq!(sampled_to_rgb(&sorted), sampled_to_rgb(&shuffled));
        assert_eq!(interpolate(&sorted, 450.0), 0.5);
        assert_eq!(interpolate(&sorted, 600.0), 0.75);
        assert_eq!(interpolate(&sorted, 300.0), 0.0);
        assert_eq!(interpolate(&sorted, 800.0), 0.5);
        assert_eq!(sampled_to_rgb(&[]), [0.0; 3]);
    }

    #[test]
    fn blackbodies_match_pbrt_v3() {
        // pbrt-v3's results with its CIE tables (RGB mode, scale 1).
        let pbrt = [
            (3000.0, [0.73506, 0.35049, 0.11298]),
            (6500.0, [0.92222, 0.86950, 0.91522]),
            (10000.0, [0.38594, 0.44029, 0.63353]),
        ];
        for (kelvin, want) in pbrt {
            let got = blackbody_to_rgb(kelvin);
            assert!(close(got, want, 0.02), "{kelvin} K: {got:?} vs {want:?}");
        }
        let warm = param_to_rgb(&param(ParamType::Blackbody, nums(&[3000.0, 2.0]))).unwrap();
        assert!(warm[0] > warm[1] && warm[1] > warm[2], "3000 K should be orange: {warm:?}");
        assert!(close(warm, blackbody_to_rgb(3000.0).map(|c| 2.0 * c), 1e-12));
        let cool = blackbody_to_rgb(10000.0);
        assert!(cool[2] > cool[1] && cool[1] > cool[0], "10000 K should be blue: {cool:?}");
    }

    #[test]
    fn blackbody_errors() {
        let pairs = param(ParamType::Blackbody, nums(&[3000.0, 1.0, 5000.0, 1.0]));
        assert_eq!(
            err(&pairs),
            "t.pbrt:3:5: parameter \"c\": expected 1 blackbody value (temperature and scale), got 4 numbers"
        );
        let cold = param(ParamType::Blackbody, nums(&[0.0, 1.0]));
        assert_eq!(
            err(&cold),
            "t.pbrt:3:5: parameter \"c\": blackbody temperature must be a positive number of kelvin, got 0"
        );
    }

    #[test]
    fn sampled_spectrum_errors() {
        let odd = param(ParamType::Spectrum, nums(&[400.0, 1.0, 500.0]));
        assert_eq!(err(&odd), "t.pbrt:3:5: parameter \"c\": expected wavelength and value pairs, got 3 numbers");
        let empty = param(ParamType::Spectrum, nums(&[]));
        assert_eq!(err(&empty), "t.pbrt:3:5: parameter \"c\": expected wavelength and value pairs, got 0 numbers");
        let inf = param(ParamType::Spectrum, nums(&[f64::INFINITY, 1.0]));
        assert_eq!(err(&inf), "t.pbrt:3:5: parameter \"c\": wavelength inf is not a finite number");
        let two = param(ParamType::Spectrum, ParamValue::Strings(vec!["a.spd".into(), "b.spd".into()]));
        assert_eq!(err(&two), "t.pbrt:3:5: parameter \"c\": expected one spectrum file name, got 2");
    }

    #[test]
    fn spd_files_resolve_next_to_the_parameter_file() {
        let dir: PathBuf = std::env::temp_dir().join(format!("cachert-spectrum-{}", std::process::id()));
        std::fs::create_dir_all(dir.join("spds")).unwrap();
        let scene = dir.join("scene.pbrt");
        let spd = |name: &str| param_in(&scene, ParamType::Spectrum, ParamValue::Strings(vec![name.into()]));
        std::fs::write(dir.join("spds/flat.spd"), "# a flat spectrum\n300 1 # start\n\n900 1\n").unwrap();
        std::fs::write(dir.join("spds/odd.spd"), "300 1\n900\n").unwrap();
        std::fs::write(dir.join("spds/bad.spd"), "300 1\n900 one\n").unwrap();
        let flat = param_to_rgb(&spd("spds/flat.spd"));
        let odd = param_to_rgb(&spd("spds/odd.spd")).map_err(|e| e.to_string());
        let bad = param_to_rgb(&spd("spds/bad.spd")).map_err(|e| e.to_string());
        let missing = param_to_rgb(&spd("spds/none.spd")).map_err(|e| e.to_string());
        let _ = std::fs::remove_dir_all(&dir);
        let d = dir.display();
        assert!(close(flat.unwrap(), xyz_to_rgb([1.0; 3]), 0.01));
        let at = format!("{d}/scene.pbrt:3:5: parameter \"c\"");
        assert_eq!(
            odd.unwrap_err(),
            format!("{at}: spectrum file \"{d}/spds/odd.spd\": expected wavelength and value pairs, got 3 numbers")
        );
        assert_eq!(
            bad.unwrap_err(),
            format!("{at}: spectrum file \"{d}/spds/bad.spd\" line 2: malformed number \"one\"")
        );
        assert_eq!(
            missing.unwrap_err(),
            format!("{at}: cannot read spectrum file \"{d}/spds/none.spd\": No such file or directory (os error 2)")
        );
    }
}
