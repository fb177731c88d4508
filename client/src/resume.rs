//! A session that survives its server (feature `zenoh`): when the stream fails with UNAVAILABLE (the server shut
//! down, or gave the cell back after a fail-over) or a transport error (the server died), it finds the cell's
//! server again through Zenoh ([`crate::discovery::resolve_cell`]), opens a new session there with the same
//! motion, and goes on from the robot's last commanded state.
//!
//! A server that freezes or is cut off without closing its connection is noticed when no segment came for
//! [`ResumeOptions::stall_timeout`], and its cells fail over once Zenoh's lease expires (`deploy/zenoh-lease.json5`).
//!
//! **Continuity.** The new session starts where the last setpoint received was and as fast
//! (`MotionSpec.start`, `MotionSpec.start_velocity`), and its first `state` message reports that state, so that
//! the cell sees the robot at once. Its segments are shifted onto the first session's timeline: their run times
//! start at the last setpoint's (the first point of the new session, the same state, supersedes it, as
//! [`crate::Setpoints`] expects), and their sequence numbers go on from the last. The phase of the primitive starts
//! over: the rest of the motion is the primitive replayed from where the robot is to the goal (the last goal and
//! `tau` set through this session). A pose run resumes from the last orientation received, at rest in rotation;
//! groups are not resumed.
//!
//! **The same primitive.** A request for the latest version is pinned, when the session opens, to the version
//! that is the latest then: every resumption runs it, even if another is learned meanwhile or the server resumed on
//! has not caught up with a newer one.
//!
//! **Commands survive.** A session paused when its server went is resumed paused, and a stopped one stopped: the
//! new server brings the robot to rest from the state it had, and never sets it moving towards the goal again.
//!
//! **Bounds.** At most [`ResumeOptions::max_attempts`] attempts within [`ResumeOptions::max_total`] for one
//! resumption, waiting [`ResumeOptions::retry_delay`] (doubling, up to 16 times as long) between attempts, and at
//! most [`ResumeOptions::max_resumes`] resumptions within [`ResumeOptions::resume_window`] (a server that keeps failing
//! the stream is not chased forever; a session that runs all day may fail over any number of times); then the stream ends with [`ClientError::Resume`],
//! naming the attempts, the time spent and the last failure. Only a server or a route that went away is resumed
//! from (UNAVAILABLE, a transport error, a stall); anything else the server says ends the stream at once, as it
//! would a plain session (a run that diverged, an internal error, bad input, a denied permission, a robot taken
//! over by another stream).

use std::time::{Duration, Instant};

use dmp_proto::v1;
use dmp_proto::v1::session_request::Message;
use tokio_stream::StreamExt;

use crate::connect::ConnectOptions;
use crate::discovery::resolve_cell;
use crate::error::ClientError;
use crate::grpc::{DmpClient, SegmentStream, Session};

/// How hard a [`ResumableSession`] tries.
#[derive(Debug, Clone)]
pub struct ResumeOptions {
    /// Attempts per resumption (resolve, connect, open), at least 1.
    pub max_attempts: u32,
    /// The longest one resumption may take, all attempts together.
    pub max_total: Duration,
    /// The wait after a failed attempt, doubled after each up to 16 times as long.
    pub retry_delay: Duration,
    /// How long each resolution waits for the servers' answers.
    pub resolve_timeout: Duration,
    /// How to connect to a server (TLS, token); its timeout bounds each connection.
    pub connect: ConnectOptions,
    /// No segment for this long: the server is taken as gone (frozen, or cut off without its connection
    /// closing) and the session resumes. None: wait as long as the connection lasts (HTTP/2 keep-alive).
    /// (At least twice the request's `segment_s`, so that long segments are not taken for a stall.)
    pub stall_timeout: Option<Duration>,
    /// Resumptions within [`ResumeOptions::resume_window`], at least 1: a server that keeps failing the stream is
    /// not chased forever.
    pub max_resumes: u32,
    /// The window [`ResumeOptions::max_resumes`] counts in.
    pub resume_window: Duration,
}

impl Default for ResumeOptions {
    fn default() -> Self {
        Self {
            max_attempts: 50,
            max_total: Duration::from_secs(10),
            retry_delay: Duration::from_millis(10),
            resolve_timeout: Duration::from_millis(500),
            connect: ConnectOptions { timeout: Duration::from_secs(2), ..Default::default() },
            stall_timeout: Some(Duration::from_millis(500)),
            max_resumes: 20,
            resume_window: Duration::from_secs(60),
        }
    }
}

