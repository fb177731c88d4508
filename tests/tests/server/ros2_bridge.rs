//! End to end: a stock eclipse-zenoh session publishes rosbags-encoded collision objects on rmw_zenoh's key
//! (`tests/python/ros2_publish.py`), as a ROS 2 node on rmw_zenoh would; the server, with `ros2.domain`, puts the
//! box in the scene at its pose within 1 s, a REMOVE empties the scene, and an unknown frame is refused and
//! counted. Out: the cell's markers (the box's true shape and isopotential) arrive on rmw_zenoh's key with its
//! attachment, are deleted when the box goes, and the node's and the publisher's liveliness tokens are there.

use std::future::IntoFuture;
use std::io::{BufRead, BufReader, Write};
use std::process::{Child, ChildStdin, Command, Stdio};
use std::sync::mpsc;
use std::time::{Duration, Instant};

use dmp_proto::zenoh_session::{SessionOptions, session_config};
use dmp_ros2::attachment::Attachment;
use dmp_ros2::keys::{MARKER_ARRAY, topic_key};
use dmp_ros2::msgs::visualization_msgs::{Marker, MarkerArray};
use dmp_server::ros2::Ros2Counters;
use dmp_server::server::{ServerHandle, start};
use dmp_tests::{config, within};

use super::python_clients::{python, workspace};

struct Publisher {
    child: Child,
    stdin: ChildStdin,
    lines: mpsc::Receiver<String>,
}

impl Publisher {
    fn start(locator: &str, domain: u32) -> Self {
        let mut child = Command::new(python())
            .arg(workspace().join("tests/python/ros2_publish.py"))
            .arg(locator)
            .arg(workspace().join("ros2/msg"))
            .arg(domain.to_string())
            .stdin(Stdio::piped())
            .stdout(Stdio::piped())
            .stderr(Stdio::inherit())
            .spawn()
            .expect("python starts");
        let stdin = child.stdin.take().unwrap();
        let stdout = child.stdout.take().unwrap();
        let (tx, lines) = mpsc::channel();
        std::thread::spawn(move || {
            for l in BufReader::new(stdout).lines().map_while(Result::ok) {
                eprintln!("python: {l}");
                if tx.send(l).is_err() {
                    break;
                }
            }
        });
        let mut p = Self { child, stdin, lines };
        p.expect("ok: matched", Duration::from_secs(60));
        p
    }

    fn expect(&mut self, want: &str, within: Duration) {
        let line = self.lines.recv_timeout(within).unwrap_or_else(|e| panic!("waiting for `{want}`: {e}"));
        assert_eq!(line, want);
    }

    fn send(&mut self, cmd: &str) -> Instant {
        writeln!(self.stdin, "{cmd}").unwrap();
        self.stdin.flush().unwrap();
        let sent = Instant::now();
        self.expect(&format!("ok: {cmd}"), Duration::from_secs(10));
        sent
    }
}

/// Polls until `cond` holds, at most 1 s after `since`.
async fn within_1s(what: &str, since: Instant, cond: impl Fn() -> bool) {
    while !cond() {
        assert!(since.elapsed() < Duration::from_secs(1), "not within 1 s: {what}");
        tokio::time::sleep(Duration::from_millis(5)).await;
    }
}

fn counters(h: &ServerHandle) -> &Ros2Counters {
    h.ros2_counters().expect("the ROS 2 bridge runs")
}

