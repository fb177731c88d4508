//! One careless or hostile client must not delay the other robots: the real server in-process, attacked by clients
//! on their own connections while a robot streams in real time. Its own test binary, so that no other test of the
//! suite runs beside it and disturbs its timing.

use std::time::{Duration, Instant, SystemTime, UNIX_EPOCH};

use dmp::Primitive;
use dmp_client::DmpClient;
use dmp_proto::v1;
use dmp_tests::{TestServer, within};
use tokio_stream::StreamExt;

fn now_unix_s() -> f64 {
    SystemTime::now().duration_since(UNIX_EPOCH).unwrap().as_secs_f64()
}

fn line(tau: f64) -> Primitive {
    Primitive::straight_line(50, 4.0, vec![1000.0; 3], None, tau, vec![0.0; 3], vec![1.0, 0.5, 0.0]).unwrap()
}

fn spec(robot: &str, extra: Vec<v1::Obstacle>, avoidance: v1::Avoidance) -> v1::MotionSpec {
    v1::MotionSpec {
        robot_id: robot.into(),
        primitive: "reach".into(),
        extra_obstacles: extra,
        avoidance: Some(avoidance),
        ..Default::default()
    }
}

/// `n` spheres of 10 cm, 50 m away from everything.
fn far_obstacles(n: usize) -> Vec<v1::Obstacle> {
    (0..n)
        .map(|i| v1::Obstacle {
            id: format!("far-{i}"),
            shape: Some(v1::obstacle::Shape::Superquadric(v1::Superquadric {
                semi_axes: vec![0.1; 3],
                exponents: vec![],
            })),
            center: vec![50.0 + (i % 10) as f64, 50.0 + (i / 10 % 10) as f64, 50.0 + (i / 100) as f64],
            ..Default::default()
        })
        .collect()
}

fn static_point(samples: u32) -> v1::Avoidance {
    v1::Avoidance {
        method: Some(v1::avoidance::Method::StaticPoint(v1::avoidance::StaticPoint { eta: 1.0, p0: 1.0 })),
        point_samples: samples,
        ..Default::default()
    }
}

fn volumetric() -> v1::Avoidance {
    v1::Avoidance {
        method: Some(v1::avoidance::Method::DynamicVolumetric(v1::avoidance::DynamicVolumetric {
            lambda: 10.0,
            beta: 2.0,
            eta: 0.5,
        })),
        ..Default::default()
    }
}

/// Plans as costly as the server admits, one after the other, until the task is dropped.
async fn planner_attack(client: DmpClient, robot: &'static str) {
    loop {
        let request = v1::PlanRequest {
            motion: Some(spec(robot, far_obstacles(1000), volumetric())),
            duration: 20.0,
            ..Default::default()
        };
        let _ = client.plan(request).await;
    }
}

/// As-fast-as-read streams with a thousand obstacles, read as fast as they come.
async fn reader_attack(client: DmpClient, robot: &'static str) {
    loop {
        let request = v1::ExecuteRequest {
            motion: Some(spec(robot, far_obstacles(1000), volumetric())),
            max_duration_s: 3.0,
            ..Default::default()
        };
        if let Ok(mut s) = client.execute(request).await {
            while s.next().await.is_some() {}
        }
    }
}

