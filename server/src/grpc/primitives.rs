//! `PrimitiveService`: learn, store, read and delete the primitives of each robot.
//!
//! Every request is validated first (an InvalidArgument status names the field); learning and the store run on
//! tokio's blocking pool (redb and the SVD are synchronous), and a Learn or Put returns once the record is durable.

use std::sync::Arc;
use std::time::{SystemTime, UNIX_EPOCH};

use dmp_proto::v1;
use dmp_proto::v1::primitive_service_server::PrimitiveService;
use tonic::{Request, Response, Status};
use tracing::{debug, error, info};

use dmp_proto::keys::check_name;

use crate::access::{Action, Caller};
use crate::audit;
use crate::error::ServerError;
use crate::grpc::shared::ServiceState;
use crate::wire::{demonstration_from_proto, learn_config_from_proto, primitive_from_proto};

/// Most cells of the least-squares design matrix of a Learn (samples x (N + 1)): the SVD keeps about three such
/// matrices and costs samples x (N + 1)^2 operations. This is 200,000 samples with the default N = 50 (about
/// 80 MB a matrix), or 10,000 samples with N = 1000.
pub(crate) const MAX_LEARN_CELLS: usize = 200_000 * 51;

/// The gRPC primitive service.
#[derive(Debug, Clone)]
pub(crate) struct PrimitiveServiceImpl {
    /// What every service shares (the store and the limits here).
    pub state: Arc<ServiceState>,
}

impl PrimitiveServiceImpl {
    /// The service over the shared state.
    pub(crate) fn new(state: Arc<ServiceState>) -> Self {
        Self { state }
    }
}

/// Milliseconds since the Unix epoch.
pub(super) fn now_unix_ms() -> i64 {
    SystemTime::now()
        .duration_since(UNIX_EPOCH)
        .map_or(0, |d| i64::try_from(d.as_millis()).unwrap_or(i64::MAX))
}

/// Runs blocking work (redb, the SVD) on tokio's blocking pool.
pub(super) async fn blocking<T: Send + 'static>(
    f: impl FnOnce() -> Result<T, ServerError> + Send + 'static,
) -> Result<T, ServerError> {
    tokio::task::spawn_blocking(f)
        .await
        .map_err(|e| ServerError::Internal(format!("a blocking task failed: {e}")))?
}

/// The status of a failed request; failures of the server itself are logged as errors, refusals at debug level.
pub(super) fn status(rpc: &'static str, e: ServerError) -> Status {
    match &e {
        ServerError::Storage(_) | ServerError::Internal(_) => error!(rpc, error = %e, "request failed"),
        _ => debug!(rpc, error = %e, "request refused"),
    }
    e.into()
}

/// Renames the engine's field paths to the request's: `dmp.K[0]` is `parameters.k[0]`, `demonstration.x[3][1]`
/// (row 3, coordinate 1) is `demonstration.positions[3][1]`.
fn learn_field(e: ServerError) -> ServerError {
    match e {
        ServerError::InvalidArgument { field, reason } => {
            let field = [
                ("dmp.K", "parameters.k"),
                ("dmp.D", "parameters.d"),
                ("dmp.", "parameters."),
                ("demonstration.x", "demonstration.positions"),
            ]
            .iter()
            .find_map(|(from, to)| field.strip_prefix(from).map(|rest| format!("{to}{rest}")))
            .unwrap_or(field);
            ServerError::InvalidArgument { field, reason }
        }
        other => other,
    }
}

/// The error with `prefix.` in front of its field, unless the field already starts with `prefix`.
fn prefix_field_once(prefix: &str, e: ServerError) -> ServerError {
    match &e {
        ServerError::InvalidArgument { field, .. } if field.starts_with(prefix) => e,
        _ => e.within(prefix),
    }
}

