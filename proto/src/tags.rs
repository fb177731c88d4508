//! The field numbers of every top-level message of `dmp.v1`, generated from the schema by `build.rs`: one module
//! per message (`RobotState` -> [`robot_state`]), one constant per field (`start_unix_s` -> `START_UNIX_S`). For
//! code that reads a message lazily ([`crate::segment_view`]) instead of decoding it whole.

include!(concat!(env!("OUT_DIR"), "/tags.rs"));
