//! The obstacles a run could not use, as the replies' warnings: each [`IgnoredObstacle`] of a stretch becomes an
//! `OBSTACLE_IGNORED` warning naming the obstacle and why.

use dmp::execution::IgnoredObstacle;
use dmp_proto::v1;

/// The warning of an obstacle a run does not avoid.
pub(crate) fn obstacle_warning(ignored: IgnoredObstacle) -> v1::Warning {
    v1::Warning {
        kind: v1::warning::Kind::ObstacleIgnored as i32,
        field: String::new(),
        reason: ignored.reason,
        obstacle_id: ignored.id,
    }
}

/// Moves a stretch's ignored obstacles into `warnings`, as warnings.
pub(crate) fn push_obstacle_warnings(ignored: &mut Vec<IgnoredObstacle>, warnings: &mut Vec<v1::Warning>) {
    warnings.extend(ignored.drain(..).map(obstacle_warning));
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn an_ignored_obstacle_is_a_warning_naming_it() {
        let mut ignored = vec![IgnoredObstacle { id: "ghost".into(), reason: "why".into() }];
        let mut warnings = Vec::new();
        push_obstacle_warnings(&mut ignored, &mut warnings);
        assert!(ignored.is_empty());
        assert_eq!(warnings.len(), 1);
        assert_eq!(warnings[0].kind(), v1::warning::Kind::ObstacleIgnored);
        assert_eq!((warnings[0].obstacle_id.as_str(), warnings[0].reason.as_str()), ("ghost", "why"));
    }
}
