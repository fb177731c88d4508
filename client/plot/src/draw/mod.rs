//! The drawing layer: the SVG backend that plotters draws into, how things look, and the primitives the panels are
//! drawn with (curves, outlines, text, axes).

pub(crate) mod backend;
pub(crate) mod primitives;
pub(crate) mod style;
