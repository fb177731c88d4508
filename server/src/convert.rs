//! The server's bounds on what the wire carries. The conversions themselves are the wire's, in `dmp_proto` (its
//! `WireError` becomes a [`ServerError`] once, in `error.rs`); this module adds the limits of the configuration.

use dmp_proto::v1;

use crate::config::Limits;
use crate::error::ServerError;

/// The engine's primitive of a message, validated and within the limits.
pub fn primitive_from_proto(p: &v1::Primitive, limits: &Limits) -> Result<dmp::Primitive, ServerError> {
    if p.dim as usize > limits.max_dim {
        return Err(ServerError::invalid("dim", format!("must be at most {}", limits.max_dim)));
    }
    if p.n_basis as usize > limits.max_basis {
        return Err(ServerError::invalid("n_basis", format!("must be at most {}", limits.max_basis)));
    }
    Ok(dmp_proto::primitive::primitive_from_proto(p)?)
}

/// The engine's demonstration of a message, within the limits.
pub fn demonstration_from_proto(
    d: &v1::Demonstration,
    limits: &Limits,
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
pub fn learn_config_from_proto(
    p: Option<&v1::LearnParameters>,
    limits: &Limits,
) -> Result<dmp::LearnConfig, ServerError> {
    if let Some(p) = p
        && p.n_basis as usize > limits.max_basis
    {
        return Err(ServerError::invalid(
            "parameters.n_basis",
            format!("must be at most {}", limits.max_basis),
        ));
    }
    Ok(dmp_proto::learning::learn_config_from_proto(p))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn messages_over_the_limits_are_refused() {
        let limits = Limits::default();
        let p = v1::Primitive { dim: limits.max_dim as u32 + 1, ..Default::default() };
        assert!(primitive_from_proto(&p, &limits).unwrap_err().to_string().starts_with("dim:"));
        let d = v1::Demonstration { dim: 0, ..Default::default() };
        assert!(
            demonstration_from_proto(&d, &limits).unwrap_err().to_string().starts_with("demonstration.dim")
        );
        let d = v1::Demonstration { dim: 1, t: vec![0.0; limits.max_samples + 1], positions: vec![] };
        assert!(matches!(demonstration_from_proto(&d, &limits), Err(ServerError::ResourceExhausted(_))));
        let many = v1::LearnParameters { n_basis: limits.max_basis as u32 + 1, ..Default::default() };
        let e = learn_config_from_proto(Some(&many), &limits).unwrap_err();
        assert!(e.to_string().starts_with("parameters.n_basis"), "{e}");
        assert_eq!(learn_config_from_proto(None, &limits).unwrap(), dmp::LearnConfig::paper());
    }
}
