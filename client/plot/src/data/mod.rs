//! The data layer: what a figure shows, before anything is drawn. The input as handed in, checked; the robots;
//! the curves, decimated; true shapes, clearance and contacts; everything projected on a panel's plane with its
//! data ranges. Nothing here knows of plotters or SVG.

pub(crate) mod bounds;
pub(crate) mod clearance;
pub(crate) mod curve;
pub(crate) mod decimate;
pub(crate) mod differences;
pub(crate) mod geometry;
pub(crate) mod group;
pub(crate) mod input;
pub(crate) mod margin;
pub(crate) mod outline;
pub(crate) mod plane;
pub(crate) mod pose;
pub(crate) mod quantity;
pub(crate) mod run;
pub(crate) mod safety;
pub(crate) mod solid;
pub(crate) mod truth;
pub(crate) mod validate;
