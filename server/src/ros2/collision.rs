//! MoveIt's collision objects in a cell's scene. Each shape of an object (its primitives, then its meshes) is one
//! obstacle `<id>.<k>` (`k` counting from 0; obstacle ids are Zenoh key chunks, which cannot hold `/`), its pose
//! `frame ∘ object pose ∘ shape pose`. `ADD` replaces the object, `APPEND` adds shapes to it (or adds it),
//! `MOVE` moves it to a new `pose` (its shapes keep their poses relative to it), `REMOVE` deletes it (every
//! object taken from ROS 2 in the cell, with an empty id). Planes are skipped with a warning; meshes become the
//! box around their vertices, with a warning.
//!
//! An operation applies whole or not at all: when the scene refuses one of its shapes (the cell's
//! `limits.max_obstacles`, its bytes, the workspace), the shapes it had put are taken back and those it had replaced
//! or removed are put back, so a REMOVE always finds every obstacle an object added.

use std::collections::{HashMap, HashSet};

use dmp_proto::v1;
use dmp_ros2::msgs::moveit_msgs::CollisionObject;
use dmp_ros2::pose::Rigid;
use tracing::{info, warn};

use super::shapes::{self, Placed};
use crate::cells::cell::Cell;
use crate::error::ServerError;

/// One shape of an object: its obstacle id, its shape, and its centre's pose relative to the object.
#[derive(Debug, Clone)]
struct ObjectShape {
    obstacle_id: String,
    shape: v1::obstacle::Shape,
    local: Rigid,
}

/// An object as last placed: its pose in the cell's frame and its shapes.
#[derive(Debug, Clone)]
struct Object {
    pose: Rigid,
    shapes: Vec<ObjectShape>,
}

/// The collision objects taken from ROS 2, per cell.
#[derive(Debug, Default)]
pub(crate) struct Objects {
    by_cell: HashMap<String, HashMap<String, Object>>,
}

impl Objects {
    /// Applies `msg`, whose frame is `frame` (to the cell's frame), to `cell` at `now_unix_s`. Nothing changes when
    /// the message is refused (a field breaks a rule); a put the scene refuses (a limit) stops there.
    pub(crate) fn apply(
        &mut self,
        cell: &Cell,
        msg: &CollisionObject,
        frame: Rigid,
        now_unix_s: f64,
    ) -> Result<(), ServerError> {
        let objects = self.by_cell.entry(cell.name().to_owned()).or_default();
        let pose = || -> Result<Rigid, ServerError> {
            Ok(frame.then(&Rigid::from_pose(&msg.pose, "pose").map_err(pose_err)?))
        };
        match msg.operation {
            CollisionObject::REMOVE => {
                let ids: Vec<String> =
                    if msg.id.is_empty() { objects.keys().cloned().collect() } else { vec![msg.id.clone()] };
                for id in ids {
                    if let Some(old) = objects.remove(&id) {
                        delete_shapes(cell, &old, now_unix_s);
                        info!(cell = cell.name(), object = %id, source = "ros2", "collision object removed");
                    }
                }
                Ok(())
            }
            CollisionObject::ADD | CollisionObject::APPEND => {
                check_id(&msg.id)?;
                let pose = pose()?;
                let append = msg.operation == CollisionObject::APPEND;
                let old = objects.get(&msg.id);
                let mut object = match old {
                    Some(old) if append => old.clone(),
                    _ => Object { pose, shapes: Vec::new() },
                };
                // The new shapes relative to the object's pose (when appending, the one it had).
                let to_object = object.pose.inverse().then(&pose);
                let first = object.shapes.len();
                for (k, (shape, local)) in placed_shapes(msg)?.into_iter().enumerate() {
                    object.shapes.push(ObjectShape {
                        obstacle_id: format!("{}.{}", msg.id, first + k),
                        shape: shape.shape,
                        local: to_object.then(&local),
                    });
                }
                replace(cell, &msg.id, old, &object, now_unix_s)?;
                info!(cell = cell.name(), object = %msg.id, shapes = object.shapes.len(), source = "ros2", "collision object placed");
                objects.insert(msg.id.clone(), object);
                Ok(())
            }
            CollisionObject::MOVE => {
                let pose = pose()?;
                let Some(object) = objects.get_mut(&msg.id) else {
                    return Err(ServerError::invalid(
                        "id",
                        format!("`{}`: MOVE of an object not in the scene", msg.id),
                    ));
                };
                let moved = Object { pose, shapes: object.shapes.clone() };
                replace(cell, &msg.id, Some(object), &moved, now_unix_s)?;
                *object = moved;
                Ok(())
            }
            other => Err(ServerError::invalid(
                "operation",
                format!("is {other}: must be ADD (0), REMOVE (1), APPEND (2) or MOVE (3)"),
            )),
        }
    }
}

