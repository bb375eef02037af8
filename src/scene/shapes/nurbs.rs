//! STAGE 2 (scene loading): pbrt-v3's `nurbs` shape — a (rational) B-spline surface — diced into a
//! 30 × 30-vertex grid of triangles, as pbrt-v3's `CreateNURBS` does, and returned as [`MeshData`] in object
//! space with pbrt-v3's normals and (u, v).
//!
//! Input: the Shape's parameters (`nu`, `nv`, `uorder`, `vorder`, `uknots`, `vknots`, `u0`, `u1`, `v0`,
//! `v1`, and `P` or the homogeneous `Pw`). Output: [`MeshData`] with positions, normals, uvs and indices; the
//! scene builder places it like any other mesh.
//!
//! Depends only on `error`, the parameter list of `parse` and [`MeshData`]; nothing here knows about
//! transforms, materials or the BVH. Counts, orders, knots and the parameter range are checked before
//! anything is evaluated, so evaluation never indexes outside the control net.
#![cfg_attr(not(test), deny(clippy::unwrap_used, clippy::expect_used))]

use super::mesh_data::MeshData;
use crate::error::{Error, Result, SourceLoc, Warnings};
use crate::parse::ParamList;

/// pbrt-v3's fixed dicing rate: vertices along u and along v.
pub const DICE: usize = 30;

/// Highest order (degree + 1) accepted in either direction; evaluation costs grow with its cube.
pub const MAX_ORDER: usize = 32;

/// A homogeneous control point `(x w, y w, z w, w)` as pbrt-v3 stores it.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
struct Homogeneous {
    x: f64,
    y: f64,
    z: f64,
    w: f64,
}

impl Homogeneous {
    /// `self · a + other · (1 - a)`.
    fn blend(self, other: Homogeneous, a: f64) -> Homogeneous {
        Homogeneous {
            x: self.x * a + other.x * (1.0 - a),
            y: self.y * a + other.y * (1.0 - a),
            z: self.z * a + other.z * (1.0 - a),
            w: self.w * a + other.w * (1.0 - a),
        }
    }
}

/// One direction of the surface: order, knots (`count + order` of them, non-decreasing) and the number of
/// control points, checked by [`Direction::new`].
#[derive(Clone, Debug)]
pub struct Direction<'a> {
    order: usize,
    knots: &'a [f64],
    count: usize,
}

impl<'a> Direction<'a> {
    /// Checks that `2 ≤ order ≤ min(count, MAX_ORDER)`, that there are `count + order` finite knots in
    /// non-decreasing order and that the domain `[knots[order-1], knots[count]]` is not empty. The error
    /// names the direction's parameters with `axis` (`"u"` or `"v"`).
    pub fn new(axis: &str, order: usize, knots: &'a [f64], count: usize) -> std::result::Result<Self, String> {
        if !(2..=MAX_ORDER).contains(&order) {
            return Err(format!("\"{axis}order\" must be between 2 and {MAX_ORDER}, got {order}"));
        }
        if order > count {
            return Err(format!("\"{axis}order\" {order} is larger than the number of control points n{axis} {count}"));
        }
        if count.checked_add(order) != Some(knots.len()) {
            return Err(format!(
                "{} knots in \"{axis}knots\" do not match n{axis} {count} + {axis}order {order}",
                knots.len()
            ));
        }
        if let Some(i) = knots.iter().position(|k| !k.is_finite()) {
            return Err(format!("\"{axis}knots\" value {i} is not finite"));
        }
        if let Some(i) = knots.windows(2).position(|w| w[1] < w[0]) {
            return Err(format!("\"{axis}knots\" decrease at value {}: {} after {}", i + 1, knots[i + 1], knots[i]));
        }
        let d = Direction { order, knots, count };
        let (lo, hi) = d.domain();
        if lo >= hi {
            return Err(format!("\"{axis}knots\" give an empty parameter range [{lo}, {hi}]"));
        }
        Ok(d)
    }

