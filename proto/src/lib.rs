//! The wire schema shared by gRPC and Zenoh (filled by the server issue).
