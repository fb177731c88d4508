//! Contacts: a robot inside an obstacle's true shape (`C <= 0`), or a robot's centre inside another robot's
//! footprint. These are checks on the states sent to a robot, not part of the dynamics: the potentials act before.

use super::{Contact, RepulsiveField, gather};

impl RepulsiveField {
    /// Appends to `out` every contact at time `t` and state `x`: a robot inside an obstacle's true shape, or a
    /// robot's centre inside another's footprint. Returns true if there is any.
    pub fn contacts(&mut self, t: f64, x: &[f64], out: &mut Vec<Contact>) -> bool {
        self.each_contact_along(t, 0.0, x, 1, |_, c| out.push(c))
    }

    /// Appends to `out` every contact at the `n` states `xs` (row-major, one DMP state each) at times
    /// `t0 + k dt`, with the index `k` of the state: exactly what [`RepulsiveField::contacts`] finds at each of
    /// them. Returns true if there is any.
    ///
    /// # Pruning
    /// An obstacle (or another robot) is checked state by state only if some state can reach it. With `x_0` the
    /// robot's first position, `R = max_k |x_k - x_0|`, `c_0` the obstacle's centre at `t0`, `|w| (n - 1) dt` how
    /// far that centre moves, and `r` the radius of a ball about the centre holding the whole shape
    /// ([`crate::Shape::bounding_radius_sq`]): if `|x_0 - c_0| > R + |w| (n - 1) dt + r`, no state is inside it.
    /// Another robot of the scene moves as its own states say, so its own `R` is added instead of `|w| (n - 1) dt`.
    pub(crate) fn contacts_along(
        &mut self,
        t0: f64,
        dt: f64,
        xs: &[f64],
        n: usize,
        out: &mut Vec<(usize, Contact)>,
    ) -> bool {
        self.each_contact_along(t0, dt, xs, n, |k, c| out.push((k, c)))
    }

    /// Calls `found` with every contact of [`RepulsiveField::contacts_along`] and the index of its state; true if
    /// there is any.
    fn each_contact_along(
        &mut self,
        t0: f64,
        dt: f64,
        xs: &[f64],
        n: usize,
        mut found: impl FnMut(usize, Contact),
    ) -> bool {
        let mut any = false;
        if n == 0 {
            return false;
        }
        let stride = xs.len() / n;
        let state = |k: usize| &xs[k * stride..(k + 1) * stride];
        let span = (n - 1) as f64 * dt;
        let s = &mut self.s;
        for (ai, a) in self.agents.iter().enumerate() {
            // How far the robot gets from its first position over the stretch.
            let reach_a = reach(xs, stride, n, &a.dims);
            gather(state(0), &a.dims, &mut s.v);
            for (oi, o) in self.scene.obstacles.iter().enumerate() {
                let r2 = o.shape().bounding_radius_sq();
                o.center_at(t0, &mut s.center);
                let travel = span * norm(o.velocity());
                if n > 1 && dist_sq(&s.v, &s.center).sqrt() > reach_a + travel + r2.sqrt() {
                    continue;
                }
                for k in 0..n {
                    gather(state(k), &a.dims, &mut s.x);
                    o.center_at(t0 + k as f64 * dt, &mut s.center);
                    if dist_sq(&s.x, &s.center) > r2 {
                        continue;
                    }
                    let c = s.eval.value(o.shape(), o.rotation(), &s.center, &s.x);
                    if c <= 0.0 {
                        found(k, Contact::Obstacle { agent: ai, obstacle: oi, c });
                        any = true;
                    }
                }
            }
            for (bi, b) in self.agents.iter().enumerate() {
                let Some(f) = b.footprint.as_ref().filter(|_| bi != ai) else { continue };
                let r2 = f.bounding_radius_sq();
                gather(state(0), &b.dims, &mut s.center);
                if n > 1
                    && dist_sq(&s.v, &s.center).sqrt() > reach_a + reach(xs, stride, n, &b.dims) + r2.sqrt()
                {
                    continue;
                }
                for k in 0..n {
                    gather(state(k), &a.dims, &mut s.x);
                    gather(state(k), &b.dims, &mut s.center);
                    if dist_sq(&s.x, &s.center) > r2 {
                        continue;
                    }
                    let c = s.eval.value(f, None, &s.center, &s.x);
                    if c <= 0.0 {
                        found(k, Contact::Robot { agent: ai, other: bi, c });
                        any = true;
                    }
                }
            }
        }
        any
    }
}

