//! The streams a call returns: the messages of a server stream, each decoded, with the call's errors as
//! [`ClientError`]. Dropping one cancels its call on the server.

use std::pin::Pin;

use dmp_proto::v1;
use tokio_stream::{Stream, StreamExt};

use crate::error::ClientError;

/// Messages of a server stream, each decoded as `T`.
pub type DecodedStream<T> = Pin<Box<dyn Stream<Item = Result<T, ClientError>> + Send>>;

/// Segments of an Execute or Session call.
pub type SegmentStream = DecodedStream<v1::Segment>;

/// Steps of an ExecuteGroup call.
pub type GroupStream = DecodedStream<v1::GroupSegment>;

/// Snapshots of a WatchScene call: the current scene, then one per change.
pub type SceneStream = DecodedStream<v1::SceneSnapshot>;

/// The stream of a call, its statuses as [`ClientError`]s.
pub(crate) fn boxed<T: Send + 'static>(s: tonic::Streaming<T>) -> DecodedStream<T> {
    Box::pin(s.map(|r| r.map_err(ClientError::from)))
}
