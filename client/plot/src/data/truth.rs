//! True shapes as the figure measures and draws them: a [`Solid`] the caller gave, or an obstacle that is its own
//! true shape (the scenario format, where the superquadric is the obstacle).

use dmp::Obstacle;

use super::geometry::{P2, convex_hull};
use super::outline::obstacle_outline;
use super::solid::{Solid, SolidShape};

/// A true shape: one given, or an obstacle that is its own true shape.
#[derive(Debug, Clone, Copy)]
pub(crate) enum Truth<'a> {
    Solid(&'a Solid),
    Obstacle(&'a Obstacle),
}

impl Truth<'_> {
    /// The obstacle's id.
    pub(crate) fn id(&self) -> &str {
        match self {
            Truth::Solid(s) => &s.id,
            Truth::Obstacle(o) => o.id(),
        }
    }

    pub(crate) fn present_at(&self, t: f64) -> bool {
        match self {
            Truth::Solid(s) => s.present_at(t),
            Truth::Obstacle(_) => true,
        }
    }

    pub(crate) fn moving(&self) -> bool {
        match self {
            Truth::Solid(s) => s.moving(),
            Truth::Obstacle(o) => o.velocity().iter().any(|v| *v != 0.0),
        }
    }

    pub(crate) fn is_cloud(&self) -> bool {
        matches!(self, Truth::Solid(Solid { shape: SolidShape::Points(_), .. }))
    }

    pub(crate) fn signed_distance(&self, x: &[f64], t: f64) -> f64 {
        match self {
            Truth::Solid(s) => s.signed_distance(x, t),
            Truth::Obstacle(o) => dmp::distance::signed_distance_world(o, x, t),
        }
    }

    /// The outline on the local axes `(i, j)` at time `t`: the convex hull of the projected surface samples (the
    /// samples in order for a 2-D superquadric), or the points of a cloud.
    pub(crate) fn outline(&self, t: f64, (i, j): (usize, usize), samples: usize) -> Vec<P2> {
        match self {
            Truth::Solid(Solid { shape: SolidShape::Superquadric(o), .. }) => {
                obstacle_outline(o, t, (i, j), samples)
            }
            Truth::Solid(s) => {
                let p: Vec<P2> = s.samples(t).iter().map(|p| (p[i], p[j])).collect();
                if self.is_cloud() { p } else { convex_hull(p) }
            }
            Truth::Obstacle(o) => obstacle_outline(o, t, (i, j), samples),
        }
    }
}

/// The true shapes of `solids`, or the obstacles themselves when none is given.
pub(crate) fn truths<'a>(solids: &'a [Solid], obstacles: &'a [Obstacle]) -> Vec<Truth<'a>> {
    if solids.is_empty() {
        obstacles.iter().map(Truth::Obstacle).collect()
    } else {
        solids.iter().map(Truth::Solid).collect()
    }
}
