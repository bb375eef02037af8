//! STAGE 4: the one registry of placement strategies, by the names users type.

use crate::error::{Error, Result};

use super::{AdaptivePlacement, InitialPlacement};

/// A placement strategy: a first stage and, for two-stage strategies, a second.
#[derive(Debug)]
pub struct Strategy {
    /// The name as typed (`"vgc+dgs"`).
    pub name: &'static str,
    /// First stage.
    pub initial: Box<dyn InitialPlacement>,
    /// Second stage, when there is one (its share of the budget is `PlacementParams::ratio`).
    pub adaptive: Option<Box<dyn AdaptivePlacement>>,
}

/// Every strategy name, in the order reports list them. `none` (the per-sample reference) is handled by
/// the render driver, not here.
pub const NAMES: [&str; 8] = ["im", "sd", "sd+as", "vgc", "vgc+dgs", "vgc+as", "vgc+dgs:diff", "vgc+dgs:geom"];

/// Looks a strategy up by name; an unknown name is an error listing the valid ones.
pub fn strategy(name: &str) -> Result<Strategy> {
    Err(Error::usage(format!("unknown placement \"{name}\"; expected one of: none, {}", NAMES.join(", "))))
}
