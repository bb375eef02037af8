//! STAGE 2 (scene builder): the parameters of `Shape "curve"`, read as pbrt-v3's `CreateCurveShape` reads
//! them — control points "P" of a degree 2 or 3 Bézier or uniform B-spline ("integer degree", "string
//! basis"), turned into cubic Bézier pieces; "string type" flat/cylinder/ribbon; "float width" (or
//! "width0"/"width1", linear along the whole curve); "normal N" (ribbons: one per piece end); "integer
//! splitdepth" (or a float, as pbrt-v3 accepts). Invalid values are refused at the parameter that has them.

use glam::Vec3A;

use crate::error::{Error, Result, Warnings};
use crate::parse::{Named, ParamType};
use crate::scene::shapes::curve::CurveType;

/// Largest "splitdepth" used: 2^10 segments per piece (pbrt-v3 clamps its subdivision depth to 10 too).
const MAX_SPLIT_DEPTH: i64 = 10;

/// One cubic Bézier piece of a curve shape, in object space.
pub(super) struct CurvePiece {
    /// Control points.
    pub cp: [Vec3A; 4],
    /// Widths at the piece's ends.
    pub width: [f32; 2],
    /// Ribbon normals at the piece's ends.
    pub normals: Option<[Vec3A; 2]>,
}

/// A whole `curve` shape.
pub(super) struct CurveSpec {
    /// Its cubic Bézier pieces.
    pub pieces: Vec<CurvePiece>,
    /// Flat, cylinder or ribbon.
    pub kind: CurveType,
    /// Each piece is split into 2^split_depth segments.
    pub split_depth: u32,
}

fn lerp(t: f32, a: Vec3A, b: Vec3A) -> Vec3A {
    (1.0 - t) * a + t * b
}

/// Reads a `curve` shape's parameters.
pub(super) fn curve_params(n: &Named, warnings: &mut Warnings) -> Result<CurveSpec> {
    let p = &n.params;
    let at = |name: &str| p.loc_of(name).unwrap_or(&n.name_loc).clone();
    let width_param = |name: &str, default: f64| -> Result<f64> {
        let w = p.float_or(name, default)?;
        if w.is_finite() && w >= 0.0 {
            Ok(w)
        } else {
            Err(Error::at(&at(name), format!("curve \"{name}\" must be finite and not negative, got {w}")))
        }
    };
    let width = width_param("width", 1.0)?;
    let (w0, w1) = (width_param("width0", width)?, width_param("width1", width)?);
    if w0 == 0.0 && w1 == 0.0 {
        let name = if p.get("width1").is_some() { "width1" } else { "width" };
        return Err(Error::at(&at(name), "curve: the width is 0 at both ends; nothing to render"));
    }

    let degree = p.int_or("degree", 3)?;
    if degree != 2 && degree != 3 {
        return Err(Error::at(&at("degree"), format!("curve \"degree\" must be 2 or 3, got {degree}")));
    }
    let degree = degree as usize;
    let basis = p.string_or("basis", "bezier")?;
    if basis != "bezier" && basis != "bspline" {
        return Err(Error::at(
            &at("basis"),
            format!("curve \"basis\" must be \"bezier\" or \"bspline\", got \"{basis}\""),
        ));
    }
    let bezier = basis == "bezier";

    let Some(points) = p.point3s("P")? else {
        return Err(Error::at(&n.name_loc, "curve: missing parameter \"point P\""));
    };
    if points.iter().flatten().any(|c| !c.is_finite()) {
        return Err(Error::at(&at("P"), "curve \"P\" must be finite"));
    }
    let cp: Vec<Vec3A> = points.iter().map(|&[x, y, z]| Vec3A::new(x as f32, y as f32, z as f32)).collect();
    let n_pieces = piece_count(cp.len(), degree, bezier).map_err(|why| Error::at(&at("P"), why))?;

    let kind = match p.string_or("type", "flat")? {
        "flat" => CurveType::Flat,
        "cylinder" => CurveType::Cylinder,
        "ribbon" => CurveType::Ribbon,
        other => {
            return Err(Error::at(
                &at("type"),
                format!("curve \"type\" must be \"flat\", \"cylinder\" or \"ribbon\", got \"{other}\""),
            ));
        }
    };

    let normals = ribbon_normals(n, kind, n_pieces, warnings)?;

    let split_depth = split_depth(n, warnings)?;

    let mut pieces = Vec::with_capacity(n_pieces);
    for seg in 0..n_pieces {
        let c = piece_bezier(&cp, seg, degree, bezier);
        let t = |i: usize| i as f32 / n_pieces as f32;
        let width =
            [(1.0 - t(seg)) * w0 as f32 + t(seg) * w1 as f32, (1.0 - t(seg + 1)) * w0 as f32 + t(seg + 1) * w1 as f32];
        pieces.push(CurvePiece { cp: c, width, normals: normals.as_ref().map(|ns| [ns[seg], ns[seg + 1]]) });
    }
    Ok(CurveSpec { pieces, kind, split_depth })
}

