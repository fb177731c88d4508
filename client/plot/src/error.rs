//! Why a figure could not be drawn.

/// Why a figure could not be drawn: the input is inconsistent, or the SVG backend failed.
#[derive(Debug, thiserror::Error)]
pub enum PlotError {
    /// Something has the wrong number of dimensions.
    #[error("{what} has {found} dimensions, expected {expected}")]
    Dimension {
        /// What.
        what: String,
        /// Expected dimension.
        expected: usize,
        /// Its dimension.
        found: usize,
    },
    /// A list of the wrong length.
    #[error("{what} has {found} entries, expected {expected}")]
    Length {
        /// What.
        what: String,
        /// Expected length.
        expected: usize,
        /// Its length.
        found: usize,
    },
    /// A trajectory without rows.
    #[error("the {0} trajectory is empty")]
    EmptyTrajectory(&'static str),
    /// An inconsistent robot.
    #[error("robots[{index}]: {reason}")]
    Robot {
        /// Index in [`PlotInput::robots`](crate::PlotInput::robots).
        index: usize,
        /// What is wrong.
        reason: String,
    },
    /// The backend failed.
    #[error("drawing the SVG failed: {0}")]
    Drawing(String),
}
