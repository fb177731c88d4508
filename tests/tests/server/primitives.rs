//! Stored primitives: they survive a restart, and a plan is the engine's own rollout.

use dmp_proto::v1;

use crate::default_limits::exact;
use crate::{dynamic_volumetric, ellipse, line, paper_curve, serve, spec};
use dmp_tests::within;

#[tokio::test(flavor = "multi_thread")]
async fn primitives_survive_a_restart_and_a_plan_equals_the_engine() {
    let dir = tempfile::tempdir().unwrap();
    let (t, x) = paper_curve();
    let (handle, client) = serve(dir.path()).await;
    let r1 = within("learn", client.learn("panda", "curve", &t, &x, Default::default())).await.unwrap();
    let r2 = within("learn again", client.learn("panda", "curve", &t, &x, Default::default())).await.unwrap();
    assert_eq!((r1.version, r2.version), (1, 2));
    within("put", client.put_primitive("panda", "line", &line(vec![0.0; 2], vec![1.0, 0.0], 1.0)))
        .await
        .unwrap();
    let before = within("list", client.list("panda")).await.unwrap();
    assert_eq!(
        before.iter().map(|r| (r.name.as_str(), r.version)).collect::<Vec<_>>(),
        [("curve", 2), ("line", 1)]
    );
    within("shutdown", handle.shutdown()).await.unwrap();

    let (handle, client) = serve(dir.path()).await;
    let after = within("list after restart", client.list("panda")).await.unwrap();
    assert_eq!(after, before);
    within("get v1", client.get("panda", "curve", 1)).await.unwrap();

    // The stored primitive is the engine's, bit for bit, and a plan is the engine's rollout.
    let demo = dmp::Demonstration::new(t.clone(), x.clone()).unwrap();
    let offline = dmp::learn(&demo, &dmp::LearnConfig::paper()).unwrap();
    let stored = dmp_client::grpc::record_primitive(&after[0]).unwrap();
    assert_eq!(stored, offline);
    let mut motion = exact(spec("panda", "curve"));
    motion.avoidance = Some(dynamic_volumetric(10.0, 2.0, 0.5));
    motion.extra_obstacles = vec![ellipse("ellipse", vec![-0.5, 0.7], vec![0.3, 0.2])];
    motion.ignore_scene = true;
    let plan = within("plan", client.plan(v1::PlanRequest { motion: Some(motion), dt: 1e-3, duration: 1.0 }))
        .await
        .unwrap();
    assert!(plan.collisions.is_empty() && !plan.stalled);
    let seg = plan.trajectory.unwrap();
    let shape = dmp::Shape::Superquadric(dmp::Superquadric::ellipsoid(vec![0.3, 0.2]).unwrap());
    let obstacle = dmp::Obstacle::new("ellipse", shape, vec![-0.5, 0.7], None, None).unwrap();
    let avoidance = dmp::Avoidance::new(dmp::Method::DynamicVolumetric(dmp::avoidance::DynamicVolumetric {
        lambda: 10.0,
        beta: 2.0,
        eta: 0.5,
    }));
    let field =
        dmp::RepulsiveField::new(dmp::Scene::with_obstacles(vec![obstacle], avoidance, 50), 2).unwrap();
    let reference =
        dmp::rollout(&offline, &dmp::Motion::of(&offline), &field, 1e-3, 1000).unwrap().trajectory;
    assert_eq!(seg.positions.len(), reference.x.len());
    let worst = seg.positions.iter().zip(&reference.x).map(|(a, b)| (a - b).abs()).fold(0.0, f64::max);
    assert!(worst <= 1e-9, "plan differs from the engine by {worst}");
    let worst_v = seg.velocities.iter().zip(&reference.xd).map(|(a, b)| (a - b).abs()).fold(0.0, f64::max);
    assert!(worst_v <= 1e-9, "velocities differ by {worst_v}");
    within("shutdown", handle.shutdown()).await.unwrap();
}
