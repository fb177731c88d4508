//! The cells' obstacles for RViz: each cell's scene, whenever its version changes, as a
//! `visualization_msgs/msg/MarkerArray` on `/dmp/<cell>/markers` (`-` and `.` of the cell's name as `_`, which ROS
//! topic names need), in the cell's frame. The first marker deletes every earlier one; then one marker per obstacle
//! (namespace `obstacles`, its id as the marker's text): a box, sphere or cylinder as itself, a superquadric or a
//! nested one as the ellipsoid of its semi-axes. Each sample carries rmw_zenoh's attachment, and the server
//! declares rmw_zenoh's liveliness tokens for its node (`dmp_server`) and each publisher, so that ROS 2's graph
//! tools list them.

use std::collections::HashMap;
use std::time::Duration;

use dmp_proto::v1;
use dmp_ros2::attachment::Attachment;
use dmp_ros2::keys::{MARKER_ARRAY, topic_key};
use dmp_ros2::liveliness::{Node, gid};
use dmp_ros2::msgs::builtin_interfaces::Time;
use dmp_ros2::msgs::geometry_msgs::Vector3;
use dmp_ros2::msgs::std_msgs::{ColorRGBA, Header};
use dmp_ros2::msgs::visualization_msgs::{Marker, MarkerArray};
use dmp_ros2::pose::Rigid;
use tokio::task::JoinHandle;
use tokio_util::sync::CancellationToken;
use tracing::{debug, warn};
use zenoh::Session;
use zenoh::liveliness::LivelinessToken;
use zenoh::pubsub::Publisher;

use crate::cells::Cells;
use crate::clock::Clock;

/// How often the cells' versions are looked at.
pub const PERIOD: Duration = Duration::from_millis(100);

/// The topic of a cell's markers.
pub fn markers_topic(cell: &str) -> String {
    format!("/dmp/{}/markers", cell.replace(['-', '.'], "_"))
}

/// One cell's publisher, its token and its count.
struct CellPublisher {
    publisher: Publisher<'static>,
    _token: LivelinessToken,
    gid: [u8; 16],
    sequence: i64,
    version: Option<u64>,
}

/// Spawns the task that publishes the cells' markers until `stop`.
pub fn spawn(
    session: Session,
    domain: u32,
    frame: String,
    cells: Cells,
    clock: Clock,
    stop: CancellationToken,
) -> JoinHandle<()> {
    tokio::spawn(async move {
        let node = Node {
            domain,
            zid: session.zid().to_string(),
            node_id: 0,
            namespace: "/".into(),
            name: "dmp_server".into(),
        };
        let _node_token = match session.liveliness().declare_token(node.token()).await {
            Ok(t) => Some(t),
            Err(e) => {
                warn!(error = %e, "ros2: cannot declare the node's liveliness token");
                None
            }
        };
        let mut publishers: HashMap<String, CellPublisher> = HashMap::new();
        let mut tick = tokio::time::interval(PERIOD);
        tick.set_missed_tick_behavior(tokio::time::MissedTickBehavior::Delay);
        loop {
            tokio::select! {
                _ = stop.cancelled() => break,
                _ = tick.tick() => {}
            }
            for cell in cells.all() {
                let snap = cell.snapshot();
                let name = cell.name().to_owned();
                if !publishers.contains_key(&name) {
                    let topic = markers_topic(&name);
                    let entity = publishers.len() as u32 + 1;
                    let token_key = node.publisher_token(entity, &topic, &MARKER_ARRAY);
                    let declared = async {
                        let publisher =
                            session.declare_publisher(topic_key(domain, &topic, &MARKER_ARRAY)).await?;
                        let token = session.liveliness().declare_token(token_key.clone()).await?;
                        Ok::<_, zenoh::Error>((publisher, token))
                    };
                    match declared.await {
                        Ok((publisher, token)) => {
                            let p = CellPublisher {
                                publisher,
                                _token: token,
                                gid: gid(&token_key),
                                sequence: 0,
                                version: None,
                            };
                            publishers.insert(name.clone(), p);
                        }
                        Err(e) => {
                            warn!(cell = %name, error = %e, "ros2: cannot declare the markers' publisher");
                            continue;
                        }
                    }
                }
                let Some(p) = publishers.get_mut(&name) else { continue };
                if p.version == Some(snap.version) {
                    continue;
                }
                let now = clock.now_unix_s();
                let obstacles: Vec<&v1::Obstacle> = snap.obstacles.values().map(|o| &o.proto).collect();
                let msg = marker_array(&frame, now, &obstacles);
                let bytes = match dmp_ros2::encode(&msg) {
                    Ok(b) => b,
                    Err(e) => {
                        warn!(cell = %name, error = %e, "ros2: markers not encoded");
                        continue;
                    }
                };
                p.sequence += 1;
                let attachment = Attachment {
                    sequence_number: p.sequence,
                    source_timestamp: (now * 1e9) as i64,
                    source_gid: p.gid,
                };
                if let Err(e) = p.publisher.put(bytes).attachment(attachment.encode()).await {
                    warn!(cell = %name, error = %e, "ros2: markers not published");
                    continue;
                }
                p.version = Some(snap.version);
                debug!(cell = %name, version = snap.version, markers = msg.markers.len(), "ros2 markers published");
            }
        }
    })
}