#[tokio::test(flavor = "multi_thread")]
async fn a_ros2_collision_object_enters_and_leaves_the_scene() {
    let data = tempfile::tempdir().unwrap();
    let mut c = config(data.path());
    c.ros2.domain = Some(7);
    let h = within("server start", start(c)).await.expect("server starts");
    let locator = h.zenoh_locators.iter().find(|l| l.starts_with("tcp/")).unwrap().clone();
    let cell = h.cells().get("").unwrap();
    // A ROS 2 tool's view: a Zenoh peer on the server, subscribed to the default cell's markers.
    let tool = session_config(&SessionOptions::loopback_peer(h.zenoh_locators.clone())).unwrap();
    let tool = within("tool open", zenoh::open(tool).into_future()).await.unwrap();
    let markers_key = topic_key(7, "/dmp/default/markers", &MARKER_ARRAY);
    let markers = within("subscribe", tool.declare_subscriber(&markers_key).into_future()).await.unwrap();
    let mut p = tokio::task::spawn_blocking(move || Publisher::start(&locator, 7)).await.unwrap();

    let sent = p.send("add");
    within_1s("the box in the scene", sent, || cell.snapshot().obstacles.contains_key("crate.0")).await;
    let snap = cell.snapshot();
    let o = &snap.obstacles["crate.0"].proto;
    // The object at (0.5, 0.25, 0.1) turned a quarter about z: the box 0.2 m along the object's x is at
    // (0.5, 0.45, 0.1), its x axis along the cell's y.
    let want = [0.5, 0.45, 0.1];
    assert!(o.center.iter().zip(want).all(|(a, b)| (a - b).abs() < 1e-9), "center {:?}", o.center);
    let r = &o.rotation;
    assert!((r[3] - 1.0).abs() < 1e-9 && r[0].abs() < 1e-9, "rotation {r:?}");
    assert_eq!(snap.obstacles.len(), 1);

    // The markers of the scene with the box, with rmw_zenoh's attachment.
    let (array, attachment) = loop {
        let sample = within("markers", markers.recv_async()).await.unwrap();
        let array: MarkerArray = dmp_ros2::decode(&sample.payload().to_bytes()).unwrap();
        let attachment = Attachment::decode(&sample.attachment().expect("an attachment").to_bytes()).unwrap();
        if array.markers.iter().any(|m| m.text == "crate.0") {
            break (array, attachment);
        }
    };
    let cube =
        array.markers.iter().find(|m| m.ns == "obstacles" && m.text == "crate.0").expect("its true shape");
    let iso = array
        .markers
        .iter()
        .find(|m| m.ns == "isopotentials" && m.text == "crate.0")
        .expect("its isopotential");
    assert_eq!((iso.r#type, iso.pose.position.y), (Marker::TRIANGLE_LIST, cube.pose.position.y));
    assert_eq!((cube.r#type, cube.header.frame_id.as_str()), (Marker::CUBE, "world"));
    assert!((cube.pose.position.y - 0.45).abs() < 1e-9 && (cube.scale.x - 0.2).abs() < 1e-12, "{cube:?}");
    assert!(attachment.sequence_number >= 1);
    // The node's and the publisher's liveliness tokens, the publisher's GID in the attachment.
    let replies = within("tokens", tool.liveliness().get("@ros2_lv/7/**").into_future()).await.unwrap();
    let mut tokens = Vec::new();
    while let Ok(reply) = within("token", replies.recv_async()).await {
        if let Ok(sample) = reply.into_result() {
            tokens.push(sample.key_expr().to_string());
        }
    }
    assert!(tokens.iter().any(|t| t.ends_with("/0/0/NN/%/%/dmp_server")), "{tokens:?}");
    let publisher =
        tokens.iter().find(|t| t.contains("/MP/") && t.contains("%dmp%default%markers")).expect("a token");
    assert_eq!(attachment.source_gid, dmp_ros2::liveliness::gid(publisher));

    let sent = p.send("remove");
    within_1s("the scene empty", sent, || cell.snapshot().obstacles.is_empty()).await;
    // Its markers are deleted, by namespace and id.
    let ids: Vec<(String, i32)> = [cube, iso].iter().map(|m| (m.ns.clone(), m.id)).collect();
    let mut deleted = Vec::new();
    while deleted.len() < 2 {
        let sample = within("markers", markers.recv_async()).await.unwrap();
        let array: MarkerArray = dmp_ros2::decode(&sample.payload().to_bytes()).unwrap();
        deleted
            .extend(array.markers.into_iter().filter(|m| m.action == Marker::DELETE).map(|m| (m.ns, m.id)));
    }
    deleted.sort();
    let mut want = ids.clone();
    want.sort();
    assert_eq!(deleted, want);

    let before = h.malformed_payloads();
    let sent = p.send("wrong-frame");
    within_1s("the wrong frame counted", sent, || Ros2Counters::get(&counters(&h).refused_frames) == 1).await;
    assert_eq!(h.malformed_payloads(), before + 1, "counted with the malformed Zenoh payloads too");
    assert!(cell.snapshot().obstacles.is_empty(), "a refused frame changed the scene");
    assert_eq!(Ros2Counters::get(&counters(&h).applied), 2);

    drop(p.stdin);
    let status = tokio::task::spawn_blocking(move || p.child.wait()).await.unwrap().unwrap();
    assert!(status.success(), "python exited with {status}");
    within("tool close", tool.close().into_future()).await.unwrap();
    within("shutdown", h.shutdown()).await.unwrap();
}
