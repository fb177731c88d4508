//! The long-running server (filled by the server issue).
