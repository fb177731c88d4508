//! A stand-in for the server in the client's unit tests: the primitive and motion services over the engine, in
//! memory, served on `127.0.0.1:0`. Plans are the engine's rollouts (what the real server promises), so a
//! `scenario run` through it must reproduce the offline metrics; `Execute` and `ExecuteGroup` cut a plan into
//! segments; `Session` answers each command with a segment, so the plumbing can be checked. Not the server:
//! nothing here is persistent, paced or adaptive.

use std::collections::HashMap;
use std::net::SocketAddr;
use std::pin::Pin;
use std::sync::{Arc, Mutex};

use dmp::avoidance::{DynamicPoint, DynamicVolumetric, StaticPoint, StaticVolumetric, SteeringAngle};
use dmp::{Agent, Avoidance, Method, Motion, RepulsiveField, Scene, Trajectory};
use dmp_proto::v1;
use dmp_proto::v1::motion_service_server::{MotionService, MotionServiceServer};
use dmp_proto::v1::primitive_service_server::{PrimitiveService, PrimitiveServiceServer};
use tokio_stream::wrappers::{ReceiverStream, TcpListenerStream};
use tokio_stream::{Stream, StreamExt};
use tonic::{Request, Response, Status};

use crate::convert::{obstacle_from_json, obstacle_json, primitive_from_proto, primitive_to_proto};

type Store = Arc<Mutex<HashMap<(String, String), Vec<v1::PrimitiveRecord>>>>;
type Boxed<T> = Pin<Box<dyn Stream<Item = Result<T, Status>> + Send>>;

fn invalid(e: impl std::fmt::Display) -> Status {
    Status::invalid_argument(e.to_string())
}

#[derive(Debug, Clone, Default)]
struct Primitives {
    store: Store,
}

impl Primitives {
    fn store(&self, robot: String, name: String, p: &dmp::Primitive) -> v1::LearnResponse {
        let mut s = self.store.lock().unwrap();
        let versions = s.entry((robot.clone(), name.clone())).or_default();
        let record = v1::PrimitiveRecord {
            robot_id: robot,
            name,
            version: versions.len() as u64 + 1,
            created_unix_ms: 1,
            primitive: Some(primitive_to_proto(p)),
        };
        versions.push(record.clone());
        v1::LearnResponse { record: Some(record) }
    }

    fn get(&self, robot: &str, name: &str, version: u64) -> Result<v1::PrimitiveRecord, Status> {
        let s = self.store.lock().unwrap();
        let versions = s.get(&(robot.to_string(), name.to_string())).ok_or_else(|| {
            Status::not_found(format!("robot_id/name: no primitive `{name}` for robot `{robot}`"))
        })?;
        let v = if version == 0 { versions.len() } else { version as usize };
        versions
            .get(v.wrapping_sub(1))
            .cloned()
            .ok_or_else(|| Status::not_found(format!("version: no version {v}")))
    }
}

#[tonic::async_trait]
impl PrimitiveService for Primitives {
    async fn learn(&self, r: Request<v1::LearnRequest>) -> Result<Response<v1::LearnResponse>, Status> {
        let r = r.into_inner();
        let d = r.demonstration.ok_or_else(|| invalid("demonstration: is required"))?;
        let dim = d.dim as usize;
        if dim == 0 || d.positions.len() != d.t.len() * dim {
            return Err(invalid("demonstration.positions: must have t.len() x dim entries"));
        }
        let demo = dmp::Demonstration::new(d.t, d.positions.chunks(dim).map(<[f64]>::to_vec).collect())
            .map_err(invalid)?;
        let mut c = dmp::LearnConfig::paper();
        if let Some(p) = r.parameters {
            if p.n_basis > 0 {
                c.n_basis = p.n_basis as usize;
            }
            if !p.k.is_empty() {
                c.k = p.k;
            }
            if !p.d.is_empty() {
                c.d = Some(p.d);
            }
            if p.alpha != 0.0 {
                c.alpha = p.alpha;
            }
        }
        let p = dmp::learn(&demo, &c).map_err(invalid)?;
        Ok(Response::new(self.store(r.robot_id, r.name, &p)))
    }

    async fn put(&self, r: Request<v1::PutPrimitiveRequest>) -> Result<Response<v1::LearnResponse>, Status> {
        let r = r.into_inner();
        let p = primitive_from_proto(&r.primitive.unwrap_or_default()).map_err(invalid)?;
        Ok(Response::new(self.store(r.robot_id, r.name, &p)))
    }