impl PrimitiveServiceImpl {
    async fn handle_learn(
        &self,
        caller: &Caller,
        req: v1::LearnRequest,
    ) -> Result<v1::LearnResponse, ServerError> {
        check_name("robot_id", &req.robot_id)?;
        check_name("name", &req.name)?;
        caller.check(&Action::WritePrimitive { robot: &req.robot_id })?;
        let limits = &self.state.config.limits;
        let demo =
            req.demonstration.as_ref().ok_or_else(|| ServerError::invalid("demonstration", "is required"))?;
        let config = learn_config_from_proto(req.parameters.as_ref(), limits)?;
        let cells = demo.t.len().saturating_mul(config.n_basis + 1);
        if cells > MAX_LEARN_CELLS {
            return Err(ServerError::ResourceExhausted(format!(
                "demonstration.t: {} samples x {} Gaussians is more than the limit of {MAX_LEARN_CELLS} \
                 (use fewer samples or a smaller parameters.n_basis)",
                demo.t.len(),
                config.n_basis + 1
            )));
        }
        let orientations = dmp_proto::learning::orientations_from_proto(demo).map_err(ServerError::from)?;
        let demo = demonstration_from_proto(demo, limits).map_err(learn_field)?;
        let (samples, dim) = (demo.times().len(), demo.dim() + if orientations.is_some() { 3 } else { 0 });
        // The least squares of samples x (N + 1) Gaussians, and the forcing targets in every dimension.
        let (s, b) = (samples as f64, (config.n_basis + 1) as f64);
        let _budget =
            self.state.runs.compute.admission.batch(s * b * b + s * b * dim as f64, "demonstration")?;
        let store = self.state.store.clone();
        let (robot_id, name) = (req.robot_id, req.name);
        let limits = limits.clone();
        // On the batch pool: dropping this future (the client cancelled, left or passed its deadline) skips it, or
        // keeps what it learned from being stored.
        let record = self
            .state
            .runs
            .compute
            .batch
            .run(move |job| {
                let learned = match &orientations {
                    Some(o) => dmp::orientation::pose::learn_pose(&demo, o, &config),
                    None => dmp::learn(&demo, &config),
                };
                let primitive = learned.map_err(|e| match e {
                    dmp::DmpError::Learning(reason) => ServerError::invalid("demonstration", reason),
                    other => learn_field(other.into()),
                })?;
                // What is stored must be usable: the same ranges as a Put (a demonstration too fast for its
                // stiffness can need weights beyond them).
                primitive_from_proto(&dmp_proto::primitive::primitive_to_proto(&primitive), &limits).map_err(|e| {
                    ServerError::invalid(
                        "demonstration",
                        format!("the primitive learned from it is outside the accepted ranges ({e}): use a slower \
                             demonstration or a larger parameters.k"),
                    )
                })?;
                if job.cancelled() {
                    return Err(ServerError::Cancelled(
                        "the client left before the primitive was stored".into(),
                    ));
                }
                store.put(&robot_id, &name, &primitive, now_unix_ms())
            })
            .await
            .map_err(|e| ServerError::Internal(e.to_string()))??;
        if let Some(r) = &self.state.replicator {
            r.publish(&record).await;
        }
        info!(robot = %record.robot_id, name = %record.name, version = record.version, samples, dim, "learned");
        audit!(caller, "learn", robot = %record.robot_id, name = %record.name, version = record.version);
        Ok(v1::LearnResponse { record: Some(record) })
    }

    async fn handle_put(
        &self,
        caller: &Caller,
        req: v1::PutPrimitiveRequest,
    ) -> Result<v1::LearnResponse, ServerError> {
        check_name("robot_id", &req.robot_id)?;
        check_name("name", &req.name)?;
        caller.check(&Action::WritePrimitive { robot: &req.robot_id })?;
        let proto = req.primitive.as_ref().ok_or_else(|| ServerError::invalid("primitive", "is required"))?;
        let primitive = primitive_from_proto(proto, &self.state.config.limits)
            .map_err(|e| prefix_field_once("primitive", e))?;
        let store = self.state.store.clone();
        let (robot_id, name) = (req.robot_id, req.name);
        let record = blocking(move || store.put(&robot_id, &name, &primitive, now_unix_ms())).await?;
        if let Some(r) = &self.state.replicator {
            r.publish(&record).await;
        }
        info!(robot = %record.robot_id, name = %record.name, version = record.version, "stored");
        audit!(caller, "put", robot = %record.robot_id, name = %record.name, version = record.version);
        Ok(v1::LearnResponse { record: Some(record) })
    }

    async fn handle_get(
        &self,
        caller: &Caller,
        req: v1::GetPrimitiveRequest,
    ) -> Result<v1::PrimitiveRecord, ServerError> {
        check_name("robot_id", &req.robot_id)?;
        check_name("name", &req.name)?;
        caller.check(&Action::ReadPrimitive { robot: &req.robot_id })?;
        let store = self.state.store.clone();
        let record = blocking(move || store.get(&req.robot_id, &req.name, req.version)).await?;
        debug!(robot = %record.robot_id, name = %record.name, version = record.version, "read");
        Ok(record)
    }

