//! The one mapping between the engine's primitive and its message, shared by the server and the client.

use dmp::{DmpError, InvalidInput};

use crate::v1;

/// The message of a primitive: weights row-major, `dim` rows of `n_basis + 1` entries.
pub fn primitive_to_proto(p: &dmp::Primitive) -> v1::Primitive {
    v1::Primitive {
        format_version: p.format_version,
        dim: p.dim as u32,
        n_basis: p.n_basis as u32,
        alpha: p.alpha,
        k: p.k.clone(),
        d: p.d.clone(),
        tau: p.tau,
        start: p.start.clone(),
        goal: p.goal.clone(),
        weights: p.weights.iter().flatten().copied().collect(),
    }
}

/// The engine's primitive of a message, validated (errors name the field).
pub fn primitive_from_proto(p: &v1::Primitive) -> Result<dmp::Primitive, DmpError> {
    let (dim, n) = (p.dim as usize, p.n_basis as usize);
    if dim == 0 {
        return Err(InvalidInput::new("dim", "must be at least 1").into());
    }
    if n == 0 {
        return Err(InvalidInput::new("n_basis", "must be at least 1").into());
    }
    if p.weights.len() != dim * (n + 1) {
        return Err(InvalidInput::new(
            "weights",
            format!("must have dim x (n_basis + 1) = {} entries, found {}", dim * (n + 1), p.weights.len()),
        )
        .into());
    }
    let prim = dmp::Primitive {
        format_version: p.format_version,
        dim,
        n_basis: n,
        alpha: p.alpha,
        k: p.k.clone(),
        d: p.d.clone(),
        tau: p.tau,
        start: p.start.clone(),
        goal: p.goal.clone(),
        weights: p.weights.chunks(n + 1).map(<[f64]>::to_vec).collect(),
    };
    prim.validate()?;
    Ok(prim)
}
