//! A segment as a load generator's robots read it: the fields of `dmp.v1.Segment` that time and place it, with the
//! positions kept as raw bytes (their count is the segment's length), a pose run's orientations, angular velocities
//! and accelerations likewise (their counts checked against it), and the robot id, velocities and accelerations
//! skipped. Robots that only time the segments need no more, and decoding every number of a segment
//! costs a generator of many robots a large share of its CPU, taken from the server it may share the machine with.
//!
//! The field numbers come from the schema ([`crate::tags::segment`]); the codec is written with prost's field
//! encoders, as `#[derive(prost::Message)]` would write it.

use prost::bytes::{Buf, BufMut, Bytes};
use prost::encoding::{self, DecodeContext, WireType};

use crate::tags::segment as tag;
use crate::v1;

/// `dmp.v1.Segment` with its positions as raw bytes (a packed `repeated double` has the wire type of `bytes`) and
/// its velocities, accelerations and robot id skipped.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct SegmentView {
    /// Sequence number within the stream.
    pub sequence: u64,
    /// Run time of the first point, seconds.
    pub start_time: f64,
    /// Step between points, seconds.
    pub dt: f64,
    /// Dimension of a point.
    pub dim: u32,
    /// The positions, packed little-endian doubles.
    pub positions: Bytes,
    /// `dmp.v1.SegmentStatus`.
    pub status: i32,
    /// Scene version the segment was computed with.
    pub scene_version: u64,
    /// Wall time (Unix seconds) the first point is due at.
    pub start_unix_s: f64,
    /// A pose run's orientations (4 per point), packed little-endian doubles; empty otherwise.
    pub orientations: Bytes,
    /// A pose run's angular velocities (3 per point), packed; empty otherwise.
    pub angular_velocities: Bytes,
    /// A pose run's angular accelerations (3 per point), packed; empty otherwise.
    pub angular_accelerations: Bytes,
}

impl SegmentView {
    /// Points in the segment.
    pub fn points(&self) -> usize {
        self.positions.len() / 8 / (self.dim as usize).max(1)
    }

    /// Whether the pose fields hold `points()` orientations, angular velocities and accelerations (4, 3 and 3
    /// doubles a point), and the first orientation is a unit quaternion (within 1e-6): what a pose robot needs of
    /// every segment.
    pub fn has_pose(&self) -> bool {
        let n = self.points() * 8;
        let first: Vec<f64> = self.orientations.chunks_exact(8).take(4).map(f64_le).collect();
        let norm = first.iter().map(|v| v * v).sum::<f64>().sqrt();
        self.orientations.len() == 4 * n
            && self.angular_velocities.len() == 3 * n
            && self.angular_accelerations.len() == 3 * n
            && (n == 0 || (norm - 1.0).abs() <= 1e-6)
    }

    /// The status (an unknown value reads as the default).
    pub fn status(&self) -> v1::SegmentStatus {
        v1::SegmentStatus::try_from(self.status).unwrap_or_default()
    }
}

impl prost::Message for SegmentView {
    fn encode_raw(&self, buf: &mut impl BufMut) {
        if self.sequence != 0 {
            encoding::uint64::encode(tag::SEQUENCE, &self.sequence, buf);
        }
        if self.start_time != 0.0 {
            encoding::double::encode(tag::START_TIME, &self.start_time, buf);
        }
        if self.dt != 0.0 {
            encoding::double::encode(tag::DT, &self.dt, buf);
        }
        if self.dim != 0 {
            encoding::uint32::encode(tag::DIM, &self.dim, buf);
        }
        if !self.positions.is_empty() {
            encoding::bytes::encode(tag::POSITIONS, &self.positions, buf);
        }
        if self.status != 0 {
            encoding::int32::encode(tag::STATUS, &self.status, buf);
        }
        if self.scene_version != 0 {
            encoding::uint64::encode(tag::SCENE_VERSION, &self.scene_version, buf);
        }
        if self.start_unix_s != 0.0 {
            encoding::double::encode(tag::START_UNIX_S, &self.start_unix_s, buf);
        }
        for (t, b) in self.pose_fields() {
            if !b.is_empty() {
                encoding::bytes::encode(t, b, buf);
            }
        }
    }

    fn merge_field(
        &mut self,
        number: u32,
        wire_type: WireType,
        buf: &mut impl Buf,
        ctx: DecodeContext,
    ) -> Result<(), prost::DecodeError> {
        match number {
            tag::SEQUENCE => encoding::uint64::merge(wire_type, &mut self.sequence, buf, ctx),
            tag::START_TIME => encoding::double::merge(wire_type, &mut self.start_time, buf, ctx),
            tag::DT => encoding::double::merge(wire_type, &mut self.dt, buf, ctx),
            tag::DIM => encoding::uint32::merge(wire_type, &mut self.dim, buf, ctx),
            tag::POSITIONS => encoding::bytes::merge(wire_type, &mut self.positions, buf, ctx),
            tag::STATUS => encoding::int32::merge(wire_type, &mut self.status, buf, ctx),
            tag::SCENE_VERSION => encoding::uint64::merge(wire_type, &mut self.scene_version, buf, ctx),
            tag::START_UNIX_S => encoding::double::merge(wire_type, &mut self.start_unix_s, buf, ctx),
            tag::ORIENTATIONS => encoding::bytes::merge(wire_type, &mut self.orientations, buf, ctx),
            tag::ANGULAR_VELOCITIES => {
                encoding::bytes::merge(wire_type, &mut self.angular_velocities, buf, ctx)
            }
            tag::ANGULAR_ACCELERATIONS => {
                encoding::bytes::merge(wire_type, &mut self.angular_accelerations, buf, ctx)
            }
            _ => encoding::skip_field(wire_type, number, buf, ctx),
        }
    }