fn pose_err(e: dmp_ros2::pose::PoseError) -> ServerError {
    ServerError::invalid(e.field, e.reason)
}

fn check_id(id: &str) -> Result<(), ServerError> {
    // `<id>.<k>` must be an obstacle id: the id's own rule, with room for the index.
    dmp_proto::keys::check_name("id", id)?;
    if id.len() + 4 > dmp_proto::keys::MAX_NAME_CHARS {
        return Err(ServerError::invalid("id", "is too long for `<id>.<k>` obstacle ids"));
    }
    Ok(())
}

/// The message's shapes with their poses relative to the object's pose: primitives, then meshes.
fn placed_shapes(msg: &CollisionObject) -> Result<Vec<(Placed, Rigid)>, ServerError> {
    let poses = |n: usize, poses: &[dmp_ros2::msgs::geometry_msgs::Pose], what: &str| {
        if poses.len() != n {
            return Err(ServerError::invalid(
                format!("{what}_poses"),
                format!("has {} poses for {n} {what}s", poses.len()),
            ));
        }
        Ok(())
    };
    poses(msg.primitives.len(), &msg.primitive_poses, "primitive")?;
    poses(msg.meshes.len(), &msg.mesh_poses, "mesh")?;
    let mut out = Vec::new();
    for (i, (p, pose)) in msg.primitives.iter().zip(&msg.primitive_poses).enumerate() {
        let placed = shapes::solid(p, &format!("primitives[{i}]"))?;
        let pose = Rigid::from_pose(pose, &format!("primitive_poses[{i}]")).map_err(pose_err)?;
        let offset = Rigid { t: placed.offset, q: Rigid::IDENTITY.q };
        out.push((placed, pose.then(&offset)));
    }
    for (i, (m, pose)) in msg.meshes.iter().zip(&msg.mesh_poses).enumerate() {
        let placed = shapes::mesh(m, &format!("meshes[{i}]"))?;
        warn!(object = %msg.id, mesh = i, "a mesh is taken as the box superquadric around its vertices");
        let pose = Rigid::from_pose(pose, &format!("mesh_poses[{i}]")).map_err(pose_err)?;
        let offset = Rigid { t: placed.offset, q: Rigid::IDENTITY.q };
        out.push((placed, pose.then(&offset)));
    }
    if !msg.planes.is_empty() {
        warn!(object = %msg.id, planes = msg.planes.len(), "planes are not obstacles here: skipped");
    }
    Ok(out)
}

/// The obstacle of one shape of an object placed at `object`.
fn obstacle(object: &Rigid, s: &ObjectShape) -> v1::Obstacle {
    let at = object.then(&s.local);
    v1::Obstacle {
        id: s.obstacle_id.clone(),
        shape: Some(s.shape.clone()),
        center: at.t.to_vec(),
        rotation: at.matrix_row_major(),
        ..Default::default()
    }
}

