//! The server's bounds on what the wire carries. The conversions themselves are the wire's, in `dmp_proto` (its
//! `WireError` becomes a [`ServerError`] once, in `error.rs`); this module adds the limits of the configuration.

use dmp::ranges::{self, check_each, check_range};
use dmp_proto::check::check_in_workspace;
use dmp_proto::v1;

use crate::config::RequestLimits;
use crate::error::ServerError;

/// The engine's primitive of a message, validated and within the limits.
pub(crate) fn primitive_from_proto(
    p: &v1::Primitive,
    limits: &RequestLimits,
) -> Result<dmp::Primitive, ServerError> {
    if p.dim as usize > limits.max_dim {
        return Err(ServerError::invalid("dim", format!("must be at most {}", limits.max_dim)));
    }
    if p.n_basis as usize > limits.max_basis {
        return Err(ServerError::invalid("n_basis", format!("must be at most {}", limits.max_basis)));
    }
    let primitive = dmp_proto::primitive::primitive_from_proto(p)?;
    check_in_workspace("start", &primitive.start, limits.workspace_m)?;
    check_in_workspace("goal", &primitive.goal, limits.workspace_m)?;
    Ok(primitive)
}

/// A stored primitive, checked again when it is used: one stored before the ranges of [`dmp::ranges`] were
/// enforced, and now outside them, is refused with the field and the range rather than run.
pub(crate) fn stored_primitive(
    p: &v1::Primitive,
    limits: &RequestLimits,
    what: &str,
) -> Result<dmp::Primitive, ServerError> {
    primitive_from_proto(p, limits).map_err(|e| {
        ServerError::FailedPrecondition(format!(
            "the stored primitive {what} does not fit what this server accepts ({e}); store it again with values \
             inside the ranges"
        ))
    })
}

/// The engine's obstacle of a message ([`dmp_proto::obstacle::obstacle_to_engine`], every number in its range), with
/// its centre within the workspace box `[-workspace_m, workspace_m]`: the one check of an obstacle's place, for the
/// cells' scenes (gRPC and Zenoh) and a motion's own obstacles.
pub(crate) fn obstacle_from_proto(o: &v1::Obstacle, workspace_m: f64) -> Result<dmp::Obstacle, ServerError> {
    let engine = dmp_proto::obstacle::obstacle_to_engine(o)?;
    check_in_workspace("center", &o.center, workspace_m)?;
    Ok(engine)
}

/// The engine's demonstration of a message, within the limits.
pub(crate) fn demonstration_from_proto(
    d: &v1::Demonstration,
    limits: &RequestLimits,
) -> Result<dmp::Demonstration, ServerError> {
    let dim = d.dim as usize;
    if dim == 0 || dim > limits.max_dim {
        return Err(ServerError::invalid(
            "demonstration.dim",
            format!("must be between 1 and {}", limits.max_dim),
        ));
    }
    if d.t.len() > limits.max_samples {
        return Err(ServerError::ResourceExhausted(format!(
            "demonstration.t: {} samples, more than the limit of {}",
            d.t.len(),
            limits.max_samples
        )));
    }
    Ok(dmp_proto::learning::demonstration_from_proto(d)?)
}

/// The learning configuration of a message, with the documented defaults, within the limits.
pub(crate) fn learn_config_from_proto(
    p: Option<&v1::LearnParameters>,
    limits: &RequestLimits,
) -> Result<dmp::LearnConfig, ServerError> {
    if let Some(p) = p
        && p.n_basis as usize > limits.max_basis
    {
        return Err(ServerError::invalid(
            "parameters.n_basis",
            format!("must be at most {}", limits.max_basis),
        ));
    }
    let c = dmp_proto::learning::learn_config_from_proto(p);
    let within = |e: dmp::InvalidInput| ServerError::from(e).within("parameters");
    check_range("alpha", c.alpha, &ranges::ALPHA, "").map_err(within)?;
    check_each("k", &c.k, &ranges::STIFFNESS, "").map_err(within)?;
    if let Some(d) = &c.d {
        check_each("d", d, &ranges::DAMPING, "").map_err(within)?;
    }
    Ok(c)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn messages_over_the_limits_are_refused() {
        let limits = RequestLimits::default();
        let p = v1::Primitive { dim: limits.max_dim as u32 + 1, ..Default::default() };
        assert!(primitive_from_proto(&p, &limits).unwrap_err().to_string().starts_with("dim:"));
        let d = v1::Demonstration { dim: 0, ..Default::default() };
        assert!(
            demonstration_from_proto(&d, &limits).unwrap_err().to_string().starts_with("demonstration.dim")
        );
        let d = v1::Demonstration {
            dim: 1,
            t: vec![0.0; limits.max_samples + 1],
            positions: vec![],
            ..Default::default()
        };
        assert!(matches!(demonstration_from_proto(&d, &limits), Err(ServerError::ResourceExhausted(_))));
        let many = v1::LearnParameters { n_basis: limits.max_basis as u32 + 1, ..Default::default() };
        let e = learn_config_from_proto(Some(&many), &limits).unwrap_err();
        assert!(e.to_string().starts_with("parameters.n_basis"), "{e}");
        assert_eq!(learn_config_from_proto(None, &limits).unwrap(), dmp::LearnConfig::paper());
    }
}
