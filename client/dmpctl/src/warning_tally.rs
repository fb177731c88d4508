//! The warnings of a run counted by kind, for the summary line of `plan` and `stream`:
//! `warnings: 3 (2 obstacle ignored: `crate` superquadric.exponents[0]: too large for this robot, 1 scene stale: ...)`.

use dmp_proto::v1;

/// How many distinct details of one kind the summary names before it says `and N more`.
const DETAILS_NAMED: usize = 2;

/// The warnings of one kind: how many, and their distinct details in the order first seen.
#[derive(Debug, Default)]
struct Kind {
    count: usize,
    details: Vec<String>,
}

/// Warnings counted by kind, in the order the kinds were first seen.
#[derive(Debug, Default)]
pub(crate) struct WarningTally {
    kinds: Vec<(String, Kind)>,
}

impl WarningTally {
    /// Counts `warnings`.
    pub(crate) fn add(&mut self, warnings: &[v1::Warning]) {
        for w in warnings {
            let name = kind_words(w.kind);
            let i = match self.kinds.iter().position(|(k, _)| *k == name) {
                Some(i) => i,
                None => {
                    self.kinds.push((name, Kind::default()));
                    self.kinds.len() - 1
                }
            };
            let kind = &mut self.kinds[i].1;
            kind.count += 1;
            let detail = detail(w);
            if !detail.is_empty() && !kind.details.contains(&detail) {
                kind.details.push(detail);
            }
        }
    }

    /// How many warnings in all.
    pub(crate) fn total(&self) -> usize {
        self.kinds.iter().map(|(_, k)| k.count).sum()
    }

    /// `0`, or `3 (2 obstacle ignored: ..., 1 scene stale: ...)`.
    pub(crate) fn words(&self) -> String {
        if self.kinds.is_empty() {
            return "0".to_string();
        }
        let kinds: Vec<String> = self
            .kinds
            .iter()
            .map(|(name, k)| {
                let mut s = format!("{} {name}", k.count);
                if !k.details.is_empty() {
                    let named = k.details.iter().take(DETAILS_NAMED).cloned().collect::<Vec<_>>().join("; ");
                    s.push_str(&format!(": {named}"));
                    let more = k.details.len().saturating_sub(DETAILS_NAMED);
                    if more > 0 {
                        s.push_str(&format!("; and {more} more"));
                    }
                }
                s
            })
            .collect();
        format!("{} ({})", self.total(), kinds.join(", "))
    }
}

/// A kind in words: `OBSTACLE_IGNORED` as `obstacle ignored`.
fn kind_words(kind: i32) -> String {
    let name = v1::warning::Kind::try_from(kind).map_or("UNKNOWN", |k| k.as_str_name());
    name.to_lowercase().replace('_', " ")
}

/// What one warning is about: `` `crate` superquadric.exponents[0]: too large ``, as short as it can be.
fn detail(w: &v1::Warning) -> String {
    let mut parts = Vec::new();
    if !w.obstacle_id.is_empty() {
        parts.push(format!("`{}`", w.obstacle_id));
    }
    if !w.field.is_empty() {
        parts.push(format!("{}:", w.field));
    }
    if !w.reason.is_empty() {
        parts.push(w.reason.clone());
    }
    parts.join(" ")
}

#[cfg(test)]
mod tests {
    use super::*;

    fn warning(kind: v1::warning::Kind, obstacle: &str, field: &str, reason: &str) -> v1::Warning {
        v1::Warning {
            kind: kind as i32,
            field: field.into(),
            reason: reason.into(),
            obstacle_id: obstacle.into(),
        }
    }

    #[test]
    fn no_warning_reads_as_zero() {
        assert_eq!(WarningTally::default().words(), "0");
    }

    #[test]
    fn warnings_are_named_by_kind_with_their_count_and_details() {
        use v1::warning::Kind::*;
        let mut t = WarningTally::default();
        t.add(&[
            warning(ObstacleIgnored, "crate", "dim", "2 axes for a 3-D robot"),
            warning(SceneStale, "ball", "", "quiet for 2 s"),
        ]);
        t.add(&[warning(ObstacleIgnored, "crate", "dim", "2 axes for a 3-D robot")]);
        assert_eq!(t.total(), 3);
        assert_eq!(
            t.words(),
            "3 (2 obstacle ignored: `crate` dim: 2 axes for a 3-D robot, 1 scene stale: `ball` quiet for 2 s)"
        );
    }

    #[test]
    fn many_distinct_details_are_cut_short() {
        let mut t = WarningTally::default();
        for field in ["goal[0]", "goal[1]", "goal[2]", "goal[3]"] {
            t.add(&[warning(v1::warning::Kind::CommandRejected, "", field, "not finite")]);
        }
        assert_eq!(t.words(), "4 (4 command rejected: goal[0]: not finite; goal[1]: not finite; and 2 more)");
    }
}