/// Puts the shapes of `new` (object `id`) in place of those of `old`, all or nothing: when the scene refuses one,
/// the shapes put so far go back to what they were, the old shapes removed come back, and the error says so.
fn replace(
    cell: &Cell,
    id: &str,
    old: Option<&Object>,
    new: &Object,
    now_unix_s: f64,
) -> Result<(), ServerError> {
    let kept: HashSet<&str> = new.shapes.iter().map(|s| s.obstacle_id.as_str()).collect();
    let before: HashMap<&str, &ObjectShape> =
        old.iter().flat_map(|o| &o.shapes).map(|s| (s.obstacle_id.as_str(), s)).collect();
    // Room first: the old shapes the new object does not keep.
    let dropped: Vec<&ObjectShape> =
        old.iter().flat_map(|o| &o.shapes).filter(|s| !kept.contains(s.obstacle_id.as_str())).collect();
    for s in &dropped {
        cell.delete(&s.obstacle_id, now_unix_s);
    }
    for (k, s) in new.shapes.iter().enumerate() {
        let Err(e) = cell.put(obstacle(&new.pose, s), now_unix_s) else { continue };
        let restore = |s: &ObjectShape| {
            let Some(old) = old else { return };
            if let Err(e) = cell.put(obstacle(&old.pose, s), now_unix_s) {
                warn!(cell = cell.name(), obstacle = %s.obstacle_id, reason = %e, "collision object: an obstacle it replaced could not be put back");
            }
        };
        for s in &new.shapes[..k] {
            match before.get(s.obstacle_id.as_str()) {
                Some(was) => restore(was),
                None => _ = cell.delete(&s.obstacle_id, now_unix_s),
            }
        }
        dropped.iter().for_each(|s| restore(s));
        return Err(match e {
            ServerError::ResourceExhausted(r) => ServerError::ResourceExhausted(format!(
                "collision object `{id}` ({} shapes) does not fit: shape {k}: {r}; nothing of it was applied",
                new.shapes.len()
            )),
            e => e.within(&format!("shapes[{k}]")),
        });
    }
    Ok(())
}

