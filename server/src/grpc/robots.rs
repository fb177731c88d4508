//! `RobotService`: put, read and delete each robot's record (its limits, footprint and tool), the defaults of its
//! motion requests (`motion_resolve.rs` applies them).
//!
//! Who may put or delete a robot's record is who may write or delete its primitives, who may read it who may read
//! them. A put is validated first (an InvalidArgument status names the field, under `robot.`), then stored in one
//! durable redb transaction (`store/robots.rs`).

use std::sync::Arc;

use dmp_proto::keys::check_name;
use dmp_proto::shape::superquadric_to_shape;
use dmp_proto::v1;
use dmp_proto::v1::robot_service_server::RobotService;
use tonic::{Request, Response, Status};
use tracing::{debug, info};

use super::limits_in_force::{check_limits, check_margin};
use super::primitives::{blocking, now_unix_ms, status};
use super::tool::tool_from_proto;
use crate::access::{Action, Caller};
use crate::audit;
use crate::config::RequestLimits;
use crate::error::ServerError;
use crate::grpc::shared::ServiceState;

/// The gRPC robot service.
#[derive(Debug, Clone)]
pub(crate) struct RobotServiceImpl {
    /// What every service shares (the store and the limits here).
    pub state: Arc<ServiceState>,
}

impl RobotServiceImpl {
    /// The service over the shared state.
    pub(crate) fn new(state: Arc<ServiceState>) -> Self {
        Self { state }
    }
}

/// The record to store for `r`, every field checked against the same rules as a motion request's (errors name
/// `robot.*`), stamped `now_unix_ms`.
pub(crate) fn checked_record(
    r: &v1::RobotRecord,
    limits: &RequestLimits,
    now_unix_ms: i64,
) -> Result<v1::RobotRecord, ServerError> {
    check_name("robot.robot_id", &r.robot_id)?;
    if let Some(l) = &r.limits {
        check_limits(l, "robot.limits")?;
    }
    check_margin(r.margin, "robot.margin")?;
    if let Some(f) = &r.footprint {
        if f.semi_axes.len() > limits.max_dim {
            return Err(ServerError::invalid(
                "robot.footprint.semi_axes",
                format!(
                    "at most {} dimensions (the server's limits.max_dim), found {}",
                    limits.max_dim,
                    f.semi_axes.len()
                ),
            ));
        }
        superquadric_to_shape(f).map_err(|e| ServerError::from(e).within("robot.footprint"))?;
    }
    if let Some(t) = &r.tool {
        tool_from_proto(t, "robot.tool")?;
    }
    Ok(v1::RobotRecord { updated_unix_ms: now_unix_ms, ..r.clone() })
}

impl RobotServiceImpl {
    async fn handle_put(
        &self,
        caller: &Caller,
        req: v1::PutRobotRequest,
    ) -> Result<v1::RobotRecord, ServerError> {
        let robot = req.robot.as_ref().ok_or_else(|| ServerError::invalid("robot", "is required"))?;
        check_name("robot.robot_id", &robot.robot_id)?;
        caller.check(&Action::WritePrimitive { robot: &robot.robot_id })?;
        let record = checked_record(robot, &self.state.config.limits, now_unix_ms())?;
        let store = self.state.store.clone();
        let stored = record.clone();
        blocking(move || store.put_robot(&stored)).await?;
        let (l, tool) = (record.limits.unwrap_or_default(), record.tool.is_some());
        info!(robot = %record.robot_id, max_speed = l.max_speed, footprint = record.footprint.is_some(), tool, "robot stored");
        audit!(caller, "put_robot", robot = %record.robot_id, max_speed = l.max_speed,
            max_acceleration = l.max_acceleration, max_jerk = l.max_jerk, tool);
        Ok(record)
    }

    async fn handle_get(
        &self,
        caller: &Caller,
        req: v1::GetRobotRequest,
    ) -> Result<v1::RobotRecord, ServerError> {
        check_name("robot_id", &req.robot_id)?;
        caller.check(&Action::ReadPrimitive { robot: &req.robot_id })?;
        let store = self.state.store.clone();
        let id = req.robot_id.clone();
        let record = blocking(move || store.get_robot(&id))
            .await?
            .ok_or_else(|| ServerError::NotFound(format!("robot `{}` has no record", req.robot_id)))?;
        debug!(robot = %record.robot_id, "robot read");
        Ok(record)
    }

    async fn handle_delete(
        &self,
        caller: &Caller,
        req: v1::DeleteRobotRequest,
    ) -> Result<v1::DeleteRobotResponse, ServerError> {
        check_name("robot_id", &req.robot_id)?;
        caller.check(&Action::DeletePrimitive { robot: &req.robot_id })?;
        let store = self.state.store.clone();
        let id = req.robot_id.clone();
        blocking(move || store.delete_robot(&id)).await?;
        info!(robot = %req.robot_id, "robot deleted");
        audit!(caller, "delete_robot", robot = %req.robot_id);
        Ok(v1::DeleteRobotResponse {})
    }
}

#[tonic::async_trait]
impl RobotService for RobotServiceImpl {
    async fn put_robot(
        &self,
        request: Request<v1::PutRobotRequest>,
    ) -> Result<Response<v1::RobotRecord>, Status> {
        let caller = self.state.caller(&request).map_err(|e| status("put_robot", e))?;
        self.handle_put(&caller, request.into_inner())
            .await
            .map(Response::new)
            .map_err(|e| status("put_robot", e))
    }

    async fn get_robot(
        &self,
        request: Request<v1::GetRobotRequest>,
    ) -> Result<Response<v1::RobotRecord>, Status> {
        let caller = self.state.caller(&request).map_err(|e| status("get_robot", e))?;
        self.handle_get(&caller, request.into_inner())
            .await
            .map(Response::new)
            .map_err(|e| status("get_robot", e))
    }

    async fn delete_robot(
        &self,
        request: Request<v1::DeleteRobotRequest>,
    ) -> Result<Response<v1::DeleteRobotResponse>, Status> {
        let caller = self.state.caller(&request).map_err(|e| status("delete_robot", e))?;
        self.handle_delete(&caller, request.into_inner())
            .await
            .map(Response::new)
            .map_err(|e| status("delete_robot", e))
    }
}