/// The last setpoint received, on the session's timeline.
#[derive(Debug, Clone, PartialEq)]
struct Setpoint {
    t: f64,
    position: Vec<f64>,
    velocity: Vec<f64>,
    /// A pose run's orientation, x, y, z, w.
    orientation: Option<Vec<f64>>,
}

/// The session's timeline across resumptions: each new session's run times start at the setpoint it resumed from,
/// and its sequence numbers after the last one received.
#[derive(Debug, Clone, Default)]
struct Timeline {
    last: Option<Setpoint>,
    last_sequence: Option<u64>,
    /// Added to the current session's run times and sequence numbers.
    time_offset: f64,
    sequence_offset: u64,
}

impl Timeline {
    /// Shifts `seg` of the current session onto the timeline and remembers its last point.
    fn shift(&mut self, mut seg: v1::Segment) -> v1::Segment {
        seg.start_time += self.time_offset;
        seg.sequence += self.sequence_offset;
        let d = seg.dim as usize;
        let n = seg.positions.len().checked_div(d).unwrap_or(0);
        if n > 0 && seg.velocities.len() == seg.positions.len() {
            let orientation =
                (seg.orientations.len() == 4 * n).then(|| seg.orientations[4 * (n - 1)..].to_vec());
            self.last = Some(Setpoint {
                t: seg.start_time + (n - 1) as f64 * seg.dt,
                position: seg.positions[(n - 1) * d..].to_vec(),
                velocity: seg.velocities[(n - 1) * d..].to_vec(),
                orientation,
            });
        }
        self.last_sequence = Some(seg.sequence);
        seg
    }

    /// A new session started from [`Timeline::last`] (or from the primitive's start when none came).
    fn resumed(&mut self) {
        if let Some(p) = &self.last {
            self.time_offset = p.t;
        }
        if let Some(s) = self.last_sequence {
            self.sequence_offset = s + 1;
        }
    }
}

/// A session (`MotionService.Session`) of one robot in a cell of a plant, resumed on another server when its
/// server goes. Open it with [`ResumableSession::open`], read it with [`ResumableSession::next_segment`].
pub struct ResumableSession {
    zenoh: zenoh::Session,
    options: ResumeOptions,
    /// The start request, with the last goal and tau set.
    request: v1::ExecuteRequest,
    cell: String,
    server: v1::PlantServer,
    session: Session,
    timeline: Timeline,
    resumes: u32,
    /// When the resumptions within the window were.
    recent_resumes: std::collections::VecDeque<Instant>,
    /// Paused through this session (kept if it resumes).
    paused: bool,
    /// Stopped through this session (kept if it resumes).
    stopped: bool,
}

impl std::fmt::Debug for ResumableSession {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("ResumableSession")
            .field("cell", &self.cell)
            .field("server", &self.server.server_id)
            .field("resumes", &self.resumes)
            .finish_non_exhaustive()
    }
}

/// Whether a failure of a running stream is worth a resumption: its server or the route to it went away (a
/// status of the server itself, e.g. a run that diverged, is the caller's to see).
fn resumable(e: &ClientError) -> bool {
    match e {
        ClientError::Status { code, .. } => matches!(code, tonic::Code::Unavailable | tonic::Code::Unknown),
        ClientError::Connect { .. } | ClientError::Closed(_) => true,
        _ => false,
    }
}

/// Whether a failure of an attempt to open the session is worth another attempt (the server or the route to it is
/// gone, or the cell is moving: not served yet, or no server answers for it yet), rather than the caller's to see.
fn retryable(e: &ClientError) -> bool {
    match e {
        ClientError::Status { code, .. } => matches!(
            code,
            tonic::Code::Unavailable
                | tonic::Code::Unknown
                | tonic::Code::Internal
                | tonic::Code::FailedPrecondition
                | tonic::Code::DeadlineExceeded
        ),
        ClientError::Connect { .. } | ClientError::Closed(_) | ClientError::Zenoh(_) => true,
        // No server answered for the cell (yet): its fail-over may not have happened.
        ClientError::Argument { field, .. } => field == "cell",
        ClientError::Protocol(_) | ClientError::Resume { .. } => false,
    }
}

impl ResumableSession {
    /// Finds the server of the robot's cell (`request.motion.cell`, which must be named) through `zenoh` and opens
    /// the session there, retrying as `options` say.
    pub async fn open(
        zenoh: &zenoh::Session,
        request: v1::ExecuteRequest,
        options: ResumeOptions,
    ) -> Result<Self, ClientError> {
        let motion = request.motion.as_ref().ok_or_else(|| ClientError::argument("motion", "is required"))?;
        if motion.cell.is_empty() {
            return Err(ClientError::argument("motion.cell", "must name the cell to find its server"));
        }
        let cell = motion.cell.clone();
        let mut request = request;
        let opener = Opener { zenoh, cell: &cell, options: &options };
        let (server, session) = opener.attempts(&mut request, None).await?;
        Ok(Self {
            zenoh: zenoh.clone(),
            options,
            request,
            cell,
            server,
            session,
            timeline: Timeline::default(),
            resumes: 0,
            recent_resumes: std::collections::VecDeque::new(),
            paused: false,
            stopped: false,
        })
    }

