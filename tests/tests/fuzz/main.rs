//! Fuzzing on the stable toolchain (proptest over raw bytes, mutated valid payloads and structured messages with
//! extreme numbers): every decoder of the wire, the file formats, and every gRPC request through the real server's
//! handlers. Nothing may panic or hang; whatever is accepted is finite; refusals are clear gRPC statuses.
//!
//! By default each target runs a fixed, seeded number of cases (the pass CI runs). `DMP_FUZZ_SECONDS=S` runs
//! random cases for S seconds per target instead and prints `fuzz <target>: <N> cases in <S> s, 0 failures`
//! (`scripts/fuzz.sh`); `DMP_FUZZ_SEED` replays a run. A failure prints the shrunk input: add it to
//! [`regressions`].
//!
//! | target | module |
//! | --- | --- |
//! | the runner: seeded pass or timed run | [`runner`] |
//! | numbers, names and v1 messages | [`values`] |
//! | mutations of valid payloads | [`mutate`] |
//! | Zenoh obstacle payloads, robot states, keys, messages -> engine | [`wire`] |
//! | scenario files, demonstration CSV | [`files`] |
//! | the real server for the gRPC targets, and what every answer must satisfy | [`fixture`] |
//! | gRPC requests | [`requests`] |
//! | Learn, Put, Get, List, Delete | [`grpc_primitives`] |
//! | PutObstacle, DeleteObstacle, ListObstacles, WatchScene | [`grpc_scene`] |
//! | Plan, Execute, ExecuteGroup (and GetStats after every case) | [`grpc_motion`] |
//! | Session | [`grpc_session`] |
//! | bugs found and being fixed elsewhere, skipped until then | [`known`] |
//! | inputs that once failed | [`regressions`] |

mod files;
mod fixture;
mod grpc_motion;
mod grpc_primitives;
mod grpc_scene;
mod grpc_session;
mod mutate;
mod regressions;
mod requests;
mod runner;
mod values;
mod wire;
