//! The client crates against the real server, in-process on 127.0.0.1:0 (the fixture of `dmp-tests`): the
//! library's calls, `dmpctl`'s commands, and scenarios computed by the server. Every await is under a timeout.

mod dmpctl;
mod dmpctl_verdicts;
mod grpc;
mod scenario_through_server;
