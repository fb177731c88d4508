//! The layout layer: where things go on the page. The figure's frame (title, panels, time strip, legend column), a
//! panel's chart inside its area, and the legend.

pub(crate) mod chart;
pub(crate) mod frame;
pub(crate) mod legend;
