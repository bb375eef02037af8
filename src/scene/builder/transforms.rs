//! STAGE 2 (scene builder): transform directives — Identity, Translate, Scale, Rotate, LookAt, Transform,
//! ConcatTransform, CoordinateSystem, CoordSysTransform, ActiveTransform, TransformTimes.

use crate::error::{Error, Result, SourceLoc};
use crate::parse::{ActiveTransform, DirectiveKind};
use crate::scene::transform::Transform;

use super::SceneBuilder;

impl SceneBuilder {
    pub(super) fn transform_directive(&mut self, kind: DirectiveKind, loc: &SourceLoc) -> Result<()> {
        let what = kind.keyword();
        let bad = |e: String| Error::at(loc, format!("{what}: {e}"));
        let finite = |v: &[f64]| -> Result<()> {
            match v.iter().position(|x| !x.is_finite()) {
                Some(i) => Err(Error::at(loc, format!("{what}: value {} is not finite ({})", i + 1, v[i]))),
                None => Ok(()),
            }
        };
        match kind {
            DirectiveKind::Identity => self.set_ctm(|_| Ok(Transform::IDENTITY))?,
            DirectiveKind::Translate(d) => {
                finite(&d)?;
                let t = Transform::translate(d).map_err(bad)?;
                self.post_multiply(&t, loc)?;
            }
            DirectiveKind::Scale(s) => {
                finite(&s)?;
                let t = Transform::scale(s).map_err(bad)?;
                self.post_multiply(&t, loc)?;
            }
            DirectiveKind::Rotate(r) => {
                finite(&r)?;
                let t = Transform::rotate(r[0], [r[1], r[2], r[3]]).map_err(bad)?;
                self.post_multiply(&t, loc)?;
            }
            DirectiveKind::LookAt(v) => {
                finite(&v)?;
                let t = Transform::look_at([v[0], v[1], v[2]], [v[3], v[4], v[5]], [v[6], v[7], v[8]]).map_err(bad)?;
                self.post_multiply(&t, loc)?;
            }
            DirectiveKind::Transform(m) => {
                finite(&m)?;
                let t = Transform::from_pbrt(&m).map_err(bad)?;
                self.set_ctm(|_| Ok(t))?;
            }
            DirectiveKind::ConcatTransform(m) => {
                finite(&m)?;
                let t = Transform::from_pbrt(&m).map_err(bad)?;
                self.post_multiply(&t, loc)?;
            }
            DirectiveKind::CoordinateSystem(name) => {
                self.named_coords.insert(name, self.ctm);
            }
            DirectiveKind::CoordSysTransform(name) => match self.named_coords.get(&name) {
                Some(t) => self.ctm = *t,
                None => {
                    let mut known: Vec<&str> = self.named_coords.keys().map(|s| s.as_str()).collect();
                    known.sort();
                    self.warnings.at(
                        loc,
                        format!(
                            "CoordSysTransform: no coordinate system named \"{name}\" (known: {}); ignored",
                            known.join(", ")
                        ),
                    );
                }
            },
            DirectiveKind::ActiveTransform(a) => {
                self.active = match a {
                    ActiveTransform::Start => [true, false],
                    ActiveTransform::End => [false, true],
                    ActiveTransform::All => [true, true],
                };
            }
            DirectiveKind::TransformTimes(a, b) if !(a.is_finite() && b.is_finite()) => {
                return Err(Error::at(loc, "TransformTimes: times must be finite"));
            }
            _ => {}
        }
        self.check_motion(loc);
        Ok(())
    }

    fn set_ctm(&mut self, f: impl Fn(&Transform) -> Result<Transform>) -> Result<()> {
        for i in 0..2 {
            if self.active[i] {
                self.ctm[i] = f(&self.ctm[i])?;
            }
        }
        Ok(())
    }

    fn post_multiply(&mut self, t: &Transform, loc: &SourceLoc) -> Result<()> {
        self.set_ctm(|c| {
            let m = c.then_local(t);
            if !m.m.is_finite() || !m.inv.is_finite() {
                return Err(Error::at(loc, "the accumulated transform is no longer finite"));
            }
            Ok(m)
        })
    }

    /// pbrt-v3 supports two-level (motion-blur) transforms; cachert renders the start transform and says so
    /// once.
    fn check_motion(&mut self, loc: &SourceLoc) {
        if self.ctm[0] != self.ctm[1] && !self.motion_warned {
            self.motion_warned = true;
            self.warnings
                .at(loc, "animated transforms (ActiveTransform/TransformTimes) are rendered at their start transform");
        }
    }
}
