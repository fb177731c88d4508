//! The panels layer: each kind of panel drawn on its area, from the data with the drawing primitives and the
//! layout. One plane of robot space, one coordinate against time, and the time strip of speed, acceleration,
//! clearance (and orientation) under either.

pub(crate) mod coordinate;
pub(crate) mod plane;
pub(crate) mod strip;
