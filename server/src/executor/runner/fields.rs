//! The two fields of a run: the scene's obstacles with the group's own robots, and the cell's other robots as
//! moving obstacles (updated in place while they are the same robots). Both are rebuilt or moved from the run's
//! current point (a rebase), never by a jump.

use std::sync::Arc;

use dmp::field::{Agent, RepulsiveField, Scene};
use dmp::{Avoidance, Obstacle};

use super::{AvoidanceSpec, Member, Runner};
use crate::error::ServerError;
use crate::scene::{RemoteRobot, SceneSnapshot};

impl Runner {
    /// Rebuilds the field from the scene (obstacles as they are at wall time `now_unix_s`, which is the run's
    /// current time) and the cell's other robots.
    pub fn apply_scene(
        &mut self,
        snap: &SceneSnapshot,
        remote: &[Arc<RemoteRobot>],
        now_unix_s: f64,
    ) -> Result<(), ServerError> {
        self.rebase();
        let t = self.out_t;
        let sub = self.field.agent_dim();
        let mut obstacles = Vec::new();
        if !self.avoidance.ignore_scene {
            for o in snap.obstacles.values() {
                if o.engine.dim() != sub {
                    continue;
                }
                // Centre now, moved back along its velocity to the run's time zero.
                let mut now = vec![0.0; sub];
                o.engine.center_at(now_unix_s - o.received_unix_s, &mut now);
                let c0: Vec<f64> = now.iter().zip(o.engine.velocity()).map(|(c, v)| c - v * t).collect();
                obstacles.push(o.engine.with_center(c0));
            }
        }
        let agents = agents(&self.members);
        self.field = build_field(&agents, &self.avoidance, obstacles, self.primitive.dim)?;
        self.scene_version = snap.version;
        self.set_remote(remote, now_unix_s)
    }

    /// Updates the cell's other robots (moving obstacles with their footprints).
    pub fn set_remote(&mut self, remote: &[Arc<RemoteRobot>], now_unix_s: f64) -> Result<(), ServerError> {
        let members = std::mem::take(&mut self.members);
        let result = self.set_remote_of(&members, remote, now_unix_s);
        self.members = members;
        result
    }

    fn set_remote_of(
        &mut self,
        members: &[Member],
        remote: &[Arc<RemoteRobot>],
        now_unix_s: f64,
    ) -> Result<(), ServerError> {
        let t = self.out_t;
        let sub = self.field.agent_dim();
        let eligible = |r: &&Arc<RemoteRobot>| {
            !members.iter().any(|m| m.robot_id == r.state.robot_id)
                && r.footprint.as_ref().is_some_and(|fp| dmp::Isopotential::dim(fp) == sub)
                && r.state.position.len() == sub
                && r.state.velocity.len() == sub
        };
        // The centre at the run's time zero of a robot seen at `stamp` moving at constant velocity.
        let c0_into = |r: &RemoteRobot, c0: &mut Vec<f64>| {
            let age = now_unix_s - r.state.stamp_unix_s;
            c0.clear();
            c0.extend(r.state.position.iter().zip(&r.state.velocity).map(|(p, v)| p + v * age - v * t));
        };
        // The same robots with the same footprints as the field holds (the common case, every segment): move them
        // in place instead of compiling a new field.
        let current = &self.remote.scene().obstacles;
        let same = remote.iter().filter(eligible).count() == current.len()
            && remote
                .iter()
                .filter(eligible)
                .zip(current)
                .all(|(r, o)| o.id() == r.state.robot_id && r.footprint.as_ref() == Some(o.shape()));
        if same {
            if current.is_empty() {
                return Ok(());
            }
            self.rebase();
            let mut c0 = std::mem::take(&mut self.c0);
            for (i, r) in remote.iter().filter(eligible).enumerate() {
                c0_into(r, &mut c0);
                self.remote.set_obstacle_motion(i, &c0, &r.state.velocity);
            }
            self.c0 = c0;
            return Ok(());
        }
        let mut obstacles = Vec::new();
        for r in remote.iter().filter(eligible) {
            let Some(fp) = &r.footprint else { continue };
            let mut c0 = Vec::new();
            c0_into(r, &mut c0);
            if let Ok(o) =
                Obstacle::new(r.state.robot_id.clone(), fp.clone(), c0, None, Some(r.state.velocity.clone()))
            {
                obstacles.push(o);
            }
        }
        self.rebase();
        let agents = agents(members);
        self.remote = build_remote(&agents, &self.avoidance, obstacles, self.primitive.dim)?;
        Ok(())
    }
}

pub(super) fn agents(members: &[Member]) -> Vec<Agent> {
    members
        .iter()
        .map(|m| Agent {
            id: m.robot_id.clone(),
            dims: m.dims.clone().collect(),
            footprint: m.footprint.clone(),
        })
        .collect()
}

/// Obstacles with the obstacle method, and the group's robots with the robot method.
pub(super) fn build_field(
    agents: &[Agent],
    a: &AvoidanceSpec,
    mut obstacles: Vec<Obstacle>,
    dim: usize,
) -> Result<RepulsiveField, ServerError> {
    obstacles.extend(a.extra.iter().cloned());
    let group = agents.len() > 1;
    let scene = Scene {
        obstacles,
        avoidance: a.obstacles.0,
        agents: agents.to_vec(),
        robot_avoidance: if group { a.robots.0 } else { Avoidance::NONE },
        point_samples: a.obstacles.1.max(a.robots.1),
    };
    Ok(RepulsiveField::new(scene, dim)?)
}

/// The cell's other robots, as moving obstacles with the robot method.
pub(super) fn build_remote(
    agents: &[Agent],
    a: &AvoidanceSpec,
    obstacles: Vec<Obstacle>,
    dim: usize,
) -> Result<RepulsiveField, ServerError> {
    let scene = Scene {
        obstacles,
        avoidance: a.robots.0,
        agents: agents.to_vec(),
        robot_avoidance: Avoidance::NONE,
        point_samples: a.robots.1,
    };
    Ok(RepulsiveField::new(scene, dim)?)
}
