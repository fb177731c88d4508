//! The server's place in ROS 2's graph: one node (`dmp_server`, node id 0, its liveliness token held while the
//! bridge runs) and its publishers, each with its own entity id, liveliness token and GID, publishing with
//! rmw_zenoh's attachment.

use std::sync::atomic::{AtomicU32, Ordering};

use dmp_ros2::attachment::Attachment;
use dmp_ros2::keys::{RosType, topic_key};
use dmp_ros2::liveliness::{Node, gid};
use serde::Serialize;
use tracing::warn;
use zenoh::Session;
use zenoh::liveliness::LivelinessToken;
use zenoh::pubsub::Publisher;

/// The node and the count of its entities.
#[derive(Debug)]
pub(crate) struct Graph {
    session: Session,
    node: Node,
    next_entity: AtomicU32,
    _token: Option<LivelinessToken>,
}

impl Graph {
    /// Declares the node `dmp_server` in `domain` on `session` (a failure is logged: the topics work without it,
    /// only the graph tools do not list the node).
    pub(crate) async fn declare(session: Session, domain: u32) -> Self {
        let node = Node {
            domain,
            zid: session.zid().to_string(),
            node_id: 0,
            namespace: "/".into(),
            name: "dmp_server".into(),
        };
        let token = match session.liveliness().declare_token(node.token()).await {
            Ok(t) => Some(t),
            Err(e) => {
                warn!(error = %e, "ros2: cannot declare the node's liveliness token");
                None
            }
        };
        Self { session, node, next_entity: AtomicU32::new(1), _token: token }
    }

    /// A publisher of `ty` on `topic`, with its liveliness token.
    pub(crate) async fn publisher(&self, topic: &str, ty: &RosType) -> Result<RosPublisher, zenoh::Error> {
        let entity = self.next_entity.fetch_add(1, Ordering::Relaxed);
        let token_key = self.node.publisher_token(entity, topic, ty);
        let publisher = self.session.declare_publisher(topic_key(self.node.domain, topic, ty)).await?;
        let token = self.session.liveliness().declare_token(token_key.clone()).await?;
        Ok(RosPublisher { publisher, _token: token, gid: gid(&token_key), sequence: 0 })
    }
}

/// A publisher in the graph: its token lives as long as it does.
#[derive(Debug)]
pub(crate) struct RosPublisher {
    publisher: Publisher<'static>,
    _token: LivelinessToken,
    gid: [u8; 16],
    sequence: i64,
}

/// A message that could not be published.
#[derive(Debug, thiserror::Error)]
pub(crate) enum PublishError {
    /// It does not encode.
    #[error(transparent)]
    Encode(#[from] dmp_ros2::CdrError),
    /// Zenoh refused it.
    #[error("zenoh: {0}")]
    Zenoh(zenoh::Error),
}

impl RosPublisher {
    /// Publishes `msg` (CDR) with the attachment: the next sequence number, `now_unix_s`, the publisher's GID.
    pub(crate) async fn put<T: Serialize>(&mut self, msg: &T, now_unix_s: f64) -> Result<(), PublishError> {
        let bytes = dmp_ros2::encode(msg)?;
        self.sequence += 1;
        let attachment = Attachment {
            sequence_number: self.sequence,
            source_timestamp: (now_unix_s * 1e9) as i64,
            source_gid: self.gid,
        };
        self.publisher.put(bytes).attachment(attachment.encode()).await.map_err(PublishError::Zenoh)
    }
}
