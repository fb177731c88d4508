//! The server's typed errors and their one conversion to a gRPC status.

use thiserror::Error;
use tonic::Status;

/// Everything a request can fail with.
#[derive(Debug, Error)]
pub enum ServerError {
    /// A field of the request breaks a rule.
    #[error("{field}: {reason}")]
    InvalidArgument {
        /// Path of the field, e.g. `motion.goal[2]`.
        field: String,
        /// The rule.
        reason: String,
    },
    /// The caller could not be identified.
    #[error("{0}")]
    Unauthenticated(String),
    /// The caller's identity may not do this.
    #[error("{0}")]
    PermissionDenied(String),
    /// The thing named does not exist.
    #[error("{0}")]
    NotFound(String),
    /// A bound was reached (streams, sizes, counts).
    #[error("{0}")]
    ResourceExhausted(String),
    /// The thing to create exists already (a second stream of an executing robot).
    #[error("{0}")]
    AlreadyExists(String),
    /// The work was ended by a concurrent request (a stream taken over by another).
    #[error("{0}")]
    Aborted(String),
    /// The request is valid but cannot be served in the current state.
    #[error("{0}")]
    FailedPrecondition(String),
    /// The store failed.
    #[error("storage: {0}")]
    Storage(String),
    /// The server is shutting down.
    #[error("the server is shutting down")]
    ShuttingDown,
    /// The cell went to another server of the plant (given back after a fail-over): the message names it.
    #[error("{0}")]
    Moved(String),
    /// The client cancelled, left or passed its deadline: the work stopped.
    #[error("cancelled: {0}")]
    Cancelled(String),
    /// A bug or an unexpected failure.
    #[error("internal: {0}")]
    Internal(String),
}

impl ServerError {
    /// An invalid argument.
    pub(crate) fn invalid(field: impl Into<String>, reason: impl Into<String>) -> Self {
        ServerError::InvalidArgument { field: field.into(), reason: reason.into() }
    }

    /// The same error with `prefix.` in front of its field, when it names one.
    pub(crate) fn within(self, prefix: &str) -> Self {
        match self {
            ServerError::InvalidArgument { field, reason } => {
                ServerError::InvalidArgument { field: format!("{prefix}.{field}"), reason }
            }
            other => other,
        }
    }
}

impl From<dmp::DmpError> for ServerError {
    fn from(e: dmp::DmpError) -> Self {
        match e {
            dmp::DmpError::Invalid(i) => ServerError::InvalidArgument { field: i.field, reason: i.rule },
            e @ dmp::DmpError::Diverged { .. } => ServerError::FailedPrecondition(e.to_string()),
            other => ServerError::invalid("primitive", other.to_string()),
        }
    }
}

/// The one conversion of the wire's error: a field of a message, a payload or a key that breaks a rule.
impl From<dmp_proto::WireError> for ServerError {
    fn from(e: dmp_proto::WireError) -> Self {
        ServerError::InvalidArgument { field: e.field, reason: e.rule }
    }
}

impl From<dmp::InvalidInput> for ServerError {
    fn from(i: dmp::InvalidInput) -> Self {
        ServerError::InvalidArgument { field: i.field, reason: i.rule }
    }
}

impl From<ServerError> for Status {
    fn from(e: ServerError) -> Self {
        let msg = e.to_string();
        match e {
            ServerError::InvalidArgument { .. } => Status::invalid_argument(msg),
            ServerError::Unauthenticated(_) => Status::unauthenticated(msg),
            ServerError::PermissionDenied(_) => Status::permission_denied(msg),
            ServerError::NotFound(_) => Status::not_found(msg),
            ServerError::ResourceExhausted(_) => Status::resource_exhausted(msg),
            ServerError::AlreadyExists(_) => Status::already_exists(msg),
            ServerError::Aborted(_) => Status::aborted(msg),
            ServerError::FailedPrecondition(_) => Status::failed_precondition(msg),
            ServerError::ShuttingDown | ServerError::Moved(_) => Status::unavailable(msg),
            ServerError::Cancelled(_) => Status::cancelled(msg),
            ServerError::Storage(_) | ServerError::Internal(_) => Status::internal(msg),
        }
    }
}
