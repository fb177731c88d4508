//! Tools that drive the real server exactly as robots and perception nodes would, through gRPC and Zenoh only:
//! simulated robots whose clearance is measured with parry3d, and the load generator.
//!
//! | concept | module |
//! | --- | --- |
//! | simulated robots (`dmpctl sim`): controllers, true shapes, reports and figures | [`robots`] |
//! | many robots at once (`dmpctl load`) | [`load`] |
//! | errors | [`error`] |

#![warn(missing_docs)]
#![warn(unreachable_pub)]

pub mod error;
pub mod load;
pub mod robots;

pub use error::SimError;