    /// The server serving the session now.
    pub fn server(&self) -> &v1::PlantServer {
        &self.server
    }

    /// How many times the session was resumed on a server.
    pub fn resumes(&self) -> u32 {
        self.resumes
    }

    /// The next segment, on the session's timeline; `None` once the run ended. A failure that a resumption
    /// cannot mend ends the stream with its error.
    pub async fn next_segment(&mut self) -> Option<Result<v1::Segment, ClientError>> {
        loop {
            let segment_s = self.request.segment_s.max(0.0);
            let stall =
                self.options.stall_timeout.map(|s| s.max(Duration::from_secs_f64(2.0 * segment_s.min(60.0))));
            let next = match stall {
                Some(stall) => {
                    tokio::time::timeout(stall, self.session.next_segment()).await.unwrap_or_else(|_| {
                        Some(Err(ClientError::Closed(format!(
                            "the session on server `{}` (no segment for {stall:?})",
                            self.server.server_id
                        ))))
                    })
                }
                None => self.session.next_segment().await,
            };
            match next {
                Some(Ok(seg)) => return Some(Ok(self.timeline.shift(seg))),
                Some(Err(e)) if resumable(&e) => {
                    let now = Instant::now();
                    let window = self.options.resume_window;
                    while self.recent_resumes.front().is_some_and(|t| now.duration_since(*t) > window) {
                        self.recent_resumes.pop_front();
                    }
                    if self.recent_resumes.len() >= self.options.max_resumes.max(1) as usize {
                        return Some(Err(ClientError::Resume {
                            cell: self.cell.clone(),
                            attempts: self.recent_resumes.len() as u32,
                            elapsed: self
                                .recent_resumes
                                .front()
                                .map_or(Duration::ZERO, |t| now.duration_since(*t)),
                            last: format!(
                                "resumed {} times within {window:?} already (max_resumes); the last failure: {e}",
                                self.recent_resumes.len()
                            ),
                        }));
                    }
                    self.recent_resumes.push_back(now);
                    if let Err(e) = self.resume().await {
                        return Some(Err(e));
                    }
                }
                other => return other,
            }
        }
    }

    /// Opens the session again on the cell's server, from the last setpoint.
    async fn resume(&mut self) -> Result<(), ClientError> {
        let from = self.timeline.last.clone();
        let mut request = self.request.clone();
        // The robot may still be held by the stream given up on (a server that only seemed gone).
        request.take_over = true;
        if let (Some(m), Some(p)) = (request.motion.as_mut(), &from) {
            m.start = p.position.clone();
            m.start_velocity = p.velocity.clone();
            if let Some(q) = &p.orientation {
                m.start_orientation = q.clone();
            }
        }
        let robot = request.motion.as_ref().map(|m| m.robot_id.clone()).unwrap_or_default();
        let state = from.as_ref().map(|p| v1::RobotState {
            robot_id: robot,
            stamp_unix_s: now_unix_s(),
            position: p.position.clone(),
            velocity: p.velocity.clone(),
            ..Default::default()
        });
        let opener = Opener { zenoh: &self.zenoh, cell: &self.cell, options: &self.options };
        let (server, session) = opener.attempts(&mut request, state).await?;
        self.server = server;
        self.session = session;
        self.timeline.resumed();
        self.resumes += 1;
        // What the robot was told goes on: a stopped robot comes to rest, a paused one holds.
        if self.stopped {
            self.session.stop().await?;
        } else if self.paused {
            self.session.pause().await?;
        }
        Ok(())
    }

    /// Sends a command or a measured state to the current server. Goals, taus, pauses and stops are kept if the
    /// session resumes.
    pub async fn send(&mut self, message: Message) -> Result<(), ClientError> {
        match &message {
            Message::SetGoal(g) => {
                if let Some(m) = self.request.motion.as_mut() {
                    if !g.goal.is_empty() {
                        m.goal = g.goal.clone();
                    }
                    if !g.goal_orientation.is_empty() {
                        m.goal_orientation = g.goal_orientation.clone();
                    }
                }
            }
            Message::SetTau(t) => {
                if let Some(m) = self.request.motion.as_mut() {
                    m.tau = t.tau;
                }
            }
            Message::Pause(_) => self.paused = true,
            Message::Resume(_) => self.paused = false,
            Message::Stop(_) => self.stopped = true,
            Message::Start(_) | Message::State(_) => {}
        }
        self.session.sender().send(message).await
    }