    /// The parameter range pbrt-v3 uses by default: `[knots[order-1], knots[count]]`.
    pub fn domain(&self) -> (f64, f64) {
        (self.knots[self.order - 1], self.knots[self.count])
    }

    /// pbrt-v3's `KnotOffset`: the knot span `[knots[o], knots[o+1]]` holding `t` (`t` within the domain),
    /// moved past empty spans (where pbrt-v3 would divide by zero).
    fn span(&self, t: f64) -> usize {
        let k = self.knots;
        let mut o = self.order - 1;
        while o + 1 < self.count && t > k[o + 1] {
            o += 1;
        }
        // Only an empty span at the start of the domain can be reached (t equal to its knots); the nearest
        // non-empty span either side has t as an end. The domain is not empty, so one exists.
        let empty = |o: usize| k[o + 1] == k[o];
        let mut f = o;
        while empty(f) && f + 1 < self.count {
            f += 1;
        }
        if !empty(f) {
            return f;
        }
        while empty(o) && o > self.order - 1 {
            o -= 1;
        }
        o
    }

    /// pbrt-v3's `NURBSEvaluate`: the curve with control points `cp(0..count)` at `t`, and with `deriv` its
    /// derivative (of the projected point) with respect to `t`.
    fn evaluate(&self, cp: impl Fn(usize) -> Homogeneous, t: f64, deriv: bool) -> (Homogeneous, [f64; 3]) {
        let o = self.span(t);
        let order = self.order;
        // knot(i) is pbrt-v3's knot[i] after `knot += knotOffset`; i ≥ 2 - order, so o + i ≥ 1.
        let knot = |i: isize| self.knots[(o as isize + i) as usize];
        let first = o + 1 - order;
        let mut work: Vec<Homogeneous> = (0..order).map(|i| cp(first + i)).collect();
        for i in 0..order - 2 {
            for j in 0..order - 1 - i {
                let (j_, i_, ord) = (j as isize, i as isize, order as isize);
                let a = (knot(1 + j_) - t) / (knot(1 + j_) - knot(j_ + 2 - ord + i_));
                work[j] = work[j].blend(work[j + 1], a);
            }
        }
        let a = (knot(1) - t) / (knot(1) - knot(0));
        let val = work[0].blend(work[1], a);
        let mut d = [0.0; 3];
        if deriv {
            let factor = (order - 1) as f64 / (knot(1) - knot(0));
            let dx = (work[1].x - work[0].x) * factor;
            let dy = (work[1].y - work[0].y) * factor;
            let dz = (work[1].z - work[0].z) * factor;
            let dw = (work[1].w - work[0].w) * factor;
            let w2 = val.w * val.w;
            d = [dx / val.w - val.x * dw / w2, dy / val.w - val.y * dw / w2, dz / val.w - val.z * dw / w2];
        }
        (val, d)
    }
}

/// A NURBS surface: its two directions and `u.count × v.count` homogeneous control points, u fastest.
#[derive(Clone, Debug)]
pub struct Surface<'a> {
    u: Direction<'a>,
    v: Direction<'a>,
    cp: Vec<Homogeneous>,
}

impl<'a> Surface<'a> {
    /// A surface from control points given as `P` (`(x, y, z)`, weight 1: `dim` 3) or `Pw`
    /// (`(x w, y w, z w, w)`: `dim` 4), u fastest. Fails when the number of values is not
    /// `nu · nv · dim` or a value is not finite.
    pub fn new(u: Direction<'a>, v: Direction<'a>, values: &[f64], dim: usize) -> std::result::Result<Self, String> {
        let name = if dim == 4 { "Pw" } else { "P" };
        if !values.len().is_multiple_of(dim) {
            return Err(format!("{} values in \"{name}\" is not a multiple of {dim}", values.len()));
        }
        let n = values.len() / dim;
        if u.count.checked_mul(v.count) != Some(n) {
            return Err(format!(
                "expected {}×{}={} control points, got {n}",
                u.count,
                v.count,
                u.count as u128 * v.count as u128
            ));
        }
        if let Some(i) = values.iter().position(|x| !x.is_finite()) {
            return Err(format!("control point {} in \"{name}\" is not finite", i / dim));
        }
        let cp = values
            .chunks_exact(dim)
            .map(|c| Homogeneous { x: c[0], y: c[1], z: c[2], w: if dim == 4 { c[3] } else { 1.0 } })
            .collect();
        Ok(Surface { u, v, cp })
    }

