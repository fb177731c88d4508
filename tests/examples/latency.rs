//! Measures, against the real server in-process (gRPC and Zenoh over loopback):
//! - plan latency for a 3-D primitive (N = 50) with ten obstacles in the scene (2 s at dt = 1 ms);
//! - the time from a Zenoh obstacle put to the first segment, at the robot, that accounts for it (real-time stream).
//!
//! `cargo run --release -p dmp-tests --example latency [-- REPEATS]` prints one JSON object (medians and p99).

use std::time::{Duration, Instant};

use dmp_client::zenoh_pub::ObstaclePublisher;
use dmp_proto::v1;
use dmp_tests::TestServer;
use tokio_stream::StreamExt;

fn percentile(v: &mut [f64], p: f64) -> f64 {
    v.sort_by(f64::total_cmp);
    v[((v.len() - 1) as f64 * p).round() as usize]
}

#[tokio::main(flavor = "multi_thread")]
async fn main() -> Result<(), Box<dyn std::error::Error>> {
    let repeats: usize = std::env::args().nth(1).map(|s| s.parse()).transpose()?.unwrap_or(50);
    let server = TestServer::start().await;
    let handle = server.handle();
    let client = server.client().await;

    // A 3-D demonstration (the bench scenario's curve) and ten superquadrics along it.
    let t: Vec<f64> = (0..=2000).map(|i| i as f64 * 1e-3).collect();
    let x: Vec<Vec<f64>> =
        t.iter().map(|t| vec![0.5 * t, 0.3 * (std::f64::consts::PI * t).sin(), 0.2 * t * t]).collect();
    client.learn("panda", "arc", &t, &x, Default::default()).await?;
    for k in 0..10 {
        let s = k as f64 / 9.0 * 2.0;
        let c = vec![
            0.5 * s + 0.05,
            0.3 * (std::f64::consts::PI * s).sin() + if k % 2 == 1 { 0.12 } else { -0.12 },
            0.2 * s * s,
        ];
        let o = v1::Obstacle {
            id: format!("o{k}"),
            shape: Some(v1::obstacle::Shape::Superquadric(v1::Superquadric {
                semi_axes: vec![0.04, 0.05, 0.06],
                exponents: vec![1.0, 1.0, 2.0],
            })),
            center: c,
            ..Default::default()
        };
        client.put_obstacle(o).await?;
    }
    let plan_request = v1::PlanRequest {
        motion: Some(v1::MotionSpec {
            robot_id: "panda".into(),
            primitive: "arc".into(),
            ..Default::default()
        }),
        dt: 1e-3,
        duration: 2.0,
    };
    client.plan(plan_request.clone()).await?;
    let mut plan_ms = Vec::with_capacity(repeats);
    for _ in 0..repeats {
        let started = Instant::now();
        let r = client.plan(plan_request.clone()).await?;
        plan_ms.push(started.elapsed().as_secs_f64() * 1e3);
        assert_eq!(r.trajectory.map(|s| s.positions.len()), Some(2001 * 3));
    }

    // Zenoh put -> first segment with the new scene version, on a real-time stream.
    client
        .put_primitive(
            "youbot",
            "corridor",
            &dmp::Primitive::straight_line(
                50,
                4.0,
                vec![3050.0; 2],
                None,
                1000.0,
                vec![0.0, 0.0],
                vec![100.0, 0.0],
            )?,
        )
        .await?;
    let perception = ObstaclePublisher::open("default", &handle.zenoh_locators, &[]).await?;
    perception.wait_for_subscriber(Duration::from_secs(10)).await?;
    let request = v1::ExecuteRequest {
        motion: Some(v1::MotionSpec {
            robot_id: "youbot".into(),
            primitive: "corridor".into(),
            ..Default::default()
        }),
        pacing: v1::Pacing::Realtime as i32,
        max_duration_s: 600.0,
        ..Default::default()
    };
    let mut stream = client.execute(request).await?;
    let mut version = stream.next().await.ok_or("stream ended")??.scene_version;
    let mut update_ms = Vec::with_capacity(repeats);
    let mut scene_ms = Vec::with_capacity(repeats);
    let scene = handle.cells().get("")?;
    for k in 0..repeats {
        let obstacle = serde_json::json!({"center": [50.0, 1.0 + k as f64 * 1e-3], "semi_axes": [0.2, 0.2]});
        let started = Instant::now();
        let before = scene.snapshot().version;
        let mut rx = scene.subscribe();
        let watcher = tokio::spawn(async move {
            while rx.borrow_and_update().version == before {
                if rx.changed().await.is_err() {
                    break;
                }
            }
            started.elapsed().as_secs_f64() * 1e3
        });
        perception.put_json("walker", &obstacle).await?;
        loop {
            let seg = stream.next().await.ok_or("stream ended")??;
            if seg.scene_version > version {
                update_ms.push(started.elapsed().as_secs_f64() * 1e3);
                scene_ms.push(watcher.await?);
                version = seg.scene_version;
                break;
            }
        }
        tokio::time::sleep(Duration::from_millis(20)).await;
    }
    drop(stream);
    let report = serde_json::json!({
        "repeats": repeats,
        "plan_3d_ten_obstacles_2000_steps_ms": {"p50": percentile(&mut plan_ms, 0.5), "p99": percentile(&mut plan_ms, 0.99)},
        "zenoh_put_to_scene_ms": {"p50": percentile(&mut scene_ms, 0.5), "p99": percentile(&mut scene_ms, 0.99)},
        "zenoh_put_to_segment_ms": {"p50": percentile(&mut update_ms, 0.5), "p99": percentile(&mut update_ms, 0.99)},
    });
    println!("{report}");
    server.stop().await;
    Ok(())
}
