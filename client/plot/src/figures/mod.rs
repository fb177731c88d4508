//! The figures layer: a whole figure from its panels, time strip and legend, as an SVG document. One figure for
//! robots moving in 2-D or 3-D, one of coordinates against time for any other dimension.

pub(crate) mod space;
pub(crate) mod time;
