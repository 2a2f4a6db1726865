//! Mitsuba 0.6 spellings read into the same scene model (issue 38), kept apart from
//! `build.rs`: what the version names or defaults differently from Mitsuba 3.

use glam::{Mat3, Vec3};

use super::{Dialect, SceneBuilder};
use crate::Result;
use crate::formats::mitsuba::plugin::Plugin;
use crate::formats::mitsuba::props::ColorSpec;
use crate::model::ColorValue;

impl<'s> SceneBuilder<'_, 's> {
    /// A 2D texture's uv transform when it has no `to_uv`: Mitsuba 0.6's `uscale`, `vscale`,
    /// `uoffset` and `voffset` (`Texture2D`: uv' = (u·uscale + uoffset, v·vscale + voffset)),
    /// read in the legacy dialect only.
    pub(super) fn legacy_uv_transform(&mut self, pl: &Plugin<'s>) -> Result<Option<Mat3>> {
        if self.ctx.dialect != Dialect::Legacy {
            return Ok(None);
        }
        const NAMES: [&str; 4] = ["uscale", "vscale", "uoffset", "voffset"];
        if !NAMES.iter().any(|n| pl.props.has(n)) {
            return Ok(None);
        }
        let (su, sv) = (
            pl.props.float("uscale", 1.0)?,
            pl.props.float("vscale", 1.0)?,
        );
        let (ou, ov) = (
            pl.props.float("uoffset", 0.0)?,
            pl.props.float("voffset", 0.0)?,
        );
        Ok(Some(Mat3::from_cols_array(&[
            su, 0.0, 0.0, 0.0, sv, 0.0, ou, ov, 1.0,
        ])))
    }

    /// A `<spectrum value="v"/>` of one value in a Mitsuba 0.6 file: the grey (v, v, v), as
    /// Mitsuba 0.6's RGB builds read it for every use — Mitsuba 3 reads an emitter's as an
    /// equal-energy illuminant, pinker than white by 20 % in red. `None`: read as Mitsuba 3.
    pub(super) fn legacy_color(&self, spec: &ColorSpec) -> Option<ColorValue> {
        match spec {
            ColorSpec::Uniform(v) if self.ctx.dialect == Dialect::Legacy => {
                Some(ColorValue::Rgb(Vec3::splat(*v as f32)))
            }
            _ => None,
        }
    }
}