    /// pbrt-v3's `NURBSEvaluateSurface`: the point at `(u, v)` and the partial derivatives ∂p/∂u, ∂p/∂v.
    /// `u` and `v` must lie in the directions' domains.
    fn evaluate(&self, u: f64, v: f64) -> ([f64; 3], [f64; 3], [f64; 3]) {
        let nu = self.u.count;
        let cp = |i: usize| self.cp.get(i).copied().unwrap_or_default();
        let u_first = self.u.span(u) + 1 - self.u.order;
        let iso: Vec<Homogeneous> =
            (0..self.u.order).map(|i| self.v.evaluate(|k| cp(u_first + i + k * nu), v, false).0).collect();
        let at =
            |iso: &[Homogeneous], first: usize, k: usize| iso.get(k.wrapping_sub(first)).copied().unwrap_or_default();
        let (p, dpdu) = self.u.evaluate(|k| at(&iso, u_first, k), u, true);
        let v_first = self.v.span(v) + 1 - self.v.order;
        let iso: Vec<Homogeneous> =
            (0..self.v.order).map(|i| self.u.evaluate(|k| cp((v_first + i) * nu + k), u, false).0).collect();
        let (_, dpdv) = self.v.evaluate(|k| at(&iso, v_first, k), v, true);
        ([p.x / p.w, p.y / p.w, p.z / p.w], dpdu, dpdv)
    }

    /// The diced mesh over `[u0, u1] × [v0, v1]` (each within its domain): [`DICE`]² vertices at evenly
    /// spaced parameters, each with its (u, v) and the unit normal `∂p/∂u × ∂p/∂v`, and two triangles per
    /// grid cell split along the `(i, j)`–`(i+1, j+1)` diagonal, as pbrt-v3.
    pub fn dice(&self, (u0, u1): (f64, f64), (v0, v1): (f64, f64)) -> MeshData {
        let lerp = |i: usize, a: f64, b: f64| {
            let t = (i as f32 / (DICE - 1) as f32) as f64;
            (1.0 - t) * a + t * b
        };
        let mut m = MeshData::default();
        for j in 0..DICE {
            let v = lerp(j, v0, v1);
            for i in 0..DICE {
                let u = lerp(i, u0, u1);
                let (p, du, dv) = self.evaluate(u, v);
                let n = [du[1] * dv[2] - du[2] * dv[1], du[2] * dv[0] - du[0] * dv[2], du[0] * dv[1] - du[1] * dv[0]];
                let len = (n[0] * n[0] + n[1] * n[1] + n[2] * n[2]).sqrt();
                m.positions.push(p.map(|x| x as f32));
                m.normals.push(n.map(|x| (x / len) as f32));
                m.uvs.push([u as f32, v as f32]);
            }
        }
        let vn = |i: usize, j: usize| (j * DICE + i) as u32;
        for j in 0..DICE - 1 {
            for i in 0..DICE - 1 {
                m.indices.extend([vn(i, j), vn(i + 1, j), vn(i + 1, j + 1)]);
                m.indices.extend([vn(i, j), vn(i + 1, j + 1), vn(i, j + 1)]);
            }
        }
        m
    }
}

