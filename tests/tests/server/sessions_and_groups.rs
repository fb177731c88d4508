//! Changing a session's goal mid-run, and robots on a shared phase (a group).

use dmp::Isopotential;
use dmp_proto::v1;
use tokio_stream::StreamExt;

use crate::default_limits::exact;
use crate::{dynamic_volumetric, line, rows, serve, spec};
use dmp_tests::within;

#[tokio::test(flavor = "multi_thread")]
async fn a_goal_change_mid_session_converges_with_continuous_motion() {
    let dir = tempfile::tempdir().unwrap();
    let (handle, client) = serve(dir.path()).await;
    within("put", client.put_primitive("psm1", "reach", &line(vec![0.0; 3], vec![0.1, 0.0, 0.0], 1.0)))
        .await
        .unwrap();
    let mut motion = spec("psm1", "reach");
    motion.ignore_scene = true;
    // Slow at first (tau 20 s): as fast as read, the server computes ahead as far as the buffers and HTTP/2's
    // window let it, and the run must not reach its first goal before the change arrives.
    motion.tau = 20.0;
    let start = v1::ExecuteRequest { motion: Some(motion), max_duration_s: 30.0, ..Default::default() };
    let mut session = within("session", client.session(start)).await.unwrap();
    let mut segments = Vec::new();
    for _ in 0..20 {
        segments.push(within("segment", session.next_segment()).await.unwrap().unwrap());
    }
    let new_goal = vec![0.05, 0.08, -0.02];
    within("set goal", session.set_goal(new_goal.clone())).await.unwrap();
    within("set tau", session.set_tau(1.0)).await.unwrap();
    while let Some(s) = within("segment", session.next_segment()).await {
        segments.push(s.unwrap());
    }
    let last = segments.last().unwrap();
    assert_eq!(last.status, v1::SegmentStatus::GoalReached as i32);
    let end = rows(last, &last.positions).pop().unwrap();
    let err: f64 = end.iter().zip(&new_goal).map(|(a, b)| (a - b).powi(2)).sum::<f64>().sqrt();
    assert!(err < 2e-3, "ended {err} from the new goal");
    // Continuity across every boundary: the next segment starts one step after the last point, with position and
    // velocity changing by what one step allows.
    let mut max_acc: f64 = 0.0;
    for s in &segments {
        for a in rows(s, &s.accelerations) {
            max_acc = max_acc.max(a.iter().map(|v| v * v).sum::<f64>().sqrt());
        }
    }
    for w in segments.windows(2) {
        let (a, b) = (&w[0], &w[1]);
        let (xa, va) = (rows(a, &a.positions).pop().unwrap(), rows(a, &a.velocities).pop().unwrap());
        let (xb, vb) = (rows(b, &b.positions)[0].clone(), rows(b, &b.velocities)[0].clone());
        assert!((b.start_time - (a.start_time + a.dt * (a.positions.len() / 3) as f64)).abs() < 1e-9);
        for i in 0..3 {
            assert!(
                (xb[i] - xa[i] - va[i] * a.dt).abs() <= max_acc * a.dt * a.dt,
                "position jump at {}",
                b.start_time
            );
            assert!((vb[i] - va[i]).abs() <= max_acc * a.dt * 1.01, "velocity jump at {}", b.start_time);
        }
    }
    within("shutdown", handle.shutdown()).await.unwrap();
}

#[tokio::test(flavor = "multi_thread")]
async fn three_robots_on_a_shared_phase_do_not_collide() {
    let dir = tempfile::tempdir().unwrap();
    let (handle, client) = serve(dir.path()).await;
    let starts = [[0.0, 0.0], [2.0, 0.0], [1.0, 1.8]];
    let goals = [[2.0, 1.6], [0.0, 1.6], [1.0, -0.2]];
    let footprint = v1::Superquadric { semi_axes: vec![0.58, 0.38], exponents: vec![] };
    let mut members = Vec::new();
    for (i, (s, g)) in starts.iter().zip(&goals).enumerate() {
        let id = format!("youbot{}", i + 1);
        within("put", client.put_primitive(&id, "cross", &line(s.to_vec(), g.to_vec(), 10.0))).await.unwrap();
        // The paper's youBot test: its avoidance, without limits holding the robots back.
        let mut motion = exact(spec(&id, "cross"));
        motion.footprint = Some(footprint.clone());
        motion.ignore_scene = true;
        motion.robot_avoidance = Some(dynamic_volumetric(60.0, 2.0, 0.2));
        members.push(v1::GroupMember { motion: Some(motion) });
    }
    let request = v1::ExecuteGroupRequest { members, max_duration_s: 30.0, ..Default::default() };
    let mut stream = within("group", client.execute_group(request)).await.unwrap();
    let mut paths: Vec<Vec<Vec<f64>>> = vec![Vec::new(); 3];
    let mut last = None;
    while let Some(g) = within("group segment", stream.next()).await {
        let g = g.unwrap();
        assert_eq!(g.segments.len(), 3);
        for (k, s) in g.segments.iter().enumerate() {
            paths[k].extend(rows(s, &s.positions));
        }
        last = Some(g);
    }
    let last = last.unwrap();
    assert!(
        last.segments.iter().all(|s| s.status == v1::SegmentStatus::GoalReached as i32),
        "{:?}",
        last.segments[0].status
    );
    let fp = dmp::Superquadric::ellipsoid(vec![0.58, 0.38]).unwrap();
    for a in 0..3 {
        for b in 0..3 {
            if a == b {
                continue;
            }
            for (pa, pb) in paths[a].iter().zip(&paths[b]) {
                assert!(
                    fp.value(&[pa[0] - pb[0], pa[1] - pb[1]]) > 0.0,
                    "robot {a} inside robot {b}'s footprint"
                );
            }
        }
        let end = paths[a].last().unwrap();
        assert!((end[0] - goals[a][0]).hypot(end[1] - goals[a][1]) < 1e-2, "robot {a} ended at {end:?}");
    }
    within("shutdown", handle.shutdown()).await.unwrap();
}
