//! The one mapping of a run's outcome to the status its segments carry.

use dmp::{LimitAction, Outcome};

use crate::v1::SegmentStatus;

/// The status of a segment whose points came to `outcome`.
fn segment_status(outcome: Outcome) -> SegmentStatus {
    match outcome {
        Outcome::Running => SegmentStatus::Running,
        Outcome::Holding => SegmentStatus::Paused,
        Outcome::Stalled => SegmentStatus::Stalled,
        Outcome::Collision => SegmentStatus::Collision,
        Outcome::GoalReached => SegmentStatus::GoalReached,
        Outcome::Stopped | Outcome::EndTime => SegmentStatus::Stopped,
    }
}

/// The status of a segment whose points came to `outcome` while keeping the robot's limits did `limit`: a
/// running segment that braked to rest within them is [`SegmentStatus::LimitBraking`], and one that braked or
/// was held before the safety distance is [`SegmentStatus::Blocked`].
pub fn segment_status_limited(outcome: Outcome, limit: LimitAction) -> SegmentStatus {
    match (outcome, limit) {
        (Outcome::Running, LimitAction::Braking) => SegmentStatus::LimitBraking,
        (Outcome::Running | Outcome::Stalled, LimitAction::Blocked) => SegmentStatus::Blocked,
        _ => segment_status(outcome),
    }
}

/// Why a run ended, in words (logs), when `outcome` ends it.
pub fn end_reason(outcome: Outcome) -> Option<&'static str> {
    match outcome {
        Outcome::GoalReached => Some("goal reached"),
        Outcome::Stopped => Some("stopped"),
        Outcome::EndTime => Some("max duration"),
        Outcome::Running | Outcome::Holding | Outcome::Stalled | Outcome::Collision => None,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn final_outcomes_and_only_they_end_a_run() {
        for o in [
            Outcome::Running,
            Outcome::Holding,
            Outcome::Stalled,
            Outcome::Collision,
            Outcome::GoalReached,
            Outcome::Stopped,
            Outcome::EndTime,
        ] {
            assert_eq!(end_reason(o).is_some(), o.is_final(), "{o:?}");
        }
        assert_eq!(segment_status(Outcome::EndTime), SegmentStatus::Stopped);
        assert_eq!(segment_status(Outcome::Holding), SegmentStatus::Paused);
        assert_eq!(
            segment_status_limited(Outcome::Running, LimitAction::Braking),
            SegmentStatus::LimitBraking
        );
        assert_eq!(segment_status_limited(Outcome::Running, LimitAction::Limited), SegmentStatus::Running);
        assert_eq!(segment_status_limited(Outcome::Running, LimitAction::Blocked), SegmentStatus::Blocked);
        assert_eq!(
            segment_status_limited(Outcome::GoalReached, LimitAction::Braking),
            SegmentStatus::GoalReached
        );
    }
}