/// Reads the parameters of `Shape "nurbs"` (pbrt-v3 `CreateNURBS`) and dices the surface. Missing
/// parameters, orders, knot counts, control-point counts, and `u0/u1/v0/v1` outside the knots' domain are
/// errors at the parameter's location. Normals that are not finite (where ∂p/∂u × ∂p/∂v vanishes) are all
/// dropped, with a warning.
pub fn nurbs_params(params: &ParamList, loc: &SourceLoc, warnings: &mut Warnings) -> Result<MeshData> {
    let at = |name: &str| params.loc_of(name).unwrap_or(loc).clone();
    let int = |name: &str| -> Result<usize> {
        let Some(n) = params.int(name)? else {
            return Err(Error::at(loc, format!("nurbs: missing required parameter \"integer {name}\"")));
        };
        usize::try_from(n).map_err(|_| Error::at(&at(name), format!("nurbs: \"{name}\" must not be negative, got {n}")))
    };
    let knots = |name: &str| -> Result<&[f64]> {
        params
            .floats(name)?
            .ok_or_else(|| Error::at(loc, format!("nurbs: missing required parameter \"float {name}\"")))
    };
    let (nu, uorder, uknots) = (int("nu")?, int("uorder")?, knots("uknots")?);
    let u = Direction::new("u", uorder, uknots, nu).map_err(|e| Error::at(&at("uknots"), format!("nurbs: {e}")))?;
    let (nv, vorder, vknots) = (int("nv")?, int("vorder")?, knots("vknots")?);
    let v = Direction::new("v", vorder, vknots, nv).map_err(|e| Error::at(&at("vknots"), format!("nurbs: {e}")))?;
    let range = |d: &Direction, n0: &str, n1: &str| -> Result<(f64, f64)> {
        let (lo, hi) = d.domain();
        let t0 = params.float_or(n0, lo)?;
        let t1 = params.float_or(n1, hi)?;
        for (name, t) in [(n0, t0), (n1, t1)] {
            if !(lo..=hi).contains(&t) {
                return Err(Error::at(
                    &at(name),
                    format!("nurbs: \"{name}\" {t} is outside the knots' parameter range [{lo}, {hi}]"),
                ));
            }
        }
        Ok((t0, t1))
    };
    let ur = range(&u, "u0", "u1")?;
    let vr = range(&v, "v0", "v1")?;
    let (surface, name) = match params.point3s("P")? {
        Some(p) => {
            let flat: Vec<f64> = p.iter().flatten().copied().collect();
            (Surface::new(u, v, &flat, 3), "P")
        }
        None => match params.floats("Pw")? {
            Some(pw) => (Surface::new(u, v, pw, 4), "Pw"),
            None => {
                return Err(Error::at(loc, "nurbs: missing control points: \"point3 P\" or \"float Pw\""));
            }
        },
    };
    let surface = surface.map_err(|e| Error::at(&at(name), format!("nurbs: {e}")))?;
    let mut mesh = surface.dice(ur, vr);
    if let Err(e) = mesh.validate() {
        return Err(Error::at(&at(name), format!("nurbs: {e} (is a weight zero?)")));
    }
    if mesh.drop_unusable_normals() > 0 {
        warnings.at(&at(name), "nurbs: the surface is degenerate somewhere (no normal there); using no normals");
    }
    Ok(mesh)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn close(a: [f32; 3], b: [f64; 3], tol: f64) -> bool {
        (0..3).all(|c| (a[c] as f64 - b[c]).abs() < tol)
    }

    #[test]
    fn a_bilinear_patch_is_the_plane_through_its_corners() {
        // Order 2 in both directions, 2×2 control points: p(u, v) = bilinear blend of the corners.
        let k = [0.0, 0.0, 1.0, 1.0];
        let u = Direction::new("u", 2, &k, 2).unwrap();
        let v = Direction::new("v", 2, &k, 2).unwrap();
        let corners = [0.0, 0.0, 1.0, 2.0, 0.0, 1.0, 0.0, 3.0, 2.0, 2.0, 3.0, 2.0];
        let s = Surface::new(u, v, &corners, 3).unwrap();
        let m = s.dice((0.0, 1.0), (0.0, 1.0));
        assert_eq!(m.positions.len(), DICE * DICE);
        assert_eq!(m.triangle_count(), 2 * (DICE - 1) * (DICE - 1));
        assert_eq!(m.validate(), Ok(()));
        // The plane z = 1 + x/... : corners (0,0,1) (2,0,1) (0,3,2) (2,3,2) lie on z = 1 + y/3.
        for (p, n) in m.positions.iter().zip(&m.normals) {
            assert!((p[2] as f64 - (1.0 + p[1] as f64 / 3.0)).abs() < 1e-6, "{p:?}");
            let want = [0.0, -1.0 / 3.0, 1.0];
            let l = (1.0f64 + 1.0 / 9.0).sqrt();
            assert!(close(*n, want.map(|x| x / l), 1e-6), "{n:?}");
        }
        // Vertex (i, j) is at parameter (i/29, j/29): x = 2u, y = 3v.
        let (i, j) = (7, 11);
        let (uu, vv) = (i as f64 / 29.0, j as f64 / 29.0);
        assert!(close(m.positions[j * DICE + i], [2.0 * uu, 3.0 * vv, 1.0 + vv], 1e-6));
        assert_eq!(m.uvs[j * DICE + i], [uu as f32, vv as f32]);
        assert_eq!(&m.indices[..6], &[0, 1, 31, 0, 31, 30]);
    }

    #[test]
    fn a_point_on_a_rational_quadratic_patch() {
        // Order 3 (quadratic) in u with a weighted middle point: a quarter circle of radius 1 in x–z,
        // extruded linearly along y (order 2). At u = 1/2 the point is (√2/2, y, √2/2) by the rational
        // Bézier formula: (P0 + w P1 ·2·¼·... ) — computed here by hand:
        // B0 = B2 = 1/4, B1 = 1/2; numerator = ¼(1,0) + ½·w·(1,1) + ¼(0,1), denominator = ¼ + ½ w + ¼.
        let w = std::f64::consts::FRAC_1_SQRT_2;
        let uk = [0.0, 0.0, 0.0, 1.0, 1.0, 1.0];
        let vk = [0.0, 0.0, 2.0, 2.0];
        let u = Direction::new("u", 3, &uk, 3).unwrap();
        let v = Direction::new("v", 2, &vk, 2).unwrap();
        let mut pw = Vec::new();
        for y in [0.0, 4.0] {
            pw.extend([1.0, y, 0.0, 1.0]);
            pw.extend([w, y * w, w, w]);
            pw.extend([0.0, y, 1.0, 1.0]);
        }
        let s = Surface::new(u, v, &pw, 4).unwrap();
        let den = 0.25 + 0.5 * w + 0.25;
        let x = (0.25 + 0.5 * w) / den;
        let (p, dpdu, dpdv) = s.evaluate(0.5, 1.0);
        assert!((p[0] - x).abs() < 1e-12 && (p[2] - x).abs() < 1e-12 && (p[1] - 2.0).abs() < 1e-12, "{p:?}");
        assert!((x - w).abs() < 1e-12, "the quarter circle's middle is at 45°");
        // Tangent along u is perpendicular to the radius; along v it is (0, 2, 0) per unit v.
        assert!((dpdu[0] * p[0] + dpdu[2] * p[2]).abs() < 1e-12 && dpdu[1].abs() < 1e-12);
        assert!(dpdv[0].abs() < 1e-12 && (dpdv[1] - 2.0).abs() < 1e-12 && dpdv[2].abs() < 1e-12);
        // Every diced point lies on the unit circle in x–z.
        let m = s.dice((0.0, 1.0), (0.0, 2.0));
        for q in &m.positions {
            assert!(((q[0] * q[0] + q[2] * q[2]) as f64 - 1.0).abs() < 1e-6, "{q:?}");
        }
        // A plain quadratic B-spline point with uniform knots: at u in the middle span, the point is
        // ½ (P1 + P2)·... the standard blend ½(1-s)² P0 + (½ + s - s²) P1 + ½ s² P2 at local s = 0.5.
        let uk2 = [0.0, 1.0, 2.0, 3.0, 4.0, 5.0];
        let u2 = Direction::new("u", 3, &uk2, 3).unwrap();
        let v2 = Direction::new("v", 2, &[0.0, 0.0, 1.0, 1.0], 2).unwrap();
        let pts = [0.0, 0.0, 0.0, 1.0, 0.0, 4.0, 2.0, 0.0, 0.0, 0.0, 1.0, 0.0, 1.0, 1.0, 4.0, 2.0, 1.0, 0.0];
        let s2 = Surface::new(u2, v2, &pts, 3).unwrap();
        let (p, _, _) = s2.evaluate(2.5, 0.0);
        let z = 0.125 * 0.0 + 0.75 * 4.0 + 0.125 * 0.0;
        let xx = 0.125 * 0.0 + 0.75 * 1.0 + 0.125 * 2.0;
        assert!((p[2] - z).abs() < 1e-12 && (p[0] - xx).abs() < 1e-12 && p[1].abs() < 1e-12, "{p:?}");
    }

    #[test]
    fn bad_parameters_are_errors() {
        let k = [0.0, 0.0, 1.0, 1.0];
        assert!(Direction::new("u", 1, &k[..3], 2).unwrap_err().contains("between 2 and"));
        assert!(Direction::new("u", 3, &k, 2).unwrap_err().contains("larger than the number of control points"));
        assert!(Direction::new("u", 2, &k[..3], 2).unwrap_err().contains("3 knots"));
        assert!(Direction::new("v", 2, &[0.0, 1.0, 0.5, 2.0], 2).unwrap_err().contains("decrease"));
        assert!(Direction::new("v", 2, &[0.0, 1.0, 1.0, 2.0], 2).unwrap_err().contains("empty parameter range"));
        let u = Direction::new("u", 2, &k, 2).unwrap();
        assert!(Surface::new(u.clone(), u.clone(), &[0.0; 9], 3).unwrap_err().contains("expected 2×2=4"));
        assert!(Surface::new(u.clone(), u.clone(), &[0.0; 15], 4).unwrap_err().contains("multiple of 4"));
        // A zero weight makes non-finite points, caught by validation rather than panicking.
        let m = Surface::new(u.clone(), u, &[0.0; 16], 4).unwrap().dice((0.0, 1.0), (0.0, 1.0));
        assert!(m.validate().is_err());
    }

    #[test]
    fn empty_knot_spans_are_skipped() {
        // Order 2 with knots 0 0 0 1 1: the first span of the domain, [k1, k2] = [0, 0], is empty; pbrt-v3
        // would divide by zero at u = 0. The point there is the second control point.
        let k = [0.0, 0.0, 0.0, 1.0, 1.0];
        let u = Direction::new("u", 2, &k, 3).unwrap();
        let v = Direction::new("v", 2, &[0.0, 0.0, 1.0, 1.0], 2).unwrap();
        assert_eq!(u.span(0.0), 2);
        assert_eq!(u.span(1.0), 2);
        let mut p = Vec::new();
        for y in [0.0, 1.0] {
            for x in [0.0, 1.0, 5.0] {
                p.extend([x, y, 0.0]);
            }
        }
        let s = Surface::new(u, v, &p, 3).unwrap();
        let (q, _, _) = s.evaluate(0.0, 0.5);
        assert_eq!(q, [1.0, 0.5, 0.0]);
        let (q, _, _) = s.evaluate(0.5, 0.5);
        assert_eq!(q, [3.0, 0.5, 0.0]);
    }
}