    async fn get(
        &self,
        r: Request<v1::GetPrimitiveRequest>,
    ) -> Result<Response<v1::PrimitiveRecord>, Status> {
        let r = r.into_inner();
        Ok(Response::new(Primitives::get(self, &r.robot_id, &r.name, r.version)?))
    }

    async fn list(
        &self,
        r: Request<v1::ListPrimitivesRequest>,
    ) -> Result<Response<v1::ListPrimitivesResponse>, Status> {
        let robot = r.into_inner().robot_id;
        let s = self.store.lock().unwrap();
        let mut records: Vec<v1::PrimitiveRecord> =
            s.iter().filter(|((r, _), _)| *r == robot).filter_map(|(_, v)| v.last().cloned()).collect();
        records.sort_by(|a, b| a.name.cmp(&b.name));
        Ok(Response::new(v1::ListPrimitivesResponse { records }))
    }

    async fn delete(
        &self,
        r: Request<v1::DeletePrimitiveRequest>,
    ) -> Result<Response<v1::DeletePrimitiveResponse>, Status> {
        let r = r.into_inner();
        let n = self.store.lock().unwrap().remove(&(r.robot_id, r.name)).map_or(0, |v| v.len());
        Ok(Response::new(v1::DeletePrimitiveResponse { versions_deleted: n as u64 }))
    }
}

fn avoidance_from(a: Option<&v1::Avoidance>) -> (Avoidance, usize) {
    use v1::avoidance::Method as M;
    let Some(a) = a else { return (Avoidance::NONE, 50) };
    let method = match &a.method {
        None | Some(M::None(_)) => Method::None,
        Some(M::StaticPoint(p)) => Method::StaticPoint(StaticPoint { eta: p.eta, p0: p.p0 }),
        Some(M::DynamicPoint(p)) => Method::DynamicPoint(DynamicPoint { lambda: p.lambda, beta: p.beta }),
        Some(M::SteeringAngle(p)) => Method::SteeringAngle(SteeringAngle { gamma: p.gamma, beta: p.beta }),
        Some(M::StaticVolumetric(p)) => Method::StaticVolumetric(StaticVolumetric { a: p.a, eta: p.eta }),
        Some(M::DynamicVolumetric(p)) => {
            Method::DynamicVolumetric(DynamicVolumetric { lambda: p.lambda, beta: p.beta, eta: p.eta })
        }
    };
    let samples = if a.point_samples == 0 { 50 } else { a.point_samples as usize };
    (Avoidance { method, relative_velocity: !a.ignore_obstacle_velocity }, samples)
}

fn obstacles(list: &[v1::Obstacle]) -> Result<Vec<dmp::Obstacle>, Status> {
    list.iter()
        .map(|o| obstacle_from_json(&obstacle_json(o), "").map_err(invalid)?.to_engine().map_err(invalid))
        .collect()
}

fn segment(robot: &str, sequence: u64, t: &Trajectory, rows: std::ops::Range<usize>, dt: f64) -> v1::Segment {
    let d = t.dim();
    let r = rows.start * d..rows.end * d;
    v1::Segment {
        robot_id: robot.into(),
        sequence,
        start_time: t.t[rows.start],
        dt,
        dim: d as u32,
        positions: t.x[r.clone()].to_vec(),
        velocities: t.xd[r.clone()].to_vec(),
        accelerations: t.xdd[r].to_vec(),
        status: v1::SegmentStatus::Running as i32,
        scene_version: 0,
        start_unix_s: 0.0,
    }
}

#[derive(Debug, Clone, Default)]
struct Motions {
    primitives: Primitives,
}

impl Motions {
    /// The engine's rollout of one motion.
    fn rollout(&self, m: &v1::MotionSpec, dt: f64, duration: f64) -> Result<Trajectory, Status> {
        let record = self.primitives.get(&m.robot_id, &m.primitive, m.version)?;
        let p = primitive_from_proto(record.primitive.as_ref().unwrap()).map_err(invalid)?;
        let motion = Motion {
            start: if m.start.is_empty() { p.start.clone() } else { m.start.clone() },
            goal: if m.goal.is_empty() { p.goal.clone() } else { m.goal.clone() },
            tau: if m.tau == 0.0 { p.tau } else { m.tau },
        };
        let (avoidance, point_samples) = avoidance_from(m.avoidance.as_ref());
        let scene = Scene {
            obstacles: obstacles(&m.extra_obstacles)?,
            avoidance,
            agents: vec![],
            robot_avoidance: Avoidance::NONE,
            point_samples,
        };
        let dt = if dt == 0.0 { 0.001 } else { dt };
        let duration = if duration == 0.0 { 1.2 * motion.tau } else { duration };
        let mut field = RepulsiveField::new(scene, p.dim).map_err(invalid)?;
        let steps = ((duration / dt).round() as usize).max(1);
        Ok(dmp::rollout(&p, &motion, &mut field, dt, steps).map_err(invalid)?.trajectory)
    }

