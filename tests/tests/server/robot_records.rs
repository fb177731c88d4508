//! Robot records (`RobotService`): stored durably and kept across a restart; a run of the robot keeps the record's
//! limits (measured as finite differences of the setpoints it keeps), `MotionSpec.limits` overrides them field by
//! field; bad records are refused naming the field; who may put a robot's record is who may write its primitives.

use dmp::Limits;
use dmp_proto::limits::limits_to_proto;
use dmp_proto::v1;
use tonic::Code;

use crate::access::{as_identity, secured};
use crate::default_limits::exact;
use crate::motion_limits::{executed, kept, peaks};
use crate::{line, serve, spec};
use dmp_tests::within;

fn bar_tool() -> v1::Tool {
    v1::Tool {
        shape: Some(v1::Superquadric { semi_axes: vec![0.3, 0.02, 0.02], exponents: vec![] }),
        offset: vec![0.0, 0.0, 0.1],
        axis: true,
        control_points: 16,
    }
}

fn panda_record(id: &str) -> v1::RobotRecord {
    v1::RobotRecord {
        robot_id: id.into(),
        limits: Some(limits_to_proto(&Limits::PANDA)),
        footprint: Some(v1::Superquadric { semi_axes: vec![0.2, 0.2, 0.5], exponents: vec![] }),
        tool: Some(bar_tool()),
        updated_unix_ms: 0,
        margin: 0.0,
    }
}

#[tokio::test(flavor = "multi_thread")]
async fn a_robot_record_survives_a_restart_and_bad_ones_are_refused_naming_the_field() {
    let dir = tempfile::tempdir().unwrap();
    let (handle, client) = serve(dir.path()).await;
    let none = within("get", client.get_robot("panda")).await.unwrap_err();
    assert_eq!(none.code(), Some(Code::NotFound), "{none}");
    let stored = within("put", client.put_robot(panda_record("panda"))).await.unwrap();
    assert!(stored.updated_unix_ms > 0, "the server stamps the record");
    assert_eq!(v1::RobotRecord { updated_unix_ms: 0, ..stored.clone() }, panda_record("panda"));
    // A put replaces the record.
    let psm = v1::RobotRecord { limits: Some(limits_to_proto(&Limits::DVRK_PSM)), ..panda_record("psm") };
    within("put psm", client.put_robot(psm.clone())).await.unwrap();
    let replaced = v1::RobotRecord { tool: None, ..psm.clone() };
    let replaced = within("put psm again", client.put_robot(replaced)).await.unwrap();
    within("shutdown", handle.shutdown()).await.unwrap();

    let (handle, client) = serve(dir.path()).await;
    assert_eq!(within("get after restart", client.get_robot("panda")).await.unwrap(), stored);
    assert_eq!(within("get psm after restart", client.get_robot("psm")).await.unwrap(), replaced);

    let bad: [(&str, v1::RobotRecord); 7] = [
        ("robot.robot_id", v1::RobotRecord { robot_id: "r".repeat(129), ..panda_record("x") }),
        ("robot.robot_id", v1::RobotRecord { robot_id: "a b".into(), ..panda_record("x") }),
        (
            "robot.limits.max_jerk",
            v1::RobotRecord {
                limits: Some(v1::Limits { max_jerk: f64::NAN, ..limits_to_proto(&Limits::PANDA) }),
                ..panda_record("x")
            },
        ),
        ("robot.margin", v1::RobotRecord { margin: f64::INFINITY, ..panda_record("x") }),
        (
            "robot.footprint.semi_axes",
            v1::RobotRecord {
                footprint: Some(v1::Superquadric { semi_axes: vec![0.2, 0.0, 0.5], exponents: vec![] }),
                ..panda_record("x")
            },
        ),
        (
            "robot.tool.control_points",
            v1::RobotRecord {
                tool: Some(v1::Tool { control_points: 257, ..bar_tool() }),
                ..panda_record("x")
            },
        ),
        (
            "robot.tool.offset",
            v1::RobotRecord {
                tool: Some(v1::Tool { offset: vec![0.0; 2], ..bar_tool() }),
                ..panda_record("x")
            },
        ),
    ];
    for (field, record) in bad {
        let e = within("bad put", client.put_robot(record)).await.unwrap_err();
        assert_eq!(e.code(), Some(Code::InvalidArgument), "{field}: {e}");
        assert!(e.to_string().contains(field), "{field}: {e}");
    }
    // A refused put leaves the record as it was; a delete removes it.
    assert_eq!(within("get", client.get_robot("panda")).await.unwrap(), stored);
    within("delete", client.delete_robot("panda")).await.unwrap();
    let gone = within("get deleted", client.get_robot("panda")).await.unwrap_err();
    assert_eq!(gone.code(), Some(Code::NotFound), "{gone}");
    within("shutdown", handle.shutdown()).await.unwrap();
}