/// How many pieces `cp_count` control points make for a curve of `degree`, or why they make none.
fn piece_count(cp_count: usize, degree: usize, bezier: bool) -> std::result::Result<usize, String> {
    let ncp = cp_count;
    Ok(if bezier {
        // The first piece has degree + 1 points; each further one reuses the last and adds `degree`.
        if ncp < degree + 1 || !(ncp - 1 - degree).is_multiple_of(degree) {
            return Err(format!(
                "curve: {ncp} control points; a degree {degree} Bézier curve needs {} + n·{degree} (n ≥ 0)",
                degree + 1
            ));
        }
        (ncp - 1) / degree
    } else {
        if ncp < degree + 1 {
            return Err(format!(
                "curve: {ncp} control points; a degree {degree} B-spline needs at least {}",
                degree + 1
            ));
        }
        ncp - degree
    })
}

/// The piece-end normals of a ribbon (`None` for the other types, which ignore them with a warning).
fn ribbon_normals(n: &Named, kind: CurveType, n_pieces: usize, warnings: &mut Warnings) -> Result<Option<Vec<Vec3A>>> {
    let p = &n.params;
    let at = |name: &str| p.loc_of(name).unwrap_or(&n.name_loc).clone();
    Ok(match (p.normals("N")?, kind) {
        (Some(_), CurveType::Flat | CurveType::Cylinder) => {
            warnings.at(&at("N"), "curve normals \"N\" are only used with \"ribbon\" curves (as in pbrt-v3); ignored");
            None
        }
        (Some(ns), CurveType::Ribbon) => {
            if ns.len() != n_pieces + 1 {
                return Err(Error::at(
                    &at("N"),
                    format!("curve: {} normals; a ribbon with {n_pieces} pieces needs {}", ns.len(), n_pieces + 1),
                ));
            }
            let ns: Vec<Vec3A> = ns.iter().map(|&[x, y, z]| Vec3A::new(x as f32, y as f32, z as f32)).collect();
            if ns.iter().any(|v| !v.is_finite() || v.length_squared() == 0.0) {
                return Err(Error::at(&at("N"), "curve \"N\": every normal must be finite and non-zero"));
            }
            Some(ns)
        }
        (None, CurveType::Ribbon) => {
            return Err(Error::at(&n.name_loc, "curve: \"ribbon\" curves need \"normal N\" at the piece ends"));
        }
        (None, _) => None,
    })
}

/// The four Bézier control points of piece `seg` of a curve of `degree` (2 is elevated to a cubic); a
/// uniform B-spline's piece is converted to Bézier form by blossoming (pbrt-v3's formulas).
fn piece_bezier(cp: &[Vec3A], seg: usize, degree: usize, bezier: bool) -> [Vec3A; 4] {
    if bezier {
        let b = &cp[seg * degree..];
        if degree == 2 {
            // Degree elevation to a cubic.
            [b[0], lerp(2.0 / 3.0, b[0], b[1]), lerp(1.0 / 3.0, b[1], b[2]), b[2]]
        } else {
            [b[0], b[1], b[2], b[3]]
        }
    } else {
        // Uniform B-spline to Bézier by blossoming (pbrt-v3's formulas).
        let b = &cp[seg..];
        if degree == 2 {
            let (p11, p22) = (lerp(0.5, b[0], b[1]), lerp(0.5, b[1], b[2]));
            [p11, lerp(2.0 / 3.0, p11, b[1]), lerp(1.0 / 3.0, b[1], p22), p22]
        } else {
            let p122 = lerp(2.0 / 3.0, b[0], b[1]);
            let p223 = lerp(1.0 / 3.0, b[1], b[2]);
            let p233 = lerp(2.0 / 3.0, b[1], b[2]);
            let p334 = lerp(1.0 / 3.0, b[2], b[3]);
            [lerp(0.5, p122, p223), p223, p233, lerp(0.5, p233, p334)]
        }
    }
}

/// The curve's `splitdepth` (int or float, default 3), capped at [`MAX_SPLIT_DEPTH`] with a warning.
fn split_depth(n: &Named, warnings: &mut Warnings) -> Result<u32> {
    let p = &n.params;
    let at = |name: &str| p.loc_of(name).unwrap_or(&n.name_loc).clone();
    let split = match p.get("splitdepth").map(|q| q.ty) {
        Some(ParamType::Float) => p.float("splitdepth")?.map(|f| f.trunc()),
        _ => p.int("splitdepth")?.map(|i| i as f64),
    }
    .unwrap_or(3.0);
    if split.is_nan() || split < 0.0 {
        return Err(Error::at(&at("splitdepth"), format!("curve \"splitdepth\" must not be negative, got {split}")));
    }
    Ok(if split > MAX_SPLIT_DEPTH as f64 {
        warnings.at(
            &at("splitdepth"),
            format!("curve \"splitdepth\" {split} would make 2^{split} segments per piece; using {MAX_SPLIT_DEPTH}"),
        );
        MAX_SPLIT_DEPTH as u32
    } else {
        split as u32
    })
}