    /// Every member stacked into one primitive (member order), rolled out with the members as agents.
    fn group(&self, r: &v1::ExecuteGroupRequest) -> Result<(Trajectory, Vec<usize>), Status> {
        let mut whole: Option<dmp::Primitive> = None;
        let (mut start, mut goal, mut agents, mut dims) = (vec![], vec![], vec![], vec![]);
        for (i, member) in r.members.iter().enumerate() {
            let m = member.motion.as_ref().unwrap();
            let record = self.primitives.get(&m.robot_id, &m.primitive, m.version)?;
            let p = primitive_from_proto(record.primitive.as_ref().unwrap()).map_err(invalid)?;
            let offset = start.len();
            start.extend(if m.start.is_empty() { p.start.clone() } else { m.start.clone() });
            goal.extend(if m.goal.is_empty() { p.goal.clone() } else { m.goal.clone() });
            let fp = m.footprint.as_ref().unwrap();
            let n =
                if fp.exponents.is_empty() { vec![1.0; fp.semi_axes.len()] } else { fp.exponents.clone() };
            let footprint = dmp::Superquadric::new(fp.semi_axes.clone(), n).map_err(invalid)?;
            agents.push(Agent {
                id: format!("m{i}"),
                dims: (offset..offset + p.dim).collect(),
                footprint: Some(dmp::Shape::Superquadric(footprint)),
            });
            dims.push(p.dim);
            whole = Some(match whole {
                None => p,
                Some(mut w) => {
                    w.dim += p.dim;
                    w.k.extend(p.k);
                    w.d.extend(p.d);
                    w.start.extend(p.start);
                    w.goal.extend(p.goal);
                    w.weights.extend(p.weights);
                    w.tau = w.tau.max(p.tau);
                    w
                }
            });
        }
        let p = whole.ok_or_else(|| invalid("members: at least one"))?;
        let m0 = r.members[0].motion.as_ref().unwrap();
        let (avoidance, point_samples) = avoidance_from(m0.avoidance.as_ref());
        let (robot_avoidance, _) = avoidance_from(m0.robot_avoidance.as_ref());
        let scene = Scene {
            obstacles: obstacles(&m0.extra_obstacles)?,
            avoidance,
            agents,
            robot_avoidance,
            point_samples,
        };
        let motion = Motion { start, goal, tau: if r.tau == 0.0 { p.tau } else { r.tau } };
        let mut field = RepulsiveField::new(scene, p.dim).map_err(invalid)?;
        let steps = ((r.max_duration_s / r.dt).round() as usize).max(1);
        Ok((dmp::rollout(&p, &motion, &mut field, r.dt, steps).map_err(invalid)?.trajectory, dims))
    }
}

/// Points per segment of the mock's streams.
pub const SEGMENT_POINTS: usize = 10;

#[tonic::async_trait]
impl MotionService for Motions {
    async fn plan(&self, r: Request<v1::PlanRequest>) -> Result<Response<v1::PlanResponse>, Status> {
        let r = r.into_inner();
        let m = r.motion.ok_or_else(|| invalid("motion: is required"))?;
        let t = self.rollout(&m, r.dt, r.duration)?;
        let dt = t.t.get(1).copied().unwrap_or(0.001);
        let mut seg = segment(&m.robot_id, 0, &t, 0..t.len(), dt);
        seg.status = v1::SegmentStatus::GoalReached as i32;
        Ok(Response::new(v1::PlanResponse { trajectory: Some(seg), collisions: vec![], stalled: false }))
    }

    type ExecuteStream = Boxed<v1::Segment>;

    async fn execute(&self, r: Request<v1::ExecuteRequest>) -> Result<Response<Self::ExecuteStream>, Status> {
        let r = r.into_inner();
        let m = r.motion.ok_or_else(|| invalid("motion: is required"))?;
        let dt = if r.dt == 0.0 { 0.001 } else { r.dt };
        let t = self.rollout(&m, dt, r.max_duration_s)?;
        let mut segments: Vec<Result<v1::Segment, Status>> = (0..t.len())
            .step_by(SEGMENT_POINTS)
            .enumerate()
            .map(|(i, k)| Ok(segment(&m.robot_id, i as u64, &t, k..(k + SEGMENT_POINTS).min(t.len()), dt)))
            .collect();
        if let Some(Ok(last)) = segments.last_mut() {
            last.status = v1::SegmentStatus::GoalReached as i32;
        }
        Ok(Response::new(Box::pin(tokio_stream::iter(segments))))
    }

