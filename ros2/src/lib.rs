//! ROS 2 messages as rmw_zenoh carries them, with no ROS installation: the Rust types of the `.msg` files kept in
//! `ros2/msg/` (their source in `ros2/msg/README.md`), their CDR encoding, and rmw_zenoh's key expressions,
//! attachments and liveliness tokens.
//!
//! | concept | module |
//! | --- | --- |
//! | the payload: XCDR1 with its 4-byte encapsulation header, by the `cdr-encoding` crate | [`cdr`] |
//! | the messages, one module per ROS package | [`msgs`] |
//! | rotations and poses: quaternions, composition, rotation matrices | [`pose`] |
//! | `<domain>/<topic>/<type>/<hash>` keys, and the type names and hashes | [`keys`] |
//! | the attachment of every sample: sequence number, source timestamp, publisher GID | [`attachment`] |
//! | the liveliness tokens that list a node and its publishers in ROS 2's graph, and GIDs | [`liveliness`] |

#![warn(missing_docs)]
#![warn(unreachable_pub)]

pub mod attachment;
pub mod cdr;
pub mod keys;
pub mod liveliness;
pub mod msgs;
pub mod pose;

pub use cdr::{CdrError, decode, encode};