/// The markers of `obstacles`: a DELETEALL, then one marker each (3-D and 2-D obstacles; others are skipped).
pub fn marker_array(frame: &str, now_unix_s: f64, obstacles: &[&v1::Obstacle]) -> MarkerArray {
    let header = Header { stamp: Time::from_unix_s(now_unix_s), frame_id: frame.to_owned() };
    let mut markers = vec![Marker {
        header: header.clone(),
        ns: "obstacles".into(),
        action: Marker::DELETEALL,
        ..Default::default()
    }];
    let mut sorted = obstacles.to_vec();
    sorted.sort_by(|a, b| a.id.cmp(&b.id));
    for (k, o) in sorted.into_iter().enumerate() {
        let Some((r#type, scale)) = shape_marker(o) else { continue };
        let Some(pose) = pose_of(o) else { continue };
        markers.push(Marker {
            header: header.clone(),
            ns: "obstacles".into(),
            id: k as i32,
            r#type,
            action: Marker::ADD,
            pose: pose.to_pose(),
            scale,
            color: ColorRGBA { r: 0.8, g: 0.2, b: 0.2, a: 0.6 },
            text: o.id.clone(),
            ..Default::default()
        });
    }
    MarkerArray { markers }
}

fn pose_of(o: &v1::Obstacle) -> Option<Rigid> {
    let d = o.center.len();
    if !(d == 2 || d == 3) {
        return None;
    }
    let t = [o.center[0], o.center[1], o.center.get(2).copied().unwrap_or(0.0)];
    let mut m = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];
    if o.rotation.len() == d * d {
        for i in 0..d {
            for j in 0..d {
                m[i][j] = o.rotation[i * d + j];
            }
        }
    }
    Some(Rigid::from_matrix(t, m))
}

fn shape_marker(o: &v1::Obstacle) -> Option<(i32, Vector3)> {
    use v1::obstacle::Shape;
    let v = |x: f64, y: f64, z: f64| Vector3 { x, y, z };
    let axes = |a: &[f64]| match a {
        [x, y] => Some(v(2.0 * x, 2.0 * y, 0.01)),
        [x, y, z] => Some(v(2.0 * x, 2.0 * y, 2.0 * z)),
        _ => None,
    };
    match o.shape.as_ref()? {
        Shape::Solid(s) => {
            match (v1::solid_primitive::Type::try_from(s.r#type).ok()?, s.dimensions.as_slice()) {
                (v1::solid_primitive::Type::Box, [x, y, z]) => Some((Marker::CUBE, v(*x, *y, *z))),
                (v1::solid_primitive::Type::Sphere, [r]) => {
                    Some((Marker::SPHERE, v(2.0 * r, 2.0 * r, 2.0 * r)))
                }
                (v1::solid_primitive::Type::Cylinder, [h, r]) => {
                    Some((Marker::CYLINDER, v(2.0 * r, 2.0 * r, *h)))
                }
                _ => None,
            }
        }
        Shape::Superquadric(s) => Some((Marker::SPHERE, axes(&s.semi_axes)?)),
        Shape::Nested(n) => Some((Marker::SPHERE, axes(&n.semi_axes)?)),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn obstacles_become_markers_after_a_deleteall() {
        let b = v1::Obstacle {
            id: "b".into(),
            shape: Some(v1::obstacle::Shape::Solid(v1::SolidPrimitive {
                r#type: 1,
                dimensions: vec![0.2, 0.1, 0.3],
            })),
            center: vec![1.0, 2.0, 3.0],
            rotation: vec![0.0, -1.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0],
            ..Default::default()
        };
        let e = v1::Obstacle {
            id: "a".into(),
            shape: Some(v1::obstacle::Shape::Superquadric(v1::Superquadric {
                semi_axes: vec![0.1, 0.2],
                exponents: vec![],
            })),
            center: vec![0.5, 0.5],
            ..Default::default()
        };
        let m = marker_array("world", 10.5, &[&b, &e]);
        assert_eq!(m.markers.len(), 3);
        assert_eq!(m.markers[0].action, Marker::DELETEALL);
        assert_eq!((m.markers[1].text.as_str(), m.markers[1].r#type), ("a", Marker::SPHERE));
        assert_eq!(m.markers[1].scale, Vector3 { x: 0.2, y: 0.4, z: 0.01 });
        let cube = &m.markers[2];
        assert_eq!((cube.r#type, cube.scale.x, cube.pose.position.z), (Marker::CUBE, 0.2, 3.0));
        let q = &cube.pose.orientation;
        let h = std::f64::consts::FRAC_1_SQRT_2;
        assert!((q.z - h).abs() < 1e-12 && (q.w - h).abs() < 1e-12, "a quarter turn about z: {q:?}");
        assert_eq!(cube.header.stamp.sec, 10);
        assert_eq!(markers_topic("cell-a.1"), "/dmp/cell_a_1/markers");
    }
}