    /// A listing's page: where it starts (after the `token`, a name, checked; empty: from the start) and how many
    /// entries it holds (`size`, 0 for the default, within the server's limit).
    fn page(&self, token: String, size: u32) -> Result<(Option<String>, usize), ServerError> {
        let after = (!token.is_empty()).then_some(token);
        if let Some(token) = &after {
            check_name("page_token", token)?;
        }
        let limits = &self.state.config.limits;
        let page_size = match size as usize {
            0 => limits.list_page_size,
            n => n,
        }
        .clamp(1, limits.max_list_page_size.max(1));
        Ok((after, page_size))
    }

    async fn handle_list(
        &self,
        caller: &Caller,
        req: v1::ListPrimitivesRequest,
    ) -> Result<v1::ListPrimitivesResponse, ServerError> {
        check_name("robot_id", &req.robot_id)?;
        caller.check(&Action::ReadPrimitive { robot: &req.robot_id })?;
        // The token is the last name of the previous page.
        let (after, page_size) = self.page(req.page_token, req.page_size)?;
        let store = self.state.store.clone();
        let robot_id = req.robot_id.clone();
        let (records, next) =
            blocking(move || store.list_page(&robot_id, after.as_deref(), page_size)).await?;
        debug!(robot = %req.robot_id, count = records.len(), more = next.is_some(), "listed");
        Ok(v1::ListPrimitivesResponse { records, next_page_token: next.unwrap_or_default() })
    }

    async fn handle_list_robots(
        &self,
        caller: &Caller,
        req: v1::ListRobotsRequest,
    ) -> Result<v1::ListRobotsResponse, ServerError> {
        // The token is the last robot of the previous page.
        let (after, page_size) = self.page(req.page_token, req.page_size)?;
        let store = self.state.store.clone();
        // Only the robots whose primitives the caller may read: the others are not even named.
        let reader = caller.clone();
        let visible = move |robot: &str| reader.check(&Action::ReadPrimitive { robot }).is_ok();
        let (robots, next) =
            blocking(move || store.list_robots_page(after.as_deref(), page_size, visible)).await?;
        debug!(count = robots.len(), more = next.is_some(), identity = %caller.name(), "listed robots");
        Ok(v1::ListRobotsResponse { robots, next_page_token: next.unwrap_or_default() })
    }

    async fn handle_delete(
        &self,
        caller: &Caller,
        req: v1::DeletePrimitiveRequest,
    ) -> Result<v1::DeletePrimitiveResponse, ServerError> {
        check_name("robot_id", &req.robot_id)?;
        check_name("name", &req.name)?;
        caller.check(&Action::DeletePrimitive { robot: &req.robot_id })?;
        let store = self.state.store.clone();
        let (robot_id, name) = (req.robot_id.clone(), req.name.clone());
        let deleted = blocking(move || store.delete_versions(&robot_id, &name)).await?;
        if let (Some(r), Some(t)) = (&self.state.replicator, &deleted.tombstone) {
            r.publish_delete(t).await;
        }
        let versions_deleted = deleted.versions;
        info!(robot = %req.robot_id, name = %req.name, versions = versions_deleted, "deleted");
        audit!(caller, "delete", robot = %req.robot_id, name = %req.name, versions = versions_deleted);
        Ok(v1::DeletePrimitiveResponse { versions_deleted })
    }
}

#[tonic::async_trait]
impl PrimitiveService for PrimitiveServiceImpl {
    async fn learn(&self, request: Request<v1::LearnRequest>) -> Result<Response<v1::LearnResponse>, Status> {
        let caller = self.state.caller(&request).map_err(|e| status("learn", e))?;
        self.handle_learn(&caller, request.into_inner())
            .await
            .map(Response::new)
            .map_err(|e| status("learn", e))
    }

    async fn put(
        &self,
        request: Request<v1::PutPrimitiveRequest>,
    ) -> Result<Response<v1::LearnResponse>, Status> {
        let caller = self.state.caller(&request).map_err(|e| status("put", e))?;
        self.handle_put(&caller, request.into_inner()).await.map(Response::new).map_err(|e| status("put", e))
    }

    async fn get(
        &self,
        request: Request<v1::GetPrimitiveRequest>,
    ) -> Result<Response<v1::PrimitiveRecord>, Status> {
        let caller = self.state.caller(&request).map_err(|e| status("get", e))?;
        self.handle_get(&caller, request.into_inner()).await.map(Response::new).map_err(|e| status("get", e))
    }