#[tokio::test(flavor = "multi_thread")]
async fn a_run_keeps_the_records_limits_and_the_request_overrides_them_field_by_field() {
    let dir = tempfile::tempdir().unwrap();
    let (handle, client) = serve(dir.path()).await;
    // 1 m in 0.5 s: about 2 m/s on average, far beyond the record.
    within("put", client.put_primitive("base", "dash", &line(vec![0.0; 2], vec![1.0, 0.0], 0.5)))
        .await
        .unwrap();
    let mut motion = spec("base", "dash");
    motion.ignore_scene = true;
    let free = peaks(&kept(&executed(&client, exact(motion.clone())).await), 1e-3);
    assert!(free[0] > 1.5, "without limits the dash is fast: {free:?}");
    // Without a record: the server's default profile (1 m/s, 5 m/s^2, 50 m/s^3).
    let p = peaks(&kept(&executed(&client, motion.clone()).await), 1e-3);
    assert!(p[0] <= 1.0 && p[1] <= 5.0 && p[2] <= 50.0, "default profile {p:?}");

    let slow = Limits { max_speed: 0.5, max_acceleration: 1.0, max_jerk: 10.0, ..Limits::NONE };
    within("put robot", client.put_robot_limits("base", &slow)).await.unwrap();
    let segments = executed(&client, motion.clone()).await;
    assert_eq!(segments.last().unwrap().status, v1::SegmentStatus::GoalReached as i32);
    let p = peaks(&kept(&segments), segments[0].dt);
    assert!(p[0] <= slow.max_speed && p[1] <= slow.max_acceleration && p[2] <= slow.max_jerk, "{p:?}");
    assert!(p[0] > 0.9 * slow.max_speed, "the run uses the speed it is given: {p:?}");
    // A plan keeps them too.
    let plan = v1::PlanRequest { motion: Some(motion.clone()), dt: 1e-3, duration: 10.0 };
    let plan = within("plan", client.plan(plan)).await.unwrap().trajectory.unwrap();
    let p = peaks(&kept(&[plan]), 1e-3);
    assert!(p[0] <= slow.max_speed && p[1] <= slow.max_acceleration && p[2] <= slow.max_jerk, "plan {p:?}");

    // The request's max_speed replaces the record's; its other fields, left 0, keep the record's.
    motion.limits = Some(v1::Limits { max_speed: 0.9, ..Default::default() });
    let p = peaks(&kept(&executed(&client, motion).await), 1e-3);
    assert!(p[0] > 1.1 * slow.max_speed && p[0] <= 0.9, "speed {p:?}");
    assert!(p[1] <= slow.max_acceleration && p[2] <= slow.max_jerk, "{p:?}");
    within("shutdown", handle.shutdown()).await.unwrap();
}

#[tokio::test(flavor = "multi_thread")]
async fn who_may_put_a_robots_record_is_who_may_write_its_primitives() {
    let set = tempfile::tempdir().unwrap();
    let (server, tokens) = secured(set.path()).await;
    let admin = as_identity(&server, Some(&tokens["admin"])).await;
    let planner = as_identity(&server, Some(&tokens["planner"])).await;
    let panda1 = as_identity(&server, Some(&tokens["panda-1"])).await;
    let observer = as_identity(&server, Some(&tokens["observer"])).await;
    within("admin put", admin.put_robot(panda_record("panda-2"))).await.unwrap();
    // The planner writes the primitives of panda-1 and panda-2, and no other robot's.
    within("planner put", planner.put_robot(panda_record("panda-1"))).await.unwrap();
    let e = within("planner put other", planner.put_robot(panda_record("panda-3"))).await.unwrap_err();
    assert_eq!(e.code(), Some(Code::PermissionDenied), "{e}");
    // A robot's token writes no primitives: neither another robot's record nor its own.
    for robot in ["panda-2", "panda-1"] {
        let e = within("robot put", panda1.put_robot(panda_record(robot))).await.unwrap_err();
        assert_eq!(e.code(), Some(Code::PermissionDenied), "{robot}: {e}");
        let e = within("robot delete", panda1.delete_robot(robot)).await.unwrap_err();
        assert_eq!(e.code(), Some(Code::PermissionDenied), "{robot}: {e}");
    }
    let e = within("observer put", observer.put_robot(panda_record("panda-1"))).await.unwrap_err();
    assert_eq!(e.code(), Some(Code::PermissionDenied), "{e}");
    // Reading follows reading the primitives: a robot reads its own record, not another's.
    within("robot get", panda1.get_robot("panda-1")).await.unwrap();
    let e = within("robot get other", panda1.get_robot("panda-2")).await.unwrap_err();
    assert_eq!(e.code(), Some(Code::PermissionDenied), "{e}");
    // The refused puts changed nothing.
    let r = within("get", admin.get_robot("panda-2")).await.unwrap();
    assert_eq!(v1::RobotRecord { updated_unix_ms: 0, ..r }, panda_record("panda-2"));
    within("stop", server.stop()).await;
}