fn delete_shapes(cell: &Cell, object: &Object, now_unix_s: f64) {
    for s in &object.shapes {
        cell.delete(&s.obstacle_id, now_unix_s);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use dmp_ros2::msgs::geometry_msgs::{Point, Pose, Quaternion};
    use dmp_ros2::msgs::shape_msgs::SolidPrimitive;

    fn pose(x: f64, y: f64, z: f64, q: [f64; 4]) -> Pose {
        Pose { position: Point { x, y, z }, orientation: Quaternion { x: q[0], y: q[1], z: q[2], w: q[3] } }
    }

    fn boxes(id: &str, op: u8, n: usize) -> CollisionObject {
        let b = SolidPrimitive {
            r#type: SolidPrimitive::BOX,
            dimensions: vec![0.1, 0.2, 0.3],
            ..Default::default()
        };
        CollisionObject {
            id: id.into(),
            operation: op,
            pose: pose(
                1.0,
                0.0,
                0.0,
                [0.0, 0.0, std::f64::consts::FRAC_1_SQRT_2, std::f64::consts::FRAC_1_SQRT_2],
            ),
            primitives: vec![b; n],
            primitive_poses: (0..n).map(|k| pose(k as f64, 0.0, 0.0, [0.0, 0.0, 0.0, 1.0])).collect(),
            ..Default::default()
        }
    }

    fn center(cell: &Cell, id: &str) -> Vec<f64> {
        cell.snapshot().obstacles[id].proto.center.clone()
    }

    fn close(a: &[f64], b: &[f64]) -> bool {
        a.iter().zip(b).all(|(x, y)| (x - y).abs() < 1e-12)
    }

    #[test]
    fn operations_add_append_move_and_remove() {
        let cell = Cell::new("c", 100);
        let mut o = Objects::default();
        o.apply(&cell, &boxes("t", CollisionObject::ADD, 2), Rigid::IDENTITY, 0.0).unwrap();
        // The object at (1, 0, 0) turned a quarter about z: its second box, 1 m along its x, is at (1, 1, 0).
        assert!(close(&center(&cell, "t.0"), &[1.0, 0.0, 0.0]));
        assert!(close(&center(&cell, "t.1"), &[1.0, 1.0, 0.0]));
        let r = &cell.snapshot().obstacles["t.1"].proto.rotation;
        assert!(close(&r[..3], &[0.0, -1.0, 0.0]), "row-major R: {r:?}");
        o.apply(&cell, &boxes("t", CollisionObject::APPEND, 1), Rigid::IDENTITY, 1.0).unwrap();
        assert_eq!(cell.snapshot().obstacles.len(), 3);
        let mut mv = boxes("t", CollisionObject::MOVE, 0);
        mv.pose = pose(0.0, 0.0, 2.0, [0.0, 0.0, 0.0, 1.0]);
        o.apply(&cell, &mv, Rigid::IDENTITY, 2.0).unwrap();
        assert!(close(&center(&cell, "t.1"), &[1.0, 0.0, 2.0]), "moved, unturned");
        assert!(close(&center(&cell, "t.2"), &[0.0, 0.0, 2.0]), "the appended box moves along");
        // ADD replaces: one box left.
        o.apply(&cell, &boxes("t", CollisionObject::ADD, 1), Rigid::IDENTITY, 3.0).unwrap();
        assert_eq!(cell.snapshot().obstacles.len(), 1);
        o.apply(&cell, &boxes("u", CollisionObject::ADD, 1), Rigid::IDENTITY, 3.0).unwrap();
        o.apply(&cell, &boxes("", CollisionObject::REMOVE, 0), Rigid::IDENTITY, 4.0).unwrap();
        assert!(cell.snapshot().obstacles.is_empty());
    }

    #[test]
    fn refused_messages_change_nothing() {
        let cell = Cell::new("c", 100);
        let mut o = Objects::default();
        let mut bad = boxes("t", CollisionObject::ADD, 2);
        bad.primitive_poses.pop();
        assert!(
            o.apply(&cell, &bad, Rigid::IDENTITY, 0.0)
                .unwrap_err()
                .to_string()
                .starts_with("primitive_poses")
        );
        let mut bad = boxes("t", CollisionObject::ADD, 1);
        bad.primitives[0].dimensions.clear();
        assert!(o.apply(&cell, &bad, Rigid::IDENTITY, 0.0).is_err());
        assert!(o.apply(&cell, &boxes("t", CollisionObject::MOVE, 0), Rigid::IDENTITY, 0.0).is_err());
        assert!(o.apply(&cell, &boxes("a b", CollisionObject::ADD, 1), Rigid::IDENTITY, 0.0).is_err());
        assert!(o.apply(&cell, &boxes("t", 7, 1), Rigid::IDENTITY, 0.0).is_err());
        assert!(cell.snapshot().obstacles.is_empty());
    }

    #[test]
    fn an_object_applies_whole_or_not_at_all_and_remove_takes_all_it_added() {
        let cell = Cell::new("c", 100);
        let mut o = Objects::default();
        let e =
            o.apply(&cell, &boxes("big", CollisionObject::ADD, 10_000), Rigid::IDENTITY, 0.0).unwrap_err();
        assert!(matches!(e, ServerError::ResourceExhausted(_)), "{e}");
        assert!(e.to_string().contains("`big` (10000 shapes) does not fit"), "{e}");
        assert!(cell.snapshot().obstacles.is_empty(), "nothing added");
        // A replacement that does not fit leaves the object as it was; so does an append.
        o.apply(&cell, &boxes("t", CollisionObject::ADD, 3), Rigid::IDENTITY, 1.0).unwrap();
        let before = center(&cell, "t.2");
        assert!(o.apply(&cell, &boxes("t", CollisionObject::ADD, 500), Rigid::IDENTITY, 2.0).is_err());
        assert!(o.apply(&cell, &boxes("t", CollisionObject::APPEND, 98), Rigid::IDENTITY, 2.0).is_err());
        assert_eq!(cell.snapshot().obstacles.len(), 3);
        assert!(close(&center(&cell, "t.2"), &before));
        // A move out of the workspace moves nothing.
        let mut mv = boxes("t", CollisionObject::MOVE, 0);
        mv.pose = pose(0.0, 0.0, 1e6, [0.0, 0.0, 0.0, 1.0]);
        assert!(o.apply(&cell, &mv, Rigid::IDENTITY, 3.0).is_err());
        assert!(close(&center(&cell, "t.2"), &before));
        // A smaller replacement drops the shapes it no longer has.
        o.apply(&cell, &boxes("t", CollisionObject::ADD, 1), Rigid::IDENTITY, 4.0).unwrap();
        assert_eq!(cell.snapshot().obstacles.len(), 1);
        o.apply(&cell, &boxes("", CollisionObject::REMOVE, 0), Rigid::IDENTITY, 5.0).unwrap();
        assert!(cell.snapshot().obstacles.is_empty(), "no orphans");
        // The whole budget is there again.
        o.apply(&cell, &boxes("u", CollisionObject::ADD, 100), Rigid::IDENTITY, 6.0).unwrap();
        assert_eq!(cell.snapshot().obstacles.len(), 100);
    }
}
