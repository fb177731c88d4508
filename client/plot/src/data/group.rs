//! The robots of a figure, as groups of DMP dimensions: which dimensions each owns, its name and footprint.

use dmp::Shape;

use super::input::PlotInput;
use crate::error::PlotError;

/// A robot: the DMP dimensions it owns, its name and footprint, and which robot of the input it is.
#[derive(Debug)]
pub(crate) struct Group<'a> {
    pub(crate) label: String,
    pub(crate) dims: Vec<usize>,
    /// Its index in [`PlotInput::robots`], which picks its colour; `None` for the one robot owning every dimension
    /// when no robot is given.
    pub(crate) index: Option<usize>,
    pub(crate) footprint: Option<&'a Shape>,
}

/// The robots of `input` (one owning all `d` dimensions if none is given), checked against each other and `d`.
pub(crate) fn groups<'a>(input: &PlotInput<'a>, d: usize) -> Result<Vec<Group<'a>>, PlotError> {
    if input.robots.is_empty() {
        return Ok(vec![Group {
            label: "robot".into(),
            dims: (0..d).collect(),
            index: None,
            footprint: None,
        }]);
    }
    let sub = input.robots[0].dims.len();
    for (index, r) in input.robots.iter().enumerate() {
        if r.dims.is_empty() {
            return Err(PlotError::Robot { index, reason: "owns no dimension".into() });
        }
        if r.dims.len() != sub {
            return Err(PlotError::Robot {
                index,
                reason: format!("owns {} dimensions, robots[0] owns {sub}", r.dims.len()),
            });
        }
        if let Some(k) = r.dims.iter().find(|&&k| k >= d) {
            return Err(PlotError::Robot {
                index,
                reason: format!("dimension {k} is outside the DMP's {d}"),
            });
        }
    }
    Ok(input
        .robots
        .iter()
        .enumerate()
        .map(|(i, r)| Group {
            label: r.id.clone(),
            dims: r.dims.clone(),
            index: Some(i),
            footprint: r.footprint.as_ref(),
        })
        .collect())
}
