//! The robot records (`RobotService`): each robot's limits, footprint and tool, the defaults of its motions.

use dmp_proto::limits::limits_to_proto;
use dmp_proto::v1;

use super::DmpClient;
use crate::ClientError;

impl DmpClient {
    /// Stores the record of `record.robot_id` (replacing the one before); returns it as stored.
    pub async fn put_robot(&self, record: v1::RobotRecord) -> Result<v1::RobotRecord, ClientError> {
        let request = v1::PutRobotRequest { robot: Some(record) };
        Ok(self.robots.clone().put_robot(request).await?.into_inner())
    }

    /// Stores a record of `robot` with `limits` and nothing else (no footprint, no tool).
    pub async fn put_robot_limits(
        &self,
        robot: &str,
        limits: &dmp::Limits,
    ) -> Result<v1::RobotRecord, ClientError> {
        self.put_robot(v1::RobotRecord {
            robot_id: robot.into(),
            limits: Some(limits_to_proto(limits)),
            ..Default::default()
        })
        .await
    }

    /// The record of `robot` (a NotFound error when it has none).
    pub async fn get_robot(&self, robot: &str) -> Result<v1::RobotRecord, ClientError> {
        let request = v1::GetRobotRequest { robot_id: robot.into() };
        Ok(self.robots.clone().get_robot(request).await?.into_inner())
    }

    /// Deletes the record of `robot` (its primitives stay).
    pub async fn delete_robot(&self, robot: &str) -> Result<(), ClientError> {
        let request = v1::DeleteRobotRequest { robot_id: robot.into() };
        self.robots.clone().delete_robot(request).await?;
        Ok(())
    }
}
