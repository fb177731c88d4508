//! The server's default profile (`[defaults.limits]`, `[defaults] margin_m`): what a robot nobody described keeps,
//! reported with the run; a negative field turns a limit off and is reported so; a bad profile stops the server
//! from starting.

use dmp_proto::limits::NO_LIMITS;
use dmp_proto::v1;
use dmp_server::server::start;
use dmp_tests::{config, within};
use tokio_stream::StreamExt;

use crate::motion_limits::{executed, kept, peaks};
use crate::{line, serve, spec};

/// `m`, asking for no limits and no safety distance: the DMP's own trajectory, as the engine computes it (a
/// motion that sets neither keeps the server's default profile).
pub(crate) fn exact(m: v1::MotionSpec) -> v1::MotionSpec {
    v1::MotionSpec { limits: Some(NO_LIMITS), margin: -1.0, ..m }
}

/// The default profile's linear limits: 1 m/s, 5 m/s², 50 m/s³.
const DEFAULT: [f64; 3] = [1.0, 5.0, 50.0];

/// The limits in force of a robot without a record, asking for nothing.
fn default_profile() -> v1::LimitsInForce {
    v1::LimitsInForce {
        limits: Some(v1::Limits {
            max_speed: 1.0,
            max_acceleration: 5.0,
            max_jerk: 50.0,
            max_angular_speed: 2.0,
            max_angular_acceleration: 10.0,
            max_angular_jerk: 100.0,
        }),
        profile: "server default".into(),
        unlimited: Vec::new(),
        margin: 0.01,
    }
}

#[tokio::test(flavor = "multi_thread")]
async fn a_robot_without_a_record_keeps_the_default_profile_and_is_told_so() {
    let dir = tempfile::tempdir().unwrap();
    let (handle, client) = serve(dir.path()).await;
    // 1 m in 0.5 s: about 2 m/s on average, far beyond the default profile.
    within("put", client.put_primitive("base", "dash", &line(vec![0.0; 2], vec![1.0, 0.0], 0.5)))
        .await
        .unwrap();
    let mut motion = spec("base", "dash");
    motion.ignore_scene = true;

    let segments = executed(&client, motion.clone()).await;
    assert_eq!(segments[0].sequence, 0);
    assert_eq!(segments[0].limits, Some(default_profile()), "the first segment");
    assert!(segments[1..].iter().all(|s| s.limits.is_none()), "only the first segment carries them");
    assert_eq!(segments.last().unwrap().status, v1::SegmentStatus::GoalReached as i32);
    let p = peaks(&kept(&segments), segments[0].dt);
    assert!(p.iter().zip(DEFAULT).all(|(p, l)| *p <= l), "a setpoint over the profile: {p:?}");
    assert!(p[0] > 0.9 * DEFAULT[0], "the run uses the speed it is given: {p:?}");

    let plan = v1::PlanRequest { motion: Some(motion.clone()), dt: 1e-3, duration: 10.0 };
    let plan = within("plan", client.plan(plan)).await.unwrap();
    assert_eq!(plan.limits, Some(default_profile()), "the plan");
    let p = peaks(&kept(&[plan.trajectory.unwrap()]), 1e-3);
    assert!(p.iter().zip(DEFAULT).all(|(p, l)| *p <= l), "a planned point over the profile: {p:?}");

    // A group: each member's first segment.
    within("put", client.put_primitive("other", "dash", &line(vec![0.0, 1.0], vec![1.0, 1.0], 0.5)))
        .await
        .unwrap();
    let members = ["base", "other"].map(|robot| v1::GroupMember {
        motion: Some(v1::MotionSpec {
            ignore_scene: true,
            footprint: Some(v1::Superquadric { semi_axes: vec![0.1, 0.1], exponents: vec![] }),
            ..spec(robot, "dash")
        }),
    });
    let request =
        v1::ExecuteGroupRequest { members: members.to_vec(), max_duration_s: 30.0, ..Default::default() };
    let mut stream = within("group", client.execute_group(request)).await.unwrap();
    let first = within("group segment", stream.next()).await.unwrap().unwrap();
    assert_eq!(first.sequence, 0);
    assert!(first.segments.iter().all(|s| s.limits == Some(default_profile())), "{:?}", first.segments);
    drop(stream);
    within("shutdown", handle.shutdown()).await.unwrap();
}

