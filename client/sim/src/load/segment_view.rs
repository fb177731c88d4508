//! A segment as the load's robots read it: the fields of `dmp.v1.Segment` that time and place it, with the
//! positions kept as raw bytes (their count is the segment's length) and the robot id, velocities and
//! accelerations skipped. The robots only time the segments, and decoding 90 numbers a segment was a quarter of the
//! generator's CPU at 1,000 robots, taken from the server it shares the machine with.

use dmp_proto::v1;

/// `dmp.v1.Segment` with its positions as raw bytes (a packed `repeated double` has the wire type of `bytes`) and
/// its velocities, accelerations and robot id skipped.
#[derive(Clone, PartialEq, prost::Message)]
pub struct SegmentView {
    /// Sequence number within the stream.
    #[prost(uint64, tag = "2")]
    pub sequence: u64,
    /// Run time of the first point, seconds.
    #[prost(double, tag = "3")]
    pub start_time: f64,
    /// Step between points, seconds.
    #[prost(double, tag = "4")]
    pub dt: f64,
    /// Dimension of a point.
    #[prost(uint32, tag = "5")]
    pub dim: u32,
    /// The positions, packed little-endian doubles.
    #[prost(bytes = "bytes", tag = "6")]
    pub positions: prost::bytes::Bytes,
    /// `dmp.v1.SegmentStatus`.
    #[prost(enumeration = "v1::SegmentStatus", tag = "9")]
    pub status: i32,
    /// Scene version the segment was computed with.
    #[prost(uint64, tag = "10")]
    pub scene_version: u64,
    /// Wall time (Unix seconds) the first point is due at.
    #[prost(double, tag = "11")]
    pub start_unix_s: f64,
}

impl SegmentView {
    /// Points in the segment.
    pub fn points(&self) -> usize {
        self.positions.len() / 8 / (self.dim as usize).max(1)
    }
}

#[cfg(test)]
mod tests {
    use prost::Message;

    use super::*;

    #[test]
    fn a_segment_reads_as_its_view() {
        let seg = v1::Segment {
            robot_id: "r".into(),
            sequence: 7,
            start_time: 0.25,
            dt: 1e-3,
            dim: 3,
            positions: (0..30).map(f64::from).collect(),
            velocities: vec![1.0; 30],
            accelerations: vec![2.0; 30],
            status: v1::SegmentStatus::GoalReached as i32,
            scene_version: 4,
            start_unix_s: 1.7e9,
        };
        let view = SegmentView::decode(seg.encode_to_vec().as_slice()).unwrap();
        assert_eq!((view.sequence, view.start_time, view.dt, view.dim), (7, 0.25, 1e-3, 3));
        assert_eq!(
            (view.status(), view.scene_version, view.start_unix_s),
            (v1::SegmentStatus::GoalReached, 4, 1.7e9)
        );
        assert_eq!(view.points(), 10);
        // The raw positions are the packed doubles, in order.
        assert_eq!(f64::from_le_bytes(view.positions[8..16].try_into().unwrap()), 1.0);
        // An empty segment (a packed field with no values is not sent at all).
        let empty = v1::Segment { dim: 3, ..Default::default() };
        assert_eq!(SegmentView::decode(empty.encode_to_vec().as_slice()).unwrap().points(), 0);
    }
}
