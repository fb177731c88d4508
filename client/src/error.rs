//! Errors of the client library.

use thiserror::Error;

/// What can go wrong in the client.
#[derive(Debug, Error)]
pub enum ClientError {
    /// An argument of a call breaks a rule.
    #[error("{field}: {message}")]
    Argument {
        /// The argument or field at fault, e.g. `server` or `demonstration.x[3]`.
        field: String,
        /// What is wrong.
        message: String,
    },
    /// The server answered with a gRPC status other than OK. InvalidArgument and NotFound are bad input; their
    /// message names the field.
    #[error("server: {} ({code:?})", if message.is_empty() { "no message" } else { message.as_str() })]
    Status {
        /// The gRPC code.
        code: tonic::Code,
        /// The server's message.
        message: String,
    },
    /// The server could not be reached (refused, timed out, bad address).
    #[error("cannot connect to the server at {url}: {message}")]
    Connect {
        /// The address dialled.
        url: String,
        /// Why.
        message: String,
    },
    /// The server sent something that breaks the schema's contract (e.g. a segment with the wrong number of values).
    #[error("unexpected answer from the server: {0}")]
    Protocol(String),
    /// A stream or session already ended (`0` names it).
    #[error("{0} has ended")]
    Closed(String),
    /// A resumable session could not be resumed on a server of its cell within its bounds.
    #[error(
        "cannot resume the session in cell `{cell}`: {attempts} attempts in {elapsed:?}, the last: {last}"
    )]
    Resume {
        /// The cell.
        cell: String,
        /// The attempts made.
        attempts: u32,
        /// The time they took.
        elapsed: std::time::Duration,
        /// Why the last one failed.
        last: String,
    },
    /// Zenoh failed (opening the session, publishing), or nobody subscribes.
    #[cfg(feature = "zenoh")]
    #[error("zenoh: {}", without_source_paths(.0))]
    Zenoh(String),
}

impl ClientError {
    /// True when the caller's input is at fault: a bad argument, or a request the server refused as
    /// InvalidArgument or NotFound.
    pub fn is_bad_input(&self) -> bool {
        match self {
            ClientError::Argument { .. } => true,
            ClientError::Status { code, .. } => {
                matches!(code, tonic::Code::InvalidArgument | tonic::Code::NotFound)
            }
            _ => false,
        }
    }

    /// An argument error.
    pub fn argument(field: impl Into<String>, message: impl Into<String>) -> Self {
        ClientError::Argument { field: field.into(), message: message.into() }
    }

    /// The gRPC code, when the server answered with a status.
    pub fn code(&self) -> Option<tonic::Code> {
        match self {
            ClientError::Status { code, .. } => Some(*code),
            _ => None,
        }
    }

    /// The server does not offer the call (it is older than this client).
    pub fn is_unimplemented(&self) -> bool {
        self.code() == Some(tonic::Code::Unimplemented)
    }

    /// The server has no such thing (a primitive, an obstacle).
    pub fn is_not_found(&self) -> bool {
        self.code() == Some(tonic::Code::NotFound)
    }

    /// A failure of the connection itself rather than an answer of the server: refused, reset, a broken pipe, a
    /// connection closed under the call (plaintext HTTP/2 against a TLS server fails in any of these ways, depending
    /// on when the server hangs up). [`crate::tls_probe::https_hint`] tells that case apart.
    pub fn is_transport_failure(&self) -> bool {
        match self {
            ClientError::Connect { .. } => true,
            ClientError::Status { code, .. } => matches!(
                code,
                tonic::Code::Unavailable
                    | tonic::Code::Unknown
                    | tonic::Code::Internal
                    | tonic::Code::Cancelled
            ),
            _ => false,
        }
    }
}

/// A value that breaks a rule of the wire (a field, a name in a key, a Zenoh setting) is bad input.
impl From<dmp_proto::WireError> for ClientError {
    fn from(e: dmp_proto::WireError) -> Self {
        ClientError::Argument { field: e.field, message: e.rule }
    }
}

impl From<tonic::Status> for ClientError {
    fn from(s: tonic::Status) -> Self {
        let mut message = s.message().to_string();
        // A status made by the transport (TLS refused, plaintext against TLS) says why only in its source.
        if let Some(source) = std::error::Error::source(&s) {
            let why = chain(source);
            if !message.contains(&why) {
                message = format!("{message}: {why}");
            }
        }
        ClientError::Status { code: s.code(), message }
    }
}

/// Every error of an error's chain, `: `-separated (tonic's transport error says little on its own).
pub(crate) fn chain(e: &dyn std::error::Error) -> String {
    let mut out = e.to_string();
    let mut source = e.source();
    while let Some(s) = source {
        let text = s.to_string();
        if !out.contains(&text) {
            out.push_str(": ");
            out.push_str(&text);
        }
        source = s.source();
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn wire_errors_are_bad_input() {
        let e = dmp_proto::obstacle_json::JsonObstacle::parse(
            &serde_json::json!({"id": "e", "center": [0], "semi_axes": [1], "bogus": 1}),
            "o",
        )
        .map_err(ClientError::from)
        .unwrap_err();
        assert!(e.is_bad_input() && e.to_string().starts_with("o.bogus"), "{e}");
    }
}

/// `message` without the source locations some libraries append to their errors (Zenoh's
/// `at /root/.cargo/registry/src/.../orchestrator.rs:123.`): a user is not helped by them.
pub fn without_source_paths(message: &str) -> String {
    let is_source = |w: &str| {
        let w = w.trim_end_matches(['.', ',', ')', ']']);
        w.contains(".cargo/")
            || w.contains("/rustc/")
            || (w.contains(".rs:") && (w.contains('/') || w.starts_with("src")))
    };
    let words: Vec<&str> = message.split(' ').collect();
    let mut out: Vec<&str> = Vec::with_capacity(words.len());
    for (i, w) in words.iter().enumerate() {
        if is_source(w) {
            continue;
        }
        // The `at` that introduces a location.
        if *w == "at" && words.get(i + 1).is_some_and(|n| is_source(n)) {
            continue;
        }
        out.push(w);
    }
    out.join(" ").trim_end().to_string()
}

#[cfg(test)]
mod source_path_tests {
    use super::*;

    #[test]
    fn source_locations_are_left_out_of_messages() {
        let m = "Unable to connect to any of [tcp/127.0.0.1:7447]! at \
                 /root/.cargo/registry/src/index.crates.io-1949cf8c6b5b557f/zenoh-1.5.0/src/net/runtime/orchestrator.rs:1005.";
        assert_eq!(without_source_paths(m), "Unable to connect to any of [tcp/127.0.0.1:7447]!");
        assert_eq!(without_source_paths("failed at src/foo.rs:12: boom"), "failed boom");
        assert_eq!(
            without_source_paths("no subscriber of dmp/a/obstacles/**"),
            "no subscriber of dmp/a/obstacles/**"
        );
    }
}
