//! A session (`MotionService.Session`) once open: its sender of commands and measured states, and its stream of
//! segments. [`crate::grpc::DmpClient::session`] opens one.

use std::fmt;
use std::pin::Pin;

use dmp_proto::v1;
use dmp_proto::v1::session_request::Message;
use tokio::sync::mpsc;
use tokio_stream::{Stream, StreamExt};

use crate::error::ClientError;
use crate::streams::SegmentStream;

/// The sending half of a session: commands and measured states. Cloneable; a send fails once the session ended.
#[derive(Debug, Clone)]
pub struct SessionSender {
    pub(crate) tx: mpsc::Sender<v1::SessionRequest>,
}

impl SessionSender {
    /// Sends one message.
    pub async fn send(&self, message: Message) -> Result<(), ClientError> {
        self.tx
            .send(v1::SessionRequest { message: Some(message) })
            .await
            .map_err(|_| ClientError::Closed("the session".into()))
    }

    /// Changes the goal, from the current state.
    pub async fn set_goal(&self, goal: Vec<f64>) -> Result<(), ClientError> {
        self.send(Message::SetGoal(v1::SetGoal { goal, ..Default::default() })).await
    }

    /// Changes a pose run's goal, from the current state: the position (empty keeps it) and the orientation
    /// (`[x, y, z, w]`; `None` keeps it).
    pub async fn set_pose_goal(
        &self,
        goal: Vec<f64>,
        orientation: Option<[f64; 4]>,
    ) -> Result<(), ClientError> {
        let goal_orientation = orientation.map(|q| q.to_vec()).unwrap_or_default();
        self.send(Message::SetGoal(v1::SetGoal { goal, goal_orientation })).await
    }

    /// Changes tau (larger is slower), from the current state.
    pub async fn set_tau(&self, tau: f64) -> Result<(), ClientError> {
        self.send(Message::SetTau(v1::SetTau { tau })).await
    }

    /// Holds position.
    pub async fn pause(&self) -> Result<(), ClientError> {
        self.send(Message::Pause(v1::Pause {})).await
    }

    /// Resumes after a pause.
    pub async fn resume(&self) -> Result<(), ClientError> {
        self.send(Message::Resume(v1::Resume {})).await
    }

    /// Ends the run: the robot decelerates to rest and the stream closes.
    pub async fn stop(&self) -> Result<(), ClientError> {
        self.send(Message::Stop(v1::Stop {})).await
    }

    /// Reports the robot's measured state.
    pub async fn state(&self, state: v1::RobotState) -> Result<(), ClientError> {
        self.send(Message::State(state)).await
    }
}

/// An open session: a [`SessionSender`] and the stream of segments. Dropping both ends the call.
pub struct Session {
    pub(crate) sender: SessionSender,
    pub(crate) segments: SegmentStream,
}

impl fmt::Debug for Session {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("Session").field("sender", &self.sender).finish_non_exhaustive()
    }
}

impl Session {
    /// A sender of commands (clone it to command from another task).
    pub fn sender(&self) -> SessionSender {
        self.sender.clone()
    }

    /// The next segment; `None` once the server closed the stream.
    pub async fn next_segment(&mut self) -> Option<Result<v1::Segment, ClientError>> {
        self.segments.next().await
    }

    /// The two halves.
    pub fn into_parts(self) -> (SessionSender, SegmentStream) {
        (self.sender, self.segments)
    }

    /// Changes the goal.
    pub async fn set_goal(&self, goal: Vec<f64>) -> Result<(), ClientError> {
        self.sender.set_goal(goal).await
    }

    /// Changes a pose run's goal ([`SessionSender::set_pose_goal`]).
    pub async fn set_pose_goal(
        &self,
        goal: Vec<f64>,
        orientation: Option<[f64; 4]>,
    ) -> Result<(), ClientError> {
        self.sender.set_pose_goal(goal, orientation).await
    }

    /// Changes tau.
    pub async fn set_tau(&self, tau: f64) -> Result<(), ClientError> {
        self.sender.set_tau(tau).await
    }

    /// Holds position.
    pub async fn pause(&self) -> Result<(), ClientError> {
        self.sender.pause().await
    }

    /// Resumes.
    pub async fn resume(&self) -> Result<(), ClientError> {
        self.sender.resume().await
    }

    /// Stops.
    pub async fn stop(&self) -> Result<(), ClientError> {
        self.sender.stop().await
    }

    /// Reports the measured state.
    pub async fn state(&self, state: v1::RobotState) -> Result<(), ClientError> {
        self.sender.state(state).await
    }
}

impl Stream for Session {
    type Item = Result<v1::Segment, ClientError>;

    fn poll_next(
        mut self: Pin<&mut Self>,
        cx: &mut std::task::Context<'_>,
    ) -> std::task::Poll<Option<Self::Item>> {
        self.segments.as_mut().poll_next(cx)
    }
}
