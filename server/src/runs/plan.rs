//! A whole plan, computed in chunks so that it stops as soon as nobody waits for it (the client cancelled, left or
//! passed its deadline).

use dmp::Execution;
use dmp::execution::{Outcome, Stretch};

use crate::error::ServerError;
use crate::runs::compute::pool::JobContext;

/// Output points computed between two checks for cancellation.
const CHUNK_POINTS: usize = 2000;

/// The next `n` points of `e`, as one stretch: the same points, contacts, stalls and outcome as one
/// `e.advance(n)`, computed `CHUNK_POINTS` at a time. Fails with `Cancelled` once the job is.
pub(crate) fn advance_cancellable(
    e: &mut Execution,
    n: usize,
    job: &JobContext<'_>,
) -> Result<Stretch, ServerError> {
    let mut all = Stretch { start_time: e.time(), ..Stretch::default() };
    let mut done = 0;
    let mut last = Outcome::Running;
    while done < n || n == 0 {
        if job.cancelled() {
            return Err(ServerError::Cancelled("the client left or its deadline passed".into()));
        }
        let k = (n - done).min(CHUNK_POINTS);
        let p = e.advance(k)?;
        all.x.extend_from_slice(&p.x);
        all.xd.extend_from_slice(&p.xd);
        all.xdd.extend_from_slice(&p.xdd);
        all.orientation.q.extend_from_slice(&p.orientation.q);
        all.orientation.omega.extend_from_slice(&p.orientation.omega);
        all.orientation.omega_dot.extend_from_slice(&p.orientation.omega_dot);
        all.contacts.extend(p.contacts.into_iter().map(|(i, c)| (i + done, c)));
        all.cell_mate_contacts.extend(p.cell_mate_contacts.into_iter().map(|(i, c)| (i + done, c)));
        all.stalls.extend(p.stalls);
        all.ignored.extend(p.ignored);
        all.limit = all.limit.max(p.limit);
        if all.min_clearance.is_empty() {
            all.min_clearance = p.min_clearance;
        } else {
            all.min_clearance.iter_mut().zip(&p.min_clearance).for_each(|(a, b)| *a = a.min(*b));
        }
        last = p.outcome;
        done += k;
        if n == 0 {
            break;
        }
    }
    all.outcome = combined_outcome(&all, last);
    Ok(all)
}

/// The outcome of the whole stretch from that of its last chunk, by the rule of [`Execution::advance`]: stopped,
/// arrived and the end time are read at the last point; a contact or a stall anywhere in the stretch outranks
/// arriving, holding and running.
fn combined_outcome(all: &Stretch, last: Outcome) -> Outcome {
    let worst = if !all.contacts.is_empty() || !all.cell_mate_contacts.is_empty() {
        Outcome::Collision
    } else if !all.stalls.is_empty() {
        Outcome::Stalled
    } else {
        Outcome::Running
    };
    match last {
        Outcome::Stopped | Outcome::EndTime => last,
        Outcome::GoalReached | Outcome::Holding if worst == Outcome::Running => last,
        _ => worst.max_with(last),
    }
}

/// Ranks the outcomes that a stretch's events decide.
trait Rank {
    fn max_with(self, other: Outcome) -> Outcome;
}

impl Rank for Outcome {
    /// Collision outranks Stalled, which outranks the rest.
    fn max_with(self, other: Outcome) -> Outcome {
        match (self, other) {
            (Outcome::Collision, _) | (_, Outcome::Collision) => Outcome::Collision,
            (Outcome::Stalled, _) | (_, Outcome::Stalled) => Outcome::Stalled,
            (Outcome::Running, o) => o,
            (s, _) => s,
        }
    }
}

#[cfg(test)]
mod tests {
    use dmp::execution::CellMateAvoidance;
    use dmp::field::Scene;
    use dmp::{Avoidance, Motion, Primitive, Stepping};

    use super::*;
    use crate::runs::compute::pool::Pool;

    fn execution() -> Execution {
        let p = Primitive::straight_line(20, 4.0, vec![100.0; 2], None, 1.0, vec![0.0; 2], vec![1.0, 1.0])
            .unwrap();
        let motion = Motion::of(&p);
        let mates = CellMateAvoidance { method: Avoidance::NONE, point_samples: 0 };
        Execution::new(p, motion, Scene::empty(), mates, Stepping::rk4(1e-3), 0).unwrap()
    }

    #[tokio::test]
    async fn chunks_give_the_points_and_outcome_of_one_advance() {
        let pool = Pool::start("test", 1, 0).unwrap();
        let (chunked, whole) = pool
            .run(|job| {
                let (mut a, mut b) = (execution(), execution());
                (advance_cancellable(&mut a, 5001, job).unwrap(), b.advance(5001).unwrap())
            })
            .await
            .unwrap();
        assert_eq!(chunked.x, whole.x);
        assert_eq!(chunked.xd, whole.xd);
        assert_eq!(chunked.xdd, whole.xdd);
        assert_eq!(chunked.outcome, whole.outcome);
        assert_eq!(chunked.start_time, whole.start_time);
    }
}