    async fn list_robots(
        &self,
        request: Request<v1::ListRobotsRequest>,
    ) -> Result<Response<v1::ListRobotsResponse>, Status> {
        let caller = self.state.caller(&request).map_err(|e| status("list_robots", e))?;
        self.handle_list_robots(&caller, request.into_inner())
            .await
            .map(Response::new)
            .map_err(|e| status("list_robots", e))
    }

    async fn list(
        &self,
        request: Request<v1::ListPrimitivesRequest>,
    ) -> Result<Response<v1::ListPrimitivesResponse>, Status> {
        let caller = self.state.caller(&request).map_err(|e| status("list", e))?;
        self.handle_list(&caller, request.into_inner())
            .await
            .map(Response::new)
            .map_err(|e| status("list", e))
    }

    async fn delete(
        &self,
        request: Request<v1::DeletePrimitiveRequest>,
    ) -> Result<Response<v1::DeletePrimitiveResponse>, Status> {
        let caller = self.state.caller(&request).map_err(|e| status("delete", e))?;
        self.handle_delete(&caller, request.into_inner())
            .await
            .map(Response::new)
            .map_err(|e| status("delete", e))
    }
}

#[cfg(test)]
mod tests {
    use tonic::Code;

    use super::*;
    use crate::config::Config;
    use dmp_proto::primitive::primitive_to_proto;

    fn service(dir: &std::path::Path) -> PrimitiveServiceImpl {
        PrimitiveServiceImpl::new(Arc::new(ServiceState::for_tests(dir, Default::default())))
    }

    /// A 2-D curve sampled at 100 non-uniform times.
    fn demonstration() -> v1::Demonstration {
        let t: Vec<f64> = (0..100).map(|i| f64::from(i) / 99.0 + 0.001 * f64::from(i % 3)).collect();
        let positions = t.iter().flat_map(|t| [t * t, (3.0 * t).sin()]).collect();
        v1::Demonstration { t, positions, dim: 2, ..Default::default() }
    }

    fn learn_request(robot: &str, name: &str) -> Request<v1::LearnRequest> {
        Request::new(v1::LearnRequest {
            robot_id: robot.into(),
            name: name.into(),
            demonstration: Some(demonstration()),
            parameters: None,
        })
    }

    fn refused<T: std::fmt::Debug>(r: Result<T, Status>, code: Code, names: &str) {
        let s = r.unwrap_err();
        assert_eq!(s.code(), code, "{s:?}");
        assert!(s.message().contains(names), "`{}` does not name `{names}`", s.message());
    }

    #[tokio::test]
    async fn learn_get_list_delete() {
        let dir = tempfile::tempdir().unwrap();
        let svc = service(dir.path());
        let first = svc.learn(learn_request("r1", "wave")).await.unwrap().into_inner().record.unwrap();
        assert_eq!((first.version, first.primitive.as_ref().unwrap().dim), (1, 2));
        let second = svc.learn(learn_request("r1", "wave")).await.unwrap().into_inner().record.unwrap();
        assert_eq!(second.version, 2);
        svc.learn(learn_request("r1", "reach")).await.unwrap();

        let get = |version| v1::GetPrimitiveRequest { robot_id: "r1".into(), name: "wave".into(), version };
        assert_eq!(PrimitiveService::get(&svc, Request::new(get(0))).await.unwrap().into_inner(), second);
        assert_eq!(PrimitiveService::get(&svc, Request::new(get(1))).await.unwrap().into_inner(), first);
        refused(PrimitiveService::get(&svc, Request::new(get(7))).await, Code::NotFound, "version 7");

        let list = svc
            .list(Request::new(v1::ListPrimitivesRequest { robot_id: "r1".into(), ..Default::default() }))
            .await
            .unwrap();
        let names: Vec<_> = list.get_ref().records.iter().map(|r| (r.name.as_str(), r.version)).collect();
        assert_eq!(names, [("reach", 1), ("wave", 2)]);

        let del = || Request::new(v1::DeletePrimitiveRequest { robot_id: "r1".into(), name: "wave".into() });
        assert_eq!(svc.delete(del()).await.unwrap().into_inner().versions_deleted, 2);
        refused(svc.delete(del()).await, Code::NotFound, "wave");
        refused(PrimitiveService::get(&svc, Request::new(get(0))).await, Code::NotFound, "wave");
    }

