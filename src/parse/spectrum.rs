//! STAGE 1 (parse): colour parameters (`rgb`, `xyz`, `blackbody`, `spectrum`) → linear sRGB.

use crate::error::Result;
use crate::parse::params::Param;

/// Converts a colour parameter of type rgb, xyz, blackbody or spectrum to linear sRGB (pbrt-v3's RGB mode).
pub fn param_to_rgb(p: &Param) -> Result<[f64; 3]> {
    let _ = p;
    todo!("spectrum conversion: being written")
}
