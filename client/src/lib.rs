//! The client side of the DMP cell: the `dmpctl` command line and what it is built from.
//!
//! | concept | module |
//! | --- | --- |
//! | reading scenario files, errors at the field | [`scenario_file`] |
//! | offline runs and timing | [`offline`] |
//! | output files | [`outputs`] |
//! | figures | [`plot`] |
//! | the command line | [`cli`] |

pub mod cli;
pub mod error;
pub mod offline;
pub mod outputs;
pub mod plot;
pub mod scenario_file;

pub use error::ClientError;
