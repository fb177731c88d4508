//! A group on one phase: the members' primitives side by side in one DMP (the paper's 6-D youBot DMP, section 4.2),
//! each member owning its dimensions.

use crate::error::{InvalidInput, Result};
use crate::field::Agent;
use crate::integrate::Motion;
use crate::isopotential::Shape;
use crate::primitive::Primitive;

/// A robot of a group: its primitive, its motion and its footprint (which the other members avoid).
#[derive(Debug, Clone)]
pub struct GroupMember<'a> {
    /// Its id.
    pub id: &'a str,
    /// Its primitive.
    pub primitive: &'a Primitive,
    /// Its start, goal and tau (the group runs at one tau).
    pub motion: &'a Motion,
    /// Its footprint.
    pub footprint: Option<&'a Shape>,
}

/// Joins the members' primitives into one DMP on one phase, with time scale `tau` (the slowest member's when
/// `None`): the primitive, the motion, and the members as agents owning consecutive dimensions. Every member must
/// share `N` and `alpha` (one phase), move in the same number of dimensions, and have a footprint; errors name
/// `members[i].primitive` or `members[i].footprint`.
pub fn join_group(members: &[GroupMember<'_>], tau: Option<f64>) -> Result<(Primitive, Motion, Vec<Agent>)> {
    let Some(first) = members.first() else {
        return Err(InvalidInput::new("members", "a group needs at least one member").into());
    };
    for (i, m) in members.iter().enumerate() {
        let (p, f) = (m.primitive, first.primitive);
        if p.n_basis != f.n_basis || p.alpha != f.alpha {
            return Err(InvalidInput::new(
                format!("members[{i}].primitive"),
                "every member's primitive must share N and alpha (they run on one phase)",
            )
            .into());
        }
        if p.orientation.is_some() {
            return Err(InvalidInput::new(
                format!("members[{i}].primitive"),
                "a pose primitive (with orientation) runs alone, not in a group",
            )
            .into());
        }
        if p.dim != f.dim {
            return Err(InvalidInput::new(
                format!("members[{i}].primitive"),
                "every member must move in the same number of dimensions",
            )
            .into());
        }
        if m.footprint.is_none() {
            return Err(InvalidInput::new(
                format!("members[{i}].footprint"),
                "is required: the other members avoid it",
            )
            .into());
        }
        if members[..i].iter().any(|o| o.id == m.id) {
            return Err(InvalidInput::new(format!("members[{i}].id"), "appears twice").into());
        }
    }
    let tau = tau.unwrap_or_else(|| members.iter().map(|m| m.motion.tau).fold(0.0, f64::max));
    if !(tau.is_finite() && tau > 0.0) {
        return Err(InvalidInput::new("tau", "must be a finite number greater than zero").into());
    }
    let mut primitive = first.primitive.clone();
    primitive.tau = tau;
    primitive.dim = 0;
    for f in [&mut primitive.k, &mut primitive.d, &mut primitive.start, &mut primitive.goal] {
        f.clear();
    }
    primitive.weights.clear();
    let mut motion = Motion { start: Vec::new(), goal: Vec::new(), tau };
    let mut agents = Vec::with_capacity(members.len());
    for m in members {
        let p = m.primitive;
        let dims = primitive.dim..primitive.dim + p.dim;
        primitive.dim += p.dim;
        primitive.k.extend(&p.k);
        primitive.d.extend(&p.d);
        primitive.start.extend(&p.start);
        primitive.goal.extend(&p.goal);
        primitive.weights.extend(p.weights.iter().cloned());
        motion.start.extend(&m.motion.start);
        motion.goal.extend(&m.motion.goal);
        agents.push(Agent { id: m.id.to_string(), dims: dims.collect(), footprint: m.footprint.cloned() });
    }
    Ok((primitive, motion, agents))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::isopotential::Superquadric;

    fn primitive(dim: usize, x: f64) -> Primitive {
        Primitive::straight_line(10, 4.0, vec![100.0; dim], None, 1.0, vec![x; dim], vec![x + 1.0; dim])
            .unwrap()
    }

    fn disc() -> Shape {
        Shape::Superquadric(Superquadric::new(vec![0.1, 0.1], vec![1.0, 1.0]).unwrap())
    }

    #[test]
    fn members_own_consecutive_dimensions_at_the_slowest_tau() {
        let (a, b) = (primitive(2, 0.0), primitive(2, 5.0));
        let (ma, mut mb) = (Motion::of(&a), Motion::of(&b));
        mb.tau = 3.0;
        let fp = disc();
        let members = [
            GroupMember { id: "a", primitive: &a, motion: &ma, footprint: Some(&fp) },
            GroupMember { id: "b", primitive: &b, motion: &mb, footprint: Some(&fp) },
        ];
        let (p, m, agents) = join_group(&members, None).unwrap();
        assert_eq!((p.dim, p.tau, m.tau), (4, 3.0, 3.0));
        assert_eq!(m.start, vec![0.0, 0.0, 5.0, 5.0]);
        assert_eq!(agents[1].dims, vec![2, 3]);
        p.validate().unwrap();
        let (_, m, _) = join_group(&members, Some(0.5)).unwrap();
        assert_eq!(m.tau, 0.5);
    }

    #[test]
    fn members_that_cannot_share_a_phase_are_refused_by_field() {
        let (a, b) = (primitive(2, 0.0), primitive(3, 5.0));
        let (ma, mb) = (Motion::of(&a), Motion::of(&b));
        let fp = disc();
        let members = [
            GroupMember { id: "a", primitive: &a, motion: &ma, footprint: Some(&fp) },
            GroupMember { id: "b", primitive: &b, motion: &mb, footprint: None },
        ];
        let e = join_group(&members, None).unwrap_err().to_string();
        assert!(e.starts_with("members[1].primitive: every member must move in the same"), "{e}");
        let members = [members[0].clone(), GroupMember { primitive: &a, motion: &ma, ..members[1].clone() }];
        let e = join_group(&members, None).unwrap_err().to_string();
        assert!(e.starts_with("members[1].footprint: is required"), "{e}");
    }
}
