//! The two fields of a run: the obstacles with the run's own members, and the cell's other robots as moving
//! obstacles (updated in place while they are the same robots). Both change from the run's next output point (a
//! rebase), never by a jump.

use super::{CellMate, Execution, cell_mate_field};
use crate::error::Result;
use crate::field::{RepulsiveField, Scene};
use crate::isopotential::Isopotential;
use crate::obstacle::Obstacle;

impl Execution {
    /// Replaces the cell's obstacles by `seen`: each obstacle with its age, how long before the run's current time
    /// its centre was where it says (it moves on along its velocity). A change is blended in from the next output
    /// point ([`Execution::set_obstacle_blend`]), so that the acceleration stays continuous. Obstacles of another dimension than the
    /// members' are left out and reported in the next stretch ([`super::Stretch::ignored`]), as are those dropped
    /// earlier in the run (until a new version with another shape replaces them); the run's own obstacles stay,
    /// after these.
    pub fn set_obstacles<'a>(&mut self, seen: impl IntoIterator<Item = (&'a Obstacle, f64)>) -> Result<()> {
        self.rebase();
        let t = self.out_t;
        let sub = self.field.agent_dim();
        let margin = self.tool_margin();
        let mut obstacles = Vec::new();
        let mut other_dim = Vec::new();
        for (o, age) in seen {
            if o.dim() != sub {
                other_dim.push(o);
                continue;
            }
            // Inflated for a tool's axis samples before the check: what was dropped is the field's shape.
            let o = if margin > 0.0 { &o.inflated(margin)? } else { o };
            if self.ignored.is_dropped(o) {
                continue;
            }
            // Centre now, moved back along its velocity to the run's time zero.
            let mut now = vec![0.0; sub];
            o.center_at(age, &mut now);
            let c0: Vec<f64> = now.iter().zip(o.velocity()).map(|(c, v)| c - v * t).collect();
            obstacles.push(o.with_center(c0));
        }
        self.ignored.set_other_dim(other_dim, sub);
        obstacles.extend(self.scene.obstacles.iter().filter(|o| !self.ignored.is_dropped(o)).cloned());
        let scene = Scene { obstacles, ..self.scene.clone() };
        let field = RepulsiveField::new(scene, self.primitive.dim)?.keeping_off(self.keep_off())?;
        // Blended in from the next point, unless nothing was handed out yet or nothing changed.
        if self.has_last && field.scene().obstacles != self.field.scene().obstacles {
            self.blend.forget_before(t - self.history_span);
            let old = std::mem::replace(&mut self.field, field);
            self.blend.push(old, t);
        } else {
            self.field = field;
        }
        Ok(())
    }

    /// Blends every later change of the obstacles in over `seconds` (`execution/blend.rs`; by default
    /// [`super::DEFAULT_OBSTACLE_BLEND`]); 0 applies them at once. Refused (naming `obstacle_blend_s`) unless finite
    /// and non-negative.
    pub fn set_obstacle_blend(&mut self, seconds: f64) -> Result<(), crate::error::InvalidInput> {
        if !(seconds.is_finite() && seconds >= 0.0) {
            return Err(crate::error::InvalidInput::new(
                "obstacle_blend_s",
                format!("must be a finite number of seconds, zero (off) or more, not {seconds}"),
            ));
        }
        if seconds == 0.0 {
            // Off: the fields being phased out go now (a zero duration would weigh them 0 / 0).
            self.rebase();
            self.blend.clear();
        }
        self.blend.duration = seconds;
        Ok(())
    }

    /// Updates the cell's other robots (moving obstacles with their footprints). Members of the run, robots of
    /// another dimension than the members' and robots dropped earlier in the run are left out.
    pub fn set_cell_mates<'a, I>(&mut self, mates: I) -> Result<()>
    where
        I: IntoIterator<Item = CellMate<'a>>,
        I::IntoIter: Clone,
    {
        // Taken out for the call, so that the filter does not borrow the run.
        let members = std::mem::take(&mut self.member_ids);
        let ignored = std::mem::take(&mut self.ignored);
        let mates = mates.into_iter().filter(|m| !ignored.is_dropped_robot(m.id, m.footprint));
        let result = self.set_cell_mates_except(&members, mates);
        self.member_ids = members;
        self.ignored = ignored;
        result
    }

    fn set_cell_mates_except<'a, I>(&mut self, members: &[String], mates: I) -> Result<()>
    where
        I: IntoIterator<Item = CellMate<'a>>,
        I::IntoIter: Clone,
    {
        let t = self.out_t;
        let sub = self.field.agent_dim();
        let mates = mates.into_iter().filter(|m| {
            !members.iter().any(|id| id == m.id)
                && m.footprint.dim() == sub
                && m.position.len() == sub
                && m.velocity.len() == sub
        });
        // The centre at the run's time zero of a robot seen `age` ago moving at constant velocity.
        let c0_into = |m: &CellMate<'_>, c0: &mut Vec<f64>| {
            c0.clear();
            c0.extend(m.position.iter().zip(m.velocity).map(|(p, v)| p + v * m.age - v * t));
        };
        // The same robots with the same footprints as the field holds (the common case, every stretch): move them
        // in place instead of compiling a new field.
        let current = &self.cell_mates.scene().obstacles;
        let same = mates.clone().count() == current.len()
            && mates.clone().zip(current).all(|(m, o)| o.id() == m.id && m.footprint == o.shape());
        if same {
            if current.is_empty() {
                return Ok(());
            }
            self.rebase();
            let mut c0 = std::mem::take(&mut self.c0);
            for (i, m) in mates.enumerate() {
                c0_into(&m, &mut c0);
                self.cell_mates.set_obstacle_motion(i, &c0, m.velocity);
            }
            self.c0 = c0;
            return Ok(());
        }
        let mut obstacles = Vec::new();
        for m in mates {
            let mut c0 = Vec::new();
            c0_into(&m, &mut c0);
            if let Ok(o) = Obstacle::new(m.id, m.footprint.clone(), c0, None, Some(m.velocity.to_vec())) {
                obstacles.push(o);
            }
        }
        self.rebase();
        let agents = self.field.agents().to_vec();
        self.cell_mates = cell_mate_field(&agents, self.cell_mate_avoidance, obstacles, self.primitive.dim)?;
        Ok(())
    }
}