#[tokio::test(flavor = "multi_thread")]
async fn a_negative_field_is_no_limit_and_is_reported_unlimited() {
    let dir = tempfile::tempdir().unwrap();
    let (handle, client) = serve(dir.path()).await;
    within("put", client.put_primitive("base", "dash", &line(vec![0.0; 2], vec![1.0, 0.0], 0.5)))
        .await
        .unwrap();
    let mut motion = spec("base", "dash");
    motion.ignore_scene = true;
    motion.limits = Some(v1::Limits { max_speed: -1.0, ..Default::default() });
    motion.margin = -1.0;

    let segments = executed(&client, motion).await;
    let in_force = segments[0].limits.clone().expect("the first segment carries the limits in force");
    assert_eq!(in_force.unlimited, ["max_speed"]);
    assert_eq!(in_force.profile, "request + server default");
    assert_eq!(in_force.margin, 0.0, "a negative margin is none");
    let bounds = in_force.limits.unwrap();
    assert_eq!((bounds.max_speed, bounds.max_acceleration, bounds.max_jerk), (0.0, 5.0, 50.0));
    let p = peaks(&kept(&segments), segments[0].dt);
    assert!(p[0] > DEFAULT[0], "no speed limit: {p:?}");
    assert!(p[1] <= DEFAULT[1] && p[2] <= DEFAULT[2], "the other fields keep the default: {p:?}");
    within("shutdown", handle.shutdown()).await.unwrap();
}

#[tokio::test(flavor = "multi_thread")]
async fn the_default_profile_comes_from_the_configuration_and_a_bad_one_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    // 0 is "not set" on the wire: refused in the profile, naming the key.
    let mut bad = config(dir.path());
    bad.defaults.limits.max_acceleration = 0.0;
    let e = within("start", start(bad)).await.unwrap_err().to_string();
    assert!(e.starts_with("defaults.limits.max_acceleration:"), "{e}");
    let mut bad = config(dir.path());
    bad.defaults.margin_m = f64::NAN;
    let e = within("start", start(bad)).await.unwrap_err().to_string();
    assert!(e.starts_with("defaults.margin_m:"), "{e}");

    // A default set negative: no default for that field.
    let mut c = config(dir.path());
    c.defaults.limits.max_jerk = -1.0;
    c.defaults.limits.max_speed = 0.5;
    c.defaults.margin_m = -1.0;
    let handle = within("start", start(c)).await.unwrap();
    let client = within("connect", dmp_client::DmpClient::connect(format!("http://{}", handle.grpc_addr)))
        .await
        .unwrap();
    within("put", client.put_primitive("base", "dash", &line(vec![0.0; 2], vec![1.0, 0.0], 0.5)))
        .await
        .unwrap();
    let motion = v1::MotionSpec { ignore_scene: true, ..spec("base", "dash") };
    let plan = v1::PlanRequest { motion: Some(motion), dt: 1e-3, duration: 10.0 };
    let plan = within("plan", client.plan(plan)).await.unwrap();
    let in_force = plan.limits.unwrap();
    assert_eq!(in_force.unlimited, ["max_jerk"]);
    assert_eq!((in_force.limits.unwrap().max_speed, in_force.margin), (0.5, 0.0));
    let p = peaks(&kept(&[plan.trajectory.unwrap()]), 1e-3);
    assert!(p[0] <= 0.5 && p[1] <= DEFAULT[1], "{p:?}");
    within("shutdown", handle.shutdown()).await.unwrap();
}