    fn encoded_len(&self) -> usize {
        let mut n = 0;
        if self.sequence != 0 {
            n += encoding::uint64::encoded_len(tag::SEQUENCE, &self.sequence);
        }
        if self.start_time != 0.0 {
            n += encoding::double::encoded_len(tag::START_TIME, &self.start_time);
        }
        if self.dt != 0.0 {
            n += encoding::double::encoded_len(tag::DT, &self.dt);
        }
        if self.dim != 0 {
            n += encoding::uint32::encoded_len(tag::DIM, &self.dim);
        }
        if !self.positions.is_empty() {
            n += encoding::bytes::encoded_len(tag::POSITIONS, &self.positions);
        }
        if self.status != 0 {
            n += encoding::int32::encoded_len(tag::STATUS, &self.status);
        }
        if self.scene_version != 0 {
            n += encoding::uint64::encoded_len(tag::SCENE_VERSION, &self.scene_version);
        }
        if self.start_unix_s != 0.0 {
            n += encoding::double::encoded_len(tag::START_UNIX_S, &self.start_unix_s);
        }
        for (t, b) in self.pose_fields() {
            if !b.is_empty() {
                n += encoding::bytes::encoded_len(t, b);
            }
        }
        n
    }

    fn clear(&mut self) {
        *self = Self::default();
    }
}

impl SegmentView {
    fn pose_fields(&self) -> [(u32, &Bytes); 3] {
        [
            (tag::ORIENTATIONS, &self.orientations),
            (tag::ANGULAR_VELOCITIES, &self.angular_velocities),
            (tag::ANGULAR_ACCELERATIONS, &self.angular_accelerations),
        ]
    }
}

fn f64_le(b: &[u8]) -> f64 {
    f64::from_le_bytes(b.try_into().unwrap_or([0; 8]))
}

#[cfg(test)]
mod tests {
    use prost::Message;

    use super::*;

    fn segment() -> v1::Segment {
        v1::Segment {
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
            ..Default::default()
        }
    }

    #[test]
    fn a_segment_reads_as_its_view() {
        let seg = segment();
        let view = SegmentView::decode(seg.encode_to_vec().as_slice()).unwrap();
        assert_eq!((view.sequence, view.start_time, view.dt, view.dim), (7, 0.25, 1e-3, 3));
        assert_eq!(
            (view.status(), view.scene_version, view.start_unix_s),
            (v1::SegmentStatus::GoalReached, 4, 1.7e9)
        );
        assert_eq!(view.points(), 10);
        // The raw positions are the packed doubles, in order.
        assert_eq!(f64::from_le_bytes(view.positions[8..16].try_into().unwrap()), 1.0);
        assert!(!view.has_pose(), "a position run has no orientations");
        let s = 0.5f64.sqrt();
        let pose = v1::Segment {
            orientations: [0.0, 0.0, s, s].repeat(10),
            angular_velocities: vec![0.1; 30],
            angular_accelerations: vec![0.2; 30],
            ..segment()
        };
        let view = SegmentView::decode(pose.encode_to_vec().as_slice()).unwrap();
        assert!(view.has_pose());
        let short = v1::Segment { angular_accelerations: vec![0.2; 27], ..pose.clone() };
        assert!(!SegmentView::decode(short.encode_to_vec().as_slice()).unwrap().has_pose());
        let skewed = v1::Segment { orientations: [0.0, 0.0, 0.5, s].repeat(10), ..pose.clone() };
        assert!(!SegmentView::decode(skewed.encode_to_vec().as_slice()).unwrap().has_pose());
        // A pose view encodes back to the same pose fields.
        let back = v1::Segment::decode(view.encode_to_vec().as_slice()).unwrap();
        assert_eq!(
            (back.orientations, back.angular_velocities, back.angular_accelerations),
            (pose.orientations, pose.angular_velocities, pose.angular_accelerations)
        );
        // An empty segment (a packed field with no values is not sent at all).
        let empty = v1::Segment { dim: 3, ..Default::default() };
        assert_eq!(SegmentView::decode(empty.encode_to_vec().as_slice()).unwrap().points(), 0);
    }

    #[test]
    fn a_view_encodes_as_the_segment_without_its_skipped_fields() {
        let seg = segment();
        let view = SegmentView::decode(seg.encode_to_vec().as_slice()).unwrap();
        let bytes = view.encode_to_vec();
        assert_eq!(bytes.len(), view.encoded_len());
        let back = v1::Segment::decode(bytes.as_slice()).unwrap();
        let skipped =
            v1::Segment { robot_id: String::new(), velocities: vec![], accelerations: vec![], ..seg };
        assert_eq!(back, skipped);
        assert_eq!(SegmentView::decode(&[][..]).unwrap(), SegmentView::default());
    }
}
