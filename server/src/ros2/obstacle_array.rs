//! nav2_dynamic_msgs' tracked obstacles in a cell's scene: each is the box of its `size` at its `position`,
//! moving at its `velocity` (all in the header's frame), as obstacle `track-<uuid>`. An array is the whole set of
//! its topic: obstacles of the previous array that are not in the new one are deleted.

use std::collections::{HashMap, HashSet};

use dmp_proto::v1;
use dmp_ros2::msgs::nav2_dynamic_msgs::ObstacleArray;
use dmp_ros2::pose::Rigid;
use tracing::debug;

use crate::cells::cell::Cell;
use crate::error::ServerError;

/// The obstacles of each (cell, topic) from its last array.
#[derive(Debug, Default)]
pub(crate) struct Tracks {
    by_topic: HashMap<(String, String), HashSet<String>>,
}

/// The obstacle id of a track.
pub(crate) fn track_id(uuid: &[u8; 16]) -> String {
    format!("track-{}", hex::encode(uuid))
}

impl Tracks {
    /// Applies the array of `topic` (its frame to the cell's `frame`) to `cell`. A refused array changes nothing.
    pub(crate) fn apply(
        &mut self,
        cell: &Cell,
        topic: &str,
        msg: &ObstacleArray,
        frame: Rigid,
        now_unix_s: f64,
    ) -> Result<(), ServerError> {
        let mut puts = Vec::with_capacity(msg.obstacles.len());
        for (i, o) in msg.obstacles.iter().enumerate() {
            let field = |f: &str| format!("obstacles[{i}].{f}");
            let size = [o.size.x, o.size.y, o.size.z];
            if let Some(k) = size.iter().position(|s| !(s.is_finite() && *s > 0.0)) {
                return Err(ServerError::invalid(
                    field(["size.x", "size.y", "size.z"][k]),
                    "must be finite and > 0",
                ));
            }
            let p = frame.apply([o.position.x, o.position.y, o.position.z]);
            let v = frame.rotate([o.velocity.x, o.velocity.y, o.velocity.z]);
            if !p.iter().chain(&v).all(|x| x.is_finite()) {
                return Err(ServerError::invalid(field("position"), "position and velocity must be finite"));
            }
            puts.push(v1::Obstacle {
                id: track_id(&o.uuid.uuid),
                shape: Some(v1::obstacle::Shape::Solid(v1::SolidPrimitive {
                    r#type: v1::solid_primitive::Type::Box as i32,
                    dimensions: size.to_vec(),
                })),
                center: p.to_vec(),
                rotation: frame.matrix_row_major(),
                velocity: v.to_vec(),
                ..Default::default()
            });
        }
        let seen: HashSet<String> = puts.iter().map(|o| o.id.clone()).collect();
        let key = (cell.name().to_owned(), topic.to_owned());
        for gone in self.by_topic.get(&key).into_iter().flatten().filter(|id| !seen.contains(*id)) {
            cell.delete(gone, now_unix_s);
            debug!(cell = cell.name(), obstacle = %gone, "track gone");
        }
        self.by_topic.insert(key, seen);
        for o in puts {
            cell.put(o, now_unix_s)?;
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use dmp_ros2::msgs::geometry_msgs::{Point, Vector3};
    use dmp_ros2::msgs::nav2_dynamic_msgs::{Obstacle, Uuid};

    fn track(n: u8, x: f64) -> Obstacle {
        Obstacle {
            uuid: Uuid { uuid: [n; 16] },
            position: Point { x, y: 0.0, z: 0.0 },
            velocity: Vector3 { x: 0.5, y: 0.0, z: 0.0 },
            size: Vector3 { x: 0.4, y: 0.4, z: 1.0 },
            ..Default::default()
        }
    }

    #[test]
    fn an_array_is_the_whole_set_of_its_topic() {
        let cell = Cell::new("c", 100);
        let mut t = Tracks::default();
        let half_turn = Rigid::new([1.0, 0.0, 0.0], [0.0, 0.0, 1.0, 0.0], "f").unwrap();
        let a = ObstacleArray { obstacles: vec![track(1, 1.0), track(2, 2.0)], ..Default::default() };
        t.apply(&cell, "/tracking", &a, half_turn, 0.0).unwrap();
        let snap = cell.snapshot();
        let o = &snap.obstacles[&track_id(&[1; 16])].proto;
        assert_eq!(o.center, vec![0.0, 0.0, 0.0]);
        assert_eq!(o.velocity, vec![-0.5, 0.0, 0.0]);
        let b = ObstacleArray { obstacles: vec![track(2, 2.0)], ..Default::default() };
        t.apply(&cell, "/tracking", &b, Rigid::IDENTITY, 1.0).unwrap();
        assert_eq!(cell.snapshot().obstacles.keys().cloned().collect::<Vec<_>>(), vec![track_id(&[2; 16])]);
        let mut flat = track(3, 0.0);
        flat.size.z = 0.0;
        let c = ObstacleArray { obstacles: vec![flat], ..Default::default() };
        let e = t.apply(&cell, "/tracking", &c, Rigid::IDENTITY, 2.0).unwrap_err();
        assert!(e.to_string().starts_with("obstacles[0].size.z"), "{e}");
    }
}
