//! A segment as the load's robots read it: `dmp_proto::segment_view`, next to the schema its field numbers come
//! from. (This file only keeps the load's module path; it can go when the load's imports name `dmp_proto`.)

pub use dmp_proto::segment_view::SegmentView;