/// `max_k |x_k - x_0|` over the robot's dimensions `dims` of the `n` states `xs` (row-major, `stride` apart).
fn reach(xs: &[f64], stride: usize, n: usize, dims: &[usize]) -> f64 {
    (1..n)
        .map(|k| dims.iter().map(|&d| (xs[k * stride + d] - xs[d]).powi(2)).sum::<f64>())
        .fold(0.0, f64::max)
        .sqrt()
}

/// `|a - b|^2`.
fn dist_sq(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(p, q)| (p - q) * (p - q)).sum()
}

/// `|v|`.
fn norm(v: &[f64]) -> f64 {
    v.iter().map(|x| x * x).sum::<f64>().sqrt()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::field::{Agent, Scene};
    use crate::{Avoidance, Obstacle, Shape, Superquadric};
    use proptest::prelude::*;

    fn scene(center: [f64; 2], velocity: [f64; 2], exponents: [f64; 2]) -> RepulsiveField {
        let shape = Shape::Superquadric(Superquadric::new(vec![0.3, 0.15], exponents.to_vec()).unwrap());
        let rot = |a: f64| vec![vec![a.cos(), -a.sin()], vec![a.sin(), a.cos()]];
        let o = Obstacle::new("o", shape, center.to_vec(), Some(rot(0.5)), Some(velocity.to_vec())).unwrap();
        let footprint = Some(Shape::Superquadric(Superquadric::ellipsoid(vec![0.1, 0.1]).unwrap()));
        let agents = vec![
            Agent { id: "a".into(), dims: vec![0, 1], footprint: footprint.clone() },
            Agent { id: "b".into(), dims: vec![2, 3], footprint },
        ];
        let scene = Scene {
            obstacles: vec![o],
            avoidance: Avoidance::NONE,
            agents,
            robot_avoidance: Avoidance::NONE,
            point_samples: 0,
        };
        RepulsiveField::new(scene, 4).unwrap()
    }

    #[test]
    fn a_robot_that_runs_into_an_obstacle_within_the_stretch_is_caught() {
        // The first state is outside the obstacle's bounding ball (0.5 m from a box of semi-axes 0.3 x 0.15): only
        // the robot's reach over the stretch keeps the obstacle in the check.
        let mut f = scene([0.0, 0.0], [0.0, 0.0], [2.0, 2.0]);
        let xs: Vec<f64> = (0..12).flat_map(|k| [-0.5 + 0.05 * k as f64, 0.0, 5.0, 5.0]).collect();
        let mut out = Vec::new();
        assert!(f.contacts_along(0.0, 0.01, &xs, 12, &mut out));
        assert!(out.iter().all(|(_, c)| matches!(c, Contact::Obstacle { agent: 0, obstacle: 0, .. })));
        assert!(out.len() >= 4, "{out:?}");
    }

    proptest! {
        /// The pruned check along a stretch finds exactly the contacts of the check at every state: two robots on
        /// straight lines past a moving rotated box and each other.
        #[test]
        fn along_a_stretch_equals_every_state_checked_alone(
            start in prop::array::uniform4(-1.0f64..1.0),
            step in prop::array::uniform4(-0.05f64..0.05),
            center in prop::array::uniform2(-0.5f64..0.5),
            velocity in prop::array::uniform2(-3.0f64..3.0),
            n in 1usize..12,
            boxy in any::<bool>(),
        ) {
            let e = if boxy { [2.0, 2.0] } else { [1.0, 1.0] };
            let mut f = scene(center, velocity, e);
            let (t0, dt) = (0.3, 0.01);
            let xs: Vec<f64> =
                (0..n).flat_map(|k| (0..4).map(move |i| start[i] + k as f64 * step[i])).collect();
            let mut one_by_one = Vec::new();
            let mut at_k = Vec::new();
            for k in 0..n {
                at_k.clear();
                f.contacts(t0 + k as f64 * dt, &xs[k * 4..(k + 1) * 4], &mut at_k);
                one_by_one.extend(at_k.iter().map(|c| (k, *c)));
            }
            let mut along = Vec::new();
            let any = f.contacts_along(t0, dt, &xs, n, &mut along);
            prop_assert_eq!(any, !one_by_one.is_empty());
            let key = |&(k, c): &(usize, Contact)| match c {
                Contact::Obstacle { agent, obstacle, c } => (k, 0, agent, obstacle, c.to_bits()),
                Contact::Robot { agent, other, c } => (k, 1, agent, other, c.to_bits()),
            };
            let mut a: Vec<_> = one_by_one.iter().map(key).collect();
            let mut b: Vec<_> = along.iter().map(key).collect();
            a.sort_unstable();
            b.sort_unstable();
            prop_assert_eq!(a, b);
        }
    }
}