    #[tokio::test]
    async fn a_put_primitive_comes_back_bit_for_bit() {
        let dir = tempfile::tempdir().unwrap();
        let svc = service(dir.path());
        let mut p = dmp::Primitive::straight_line(
            10,
            4.0,
            vec![1050.0; 3],
            None,
            2.5,
            vec![0.1, 0.2, 0.3],
            vec![1.0; 3],
        )
        .unwrap();
        p.weights[1][3] = std::f64::consts::E * 1e-7;
        let put = v1::PutPrimitiveRequest {
            robot_id: "panda".into(),
            name: "line".into(),
            primitive: Some(primitive_to_proto(&p)),
        };
        let rec = svc.put(Request::new(put)).await.unwrap().into_inner().record.unwrap();
        let got = PrimitiveService::get(
            &svc,
            Request::new(v1::GetPrimitiveRequest {
                robot_id: "panda".into(),
                name: "line".into(),
                version: rec.version,
            }),
        )
        .await
        .unwrap()
        .into_inner();
        let back = primitive_from_proto(got.primitive.as_ref().unwrap(), &Config::default().limits).unwrap();
        assert_eq!(back, p);
    }

    #[tokio::test]
    async fn bad_requests_name_the_field() {
        let dir = tempfile::tempdir().unwrap();
        let svc = service(dir.path());
        refused(svc.learn(learn_request("a/b", "x")).await, Code::InvalidArgument, "robot_id");
        refused(svc.learn(learn_request("r", "")).await, Code::InvalidArgument, "name");

        let mut req = learn_request("r", "x");
        req.get_mut().demonstration = None;
        refused(svc.learn(req).await, Code::InvalidArgument, "demonstration");

        let mut req = learn_request("r", "x");
        req.get_mut().demonstration.as_mut().unwrap().positions.pop();
        refused(svc.learn(req).await, Code::InvalidArgument, "demonstration.positions");

        let mut req = learn_request("r", "x");
        req.get_mut().demonstration.as_mut().unwrap().positions[7] = f64::NAN;
        refused(svc.learn(req).await, Code::InvalidArgument, "demonstration.positions[3][1]");

        let mut req = learn_request("r", "x");
        req.get_mut().demonstration.as_mut().unwrap().t.swap(4, 5);
        refused(svc.learn(req).await, Code::InvalidArgument, "demonstration.t[5]");

        let mut req = learn_request("r", "x");
        req.get_mut().parameters = Some(v1::LearnParameters { k: vec![1.0, 2.0, 3.0], ..Default::default() });
        refused(svc.learn(req).await, Code::InvalidArgument, "parameters.k");

        let mut req = learn_request("r", "x");
        req.get_mut().parameters = Some(v1::LearnParameters { n_basis: 100_000, ..Default::default() });
        refused(svc.learn(req).await, Code::InvalidArgument, "parameters.n_basis");

        let mut req = learn_request("r", "x");
        let demo = req.get_mut().demonstration.as_mut().unwrap();
        demo.t = (0..200_000).map(f64::from).collect();
        demo.positions = vec![0.0; 400_000];
        req.get_mut().parameters = Some(v1::LearnParameters { n_basis: 1000, ..Default::default() });
        refused(svc.learn(req).await, Code::ResourceExhausted, "demonstration.t");

        let mut bad = primitive_to_proto(
            &dmp::Primitive::straight_line(5, 4.0, vec![1050.0], None, 1.0, vec![0.0], vec![1.0]).unwrap(),
        );
        bad.weights.pop();
        let put = |p: v1::Primitive| {
            Request::new(v1::PutPrimitiveRequest {
                robot_id: "r".into(),
                name: "x".into(),
                primitive: Some(p),
            })
        };
        refused(svc.put(put(bad.clone())).await, Code::InvalidArgument, "primitive.weights");
        bad.weights.push(0.0);
        bad.format_version = 99;
        refused(svc.put(put(bad)).await, Code::InvalidArgument, "primitive: primitive format version 99");

        refused(
            svc.list(Request::new(v1::ListPrimitivesRequest {
                robot_id: String::new(),
                ..Default::default()
            }))
            .await,
            Code::InvalidArgument,
            "robot_id",
        );
        // Nothing was stored by any of them.
        assert!(svc.state.store.list("r").unwrap().is_empty());
    }
}