    type SessionStream = Boxed<v1::Segment>;

    /// Segment 0: the first 10 points of the plan. Then per command: `set_goal` sends a segment from `t = 0.005`
    /// holding the goal (superseding half of segment 0); `stop` sends an empty STOPPED segment and ends.
    async fn session(
        &self,
        r: Request<tonic::Streaming<v1::SessionRequest>>,
    ) -> Result<Response<Self::SessionStream>, Status> {
        use v1::session_request::Message;
        let mut incoming = r.into_inner();
        let Some(Ok(v1::SessionRequest { message: Some(Message::Start(start)) })) = incoming.next().await
        else {
            return Err(invalid("message: the first message must be `start`"));
        };
        let m = start.motion.unwrap_or_default();
        let t = self.rollout(&m, 0.001, 0.0)?;
        let (tx, rx) = tokio::sync::mpsc::channel(4);
        tokio::spawn(async move {
            let _ = tx.send(Ok(segment(&m.robot_id, 0, &t, 0..SEGMENT_POINTS, 0.001))).await;
            let mut sequence = 1;
            while let Some(Ok(req)) = incoming.next().await {
                let seg = match req.message {
                    Some(Message::SetGoal(g)) => {
                        let d = g.goal.len();
                        v1::Segment {
                            robot_id: m.robot_id.clone(),
                            sequence,
                            start_time: 0.005,
                            dt: 0.001,
                            dim: d as u32,
                            positions: g.goal.repeat(3),
                            velocities: vec![0.0; 3 * d],
                            accelerations: vec![0.0; 3 * d],
                            status: v1::SegmentStatus::Running as i32,
                            ..Default::default()
                        }
                    }
                    Some(Message::Stop(_)) => {
                        let seg = v1::Segment {
                            sequence,
                            start_time: 0.008,
                            dt: 0.001,
                            dim: t.dim() as u32,
                            status: v1::SegmentStatus::Stopped as i32,
                            ..Default::default()
                        };
                        let _ = tx.send(Ok(seg)).await;
                        return;
                    }
                    _ => continue,
                };
                sequence += 1;
                if tx.send(Ok(seg)).await.is_err() {
                    return;
                }
            }
        });
        Ok(Response::new(Box::pin(ReceiverStream::new(rx))))
    }

    type ExecuteGroupStream = Boxed<v1::GroupSegment>;

    async fn execute_group(
        &self,
        r: Request<v1::ExecuteGroupRequest>,
    ) -> Result<Response<Self::ExecuteGroupStream>, Status> {
        let r = r.into_inner();
        let (t, dims) = self.group(&r)?;
        let mut steps = Vec::new();
        for (i, k) in (0..t.len()).step_by(SEGMENT_POINTS).enumerate() {
            let rows = k..(k + SEGMENT_POINTS).min(t.len());
            let mut offset = 0;
            let mut segments = Vec::new();
            for (member, &d) in dims.iter().enumerate() {
                let mut part = Trajectory::with_capacity(d, rows.len());
                for row in rows.clone() {
                    let o = offset..offset + d;
                    part.push(
                        t.t[row],
                        &t.position(row)[o.clone()],
                        &t.velocity(row)[o.clone()],
                        &t.acceleration(row)[o],
                    );
                }
                segments.push(segment(&format!("m{member}"), i as u64, &part, 0..part.len(), r.dt));
                offset += d;
            }
            steps.push(Ok(v1::GroupSegment { sequence: i as u64, segments }));
        }
        Ok(Response::new(Box::pin(tokio_stream::iter(steps))))
    }
}

/// Serves the mock on `127.0.0.1:0`; returns its address (the server runs until the runtime ends).
pub async fn spawn() -> SocketAddr {
    let listener = tokio::net::TcpListener::bind("127.0.0.1:0").await.unwrap();
    let addr = listener.local_addr().unwrap();
    let primitives = Primitives::default();
    let motions = Motions { primitives: primitives.clone() };
    tokio::spawn(
        tonic::transport::Server::builder()
            .add_service(PrimitiveServiceServer::new(primitives))
            .add_service(MotionServiceServer::new(motions))
            .serve_with_incoming(TcpListenerStream::new(listener)),
    );
    addr
}
