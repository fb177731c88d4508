//! The server against the engine run offline: a scenario's metrics, and a coarse internal step's accuracy.

use std::path::Path;

use dmp_proto::v1;
use tokio_stream::StreamExt;

use crate::default_limits::exact;
use crate::{dynamic_volumetric, ellipse, paper_curve, serve, spec};
use dmp_tests::within;

#[tokio::test(flavor = "multi_thread")]
async fn scenario_run_through_the_server_gives_the_offline_metrics() {
    let dir = tempfile::tempdir().unwrap();
    let (handle, client) = serve(dir.path()).await;
    let scenarios = Path::new(env!("CARGO_MANIFEST_DIR")).join("../scenarios");
    for file in [
        "paper-one-obstacle/dynamic_volumetric.json",
        "paper-one-obstacle/static_point.json",
        "moving-obstacle-dynamic-volumetric.json",
        "youbots-three-dynamic.json",
    ] {
        let path = scenarios.join(file);
        let (off, on) = (dir.path().join("off"), dir.path().join("on"));
        let offline = dmpctl::offline::run_scenario(&path, &off).unwrap().metrics;
        let remote = within(
            "remote scenario",
            dmpctl::scenario_through_server::run_scenario_through_server(&client, &path, &on, false),
        )
        .await
        .unwrap()
        .metrics;
        let strip = |m: &dmp::metrics::Metrics| {
            let mut v = serde_json::to_value(m).unwrap();
            v.as_object_mut().unwrap().remove("compute_seconds");
            v
        };
        assert_eq!(strip(&offline), strip(&remote), "{file}");
        let (a, b) = (
            std::fs::read(off.join("trajectory.csv")).unwrap(),
            std::fs::read(on.join("trajectory.csv")).unwrap(),
        );
        assert!(a == b, "{file}: trajectory.csv differs");
    }
    within("shutdown", handle.shutdown()).await.unwrap();
}

/// The bound: a stream on a coarse internal step (RK4 every 5 or 10 ms, quintic Hermite in between) stays
/// within 1e-3 of the engine's own 1 ms RK4 rollout of the same situation: the paper's curve past a still ellipse
/// and a moving one, with the static and the dynamic volumetric potentials.
#[tokio::test(flavor = "multi_thread")]
async fn a_coarse_internal_step_stays_within_1e3_of_the_engines_1ms_rollout() {
    let dir = tempfile::tempdir().unwrap();
    let (t, x) = paper_curve();
    let (handle, client) = serve(dir.path()).await;
    within("learn", client.learn("arm", "curve", &t, &x, Default::default())).await.unwrap();
    let primitive = dmp::learn(&dmp::Demonstration::new(t, x).unwrap(), &dmp::LearnConfig::paper()).unwrap();
    let still = ellipse("still", vec![-0.5, 0.7], vec![0.3, 0.2]);
    let mut moving = ellipse("moving", vec![0.6, 0.2], vec![0.15, 0.1]);
    moving.velocity = vec![-0.4, 0.3];
    let engine_obstacle = |o: &v1::Obstacle| {
        let v1::obstacle::Shape::Superquadric(q) = o.shape.clone().unwrap() else { unreachable!() };
        let shape = dmp::Shape::Superquadric(dmp::Superquadric::ellipsoid(q.semi_axes).unwrap());
        let velocity = (!o.velocity.is_empty()).then(|| o.velocity.clone());
        dmp::Obstacle::new(o.id.clone(), shape, o.center.clone(), None, velocity).unwrap()
    };
    let methods = [
        (
            dmp::Method::StaticVolumetric(dmp::avoidance::StaticVolumetric { a: 1.0, eta: 1.0 }),
            v1::Avoidance {
                method: Some(v1::avoidance::Method::StaticVolumetric(v1::avoidance::StaticVolumetric {
                    a: 1.0,
                    eta: 1.0,
                })),
                ..Default::default()
            },
        ),
        (
            dmp::Method::DynamicVolumetric(dmp::avoidance::DynamicVolumetric {
                lambda: 10.0,
                beta: 2.0,
                eta: 0.5,
            }),
            dynamic_volumetric(10.0, 2.0, 0.5),
        ),
    ];
    for (method, avoidance) in methods {
        let scene = dmp::Scene::with_obstacles(
            vec![engine_obstacle(&still), engine_obstacle(&moving)],
            dmp::Avoidance::new(method),
            50,
        );
        let field = dmp::RepulsiveField::new(scene, 2).unwrap();
        let reference =
            dmp::rollout(&primitive, &dmp::Motion::of(&primitive), &field, 1e-3, 1500).unwrap().trajectory;
        // Fixed RK4 steps, and the adaptive step (Dormand-Prince 5(4), at most 30 ms).
        for (step, tolerance) in [(0.005, 0.0), (0.01, 0.0), (0.03, 3e-6)] {
            let mut motion = exact(spec("arm", "curve"));
            motion.avoidance = Some(avoidance);
            motion.extra_obstacles = vec![still.clone(), moving.clone()];
            motion.ignore_scene = true;
            let request = v1::ExecuteRequest {
                motion: Some(motion),
                dt: 1e-3,
                segment_s: 0.01,
                max_duration_s: 1.5,
                integration_step_s: step,
                integration_tolerance: tolerance,
                ..Default::default()
            };
            let stream = within("execute", client.execute(request)).await.unwrap();
            let mut positions = Vec::new();
            let mut stream = std::pin::pin!(stream);
            while let Some(seg) = within("segment", stream.next()).await {
                positions.extend(seg.unwrap().positions);
            }
            // Until the goal is reached (the stream ends there) or for the whole 1.5 s.
            assert!(
                positions.len() >= 2 * 1001 && positions.len() <= reference.x.len(),
                "{method:?} at {step}"
            );
            let worst = positions.iter().zip(&reference.x).map(|(a, b)| (a - b).abs()).fold(0.0, f64::max);
            println!(
                "{method:?}, internal step {step} s, tolerance {tolerance}: largest deviation from the 1 ms \
                 rollout {worst:.3e}"
            );
            assert!(worst <= 1e-3, "{method:?} at a {step} s step: {worst}");
            assert!(worst > 0.0, "a coarse step is not the 1 ms rollout itself");
        }
    }
    within("shutdown", handle.shutdown()).await.unwrap();
}