    /// Changes the goal (kept if the session resumes).
    pub async fn set_goal(&mut self, goal: Vec<f64>) -> Result<(), ClientError> {
        if let Some(m) = self.request.motion.as_mut() {
            m.goal = goal.clone();
        }
        self.session.set_goal(goal).await
    }

    /// Changes tau (kept if the session resumes).
    pub async fn set_tau(&mut self, tau: f64) -> Result<(), ClientError> {
        if let Some(m) = self.request.motion.as_mut() {
            m.tau = tau;
        }
        self.session.set_tau(tau).await
    }

    /// Holds the robot (the phase stops; kept if the session resumes).
    pub async fn pause(&mut self) -> Result<(), ClientError> {
        self.paused = true;
        self.session.pause().await
    }

    /// Goes on after a pause.
    pub async fn resume_motion(&mut self) -> Result<(), ClientError> {
        self.paused = false;
        self.session.resume().await
    }

    /// Ends the run: the robot decelerates to rest and the stream closes (a resumed session is stopped too).
    pub async fn stop(&mut self) -> Result<(), ClientError> {
        self.stopped = true;
        self.session.stop().await
    }
}

/// Where and how a session is opened: the cell, resolved through `zenoh`, within `options`.
struct Opener<'a> {
    zenoh: &'a zenoh::Session,
    cell: &'a str,
    options: &'a ResumeOptions,
}

impl Opener<'_> {
    /// Resolves the cell and opens the session, retrying within the bounds; sends `state` first when given. A
    /// request for the latest version of the primitive is pinned to the version that is the latest then, so that
    /// every resumption runs the same primitive (a server that comes back may not have caught up yet, or one may
    /// be learned meanwhile).
    async fn attempts(
        &self,
        request: &mut v1::ExecuteRequest,
        state: Option<v1::RobotState>,
    ) -> Result<(v1::PlantServer, Session), ClientError> {
        let Opener { cell, options, .. } = *self;
        let began = Instant::now();
        let mut delay = options.retry_delay;
        let mut attempt = 0;
        loop {
            attempt += 1;
            let left = options.max_total.saturating_sub(began.elapsed());
            let tried = tokio::time::timeout(left, self.once(request, state.clone())).await;
            let failure = match tried {
                Ok(Ok(opened)) => return Ok(opened),
                Ok(Err(e)) if !retryable(&e) => return Err(e),
                Ok(Err(e)) => e.to_string(),
                Err(_) => format!("no answer within {:?}", options.max_total),
            };
            let elapsed = began.elapsed();
            if attempt >= options.max_attempts.max(1) || elapsed + delay >= options.max_total {
                return Err(ClientError::Resume {
                    cell: cell.to_owned(),
                    attempts: attempt,
                    elapsed,
                    last: failure,
                });
            }
            tokio::time::sleep(delay).await;
            delay = (delay * 2).min(options.retry_delay * 16);
        }
    }

    /// One attempt: resolves the cell, connects, pins the primitive's version, opens the session and reads its
    /// first segment.
    async fn once(
        &self,
        request: &mut v1::ExecuteRequest,
        state: Option<v1::RobotState>,
    ) -> Result<(v1::PlantServer, Session), ClientError> {
        let Opener { zenoh, cell, options } = *self;
        let server = resolve_cell(zenoh, cell, options.resolve_timeout).await?;
        let client = DmpClient::connect_with(&server.grpc_address, &options.connect).await?.with_cell(cell);
        if let Some(m) = request.motion.as_mut()
            && m.version == 0
        {
            m.version = client.get(&m.robot_id, &m.primitive, 0).await?.version;
        }
        let mut session = client.session(request.clone()).await?;
        if let Some(s) = state {
            session.state(s).await?;
        }
        // The server refuses a bad start with the first item of the stream: peek it, so that a refusal counts as a
        // failed attempt and a good segment is kept.
        let first = session.next_segment().await;
        match first {
            Some(Ok(seg)) => {
                let (sender, rest) = session.into_parts();
                let segments: SegmentStream = Box::pin(tokio_stream::once(Ok(seg)).chain(rest));
                Ok((server, Session { sender, segments }))
            }
            Some(Err(e)) => Err(e),
            None => Err(ClientError::Closed(format!("the session on server `{}`", server.server_id))),
        }
    }
}

fn now_unix_s() -> f64 {
    std::time::SystemTime::now().duration_since(std::time::UNIX_EPOCH).map_or(0.0, |d| d.as_secs_f64())
}

#[cfg(test)]
mod tests;