#[tokio::test(flavor = "multi_thread")]
async fn attackers_do_not_delay_a_real_time_robot_or_health() {
    let server = TestServer::start().await;
    let client = server.client().await;
    for robot in ["victim", "attacker-1", "attacker-2"] {
        within("put", client.put_primitive(robot, "reach", &line(2.0))).await.unwrap();
    }

    // The request that used to stop every stream: refused before any work, with its cost.
    let heavy = v1::ExecuteRequest {
        motion: Some(spec("attacker-1", far_obstacles(1000), static_point(10_000))),
        segment_s: 1.0,
        pacing: v1::Pacing::Realtime as i32,
        ..Default::default()
    };
    let Err(refused) = within("heavy execute", client.execute(heavy.clone())).await else {
        panic!("admitted")
    };
    assert!(
        matches!(refused.code(), Some(tonic::Code::ResourceExhausted | tonic::Code::InvalidArgument)),
        "{refused}"
    );
    let mut as_fast = heavy;
    as_fast.pacing = v1::Pacing::AsFastAsRead as i32;
    let Err(refused) = within("heavy execute", client.execute(as_fast)).await else { panic!("admitted") };
    assert!(
        matches!(refused.code(), Some(tonic::Code::ResourceExhausted | tonic::Code::InvalidArgument)),
        "{refused}"
    );

    // Two attackers, each on its own connection, keep the batch pool full with the costliest work admitted.
    let mut attacks = Vec::new();
    for robot in ["attacker-1", "attacker-2"] {
        let c = server.client().await;
        attacks.push(tokio::spawn(planner_attack(c.clone(), robot)));
        attacks.push(tokio::spawn(reader_attack(c, robot)));
    }
    // Let them start.
    let pool = &server.handle().compute().batch;
    within("attacks running", async {
        while pool.counters().running.load(std::sync::atomic::Ordering::Acquire) == 0 {
            tokio::time::sleep(Duration::from_millis(5)).await;
        }
    })
    .await;

    // Health answers quickly all along.
    let channel = tonic::transport::Channel::from_shared(server.url()).unwrap().connect().await.unwrap();
    let mut health = tonic_health::pb::health_client::HealthClient::new(channel);
    let health_checks = tokio::spawn(async move {
        let mut slowest = Duration::ZERO;
        for _ in 0..30 {
            let t0 = Instant::now();
            let r = within("health", health.check(tonic_health::pb::HealthCheckRequest::default())).await;
            assert!(r.is_ok(), "{r:?}");
            slowest = slowest.max(t0.elapsed());
            tokio::time::sleep(Duration::from_millis(100)).await;
        }
        slowest
    });

    // The robot streams in real time: each segment must arrive before its points are due.
    let request = v1::ExecuteRequest {
        motion: Some(v1::MotionSpec {
            robot_id: "victim".into(),
            primitive: "reach".into(),
            ..Default::default()
        }),
        pacing: v1::Pacing::Realtime as i32,
        max_duration_s: 3.0,
        ..Default::default()
    };
    let mut stream = within("execute", client.execute(request)).await.unwrap();
    let (mut points, mut late) = (0usize, 0usize);
    let mut last_status = 0;
    while let Some(segment) = within("segment", stream.next()).await {
        let segment = segment.unwrap();
        let arrived = now_unix_s();
        let n = segment.positions.len() / segment.dim as usize;
        points += n;
        late += (0..n).filter(|k| segment.start_unix_s + *k as f64 * segment.dt < arrived).count();
        last_status = segment.status;
    }
    let slowest_health = within("health checks", health_checks).await.unwrap();
    for a in &attacks {
        a.abort();
    }
    let on_time = 1.0 - late as f64 / points as f64;
    println!("robot: {late} of {points} setpoints late; slowest health check {slowest_health:?}");
    assert!(points >= 1000, "{points} points");
    assert!(on_time >= 0.999, "{late} of {points} setpoints late");
    assert!(
        [v1::SegmentStatus::GoalReached as i32, v1::SegmentStatus::Stopped as i32].contains(&last_status),
        "{last_status}"
    );
    assert!(slowest_health < Duration::from_millis(100), "health took {slowest_health:?}");

    // The attackers are gone: their work stops (plans between chunks, streams at once), it does not run on.
    drop(attacks);
    within("abandoned work stops", async {
        while pool.counters().running.load(std::sync::atomic::Ordering::Acquire) > 0 {
            tokio::time::sleep(Duration::from_millis(5)).await;
        }
    })
    .await;
    server.stop().await;
}
