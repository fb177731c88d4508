//! The one mapping between the engine's primitive and its message, shared by the server and the client.

use dmp::ranges::{self, check_count, check_each, check_range};

use crate::WireError;
use crate::check::check_tau;
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
        orientation_reference: p.orientation.map(|o| o.reference.to_vec()).unwrap_or_default(),
    }
}

/// The engine's primitive of a message, validated (errors name the field).
pub fn primitive_from_proto(p: &v1::Primitive) -> Result<dmp::Primitive, WireError> {
    let (dim, n) = (p.dim as usize, p.n_basis as usize);
    if dim == 0 {
        return Err(WireError::new("dim", "must be at least 1"));
    }
    if n == 0 {
        return Err(WireError::new("n_basis", "must be at least 1"));
    }
    if p.weights.len() != dim * (n + 1) {
        return Err(WireError::new(
            "weights",
            format!("must have dim x (n_basis + 1) = {} entries, found {}", dim * (n + 1), p.weights.len()),
        ));
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
        orientation: match p.orientation_reference.as_slice() {
            [] => None,
            &[x, y, z, w] => Some(dmp::OrientationChart { reference: [x, y, z, w] }),
            other => {
                return Err(WireError::new(
                    "orientation_reference",
                    format!("must be empty or 4 numbers (x, y, z, w), found {}", other.len()),
                ));
            }
        },
    };
    prim.validate()?;
    check_primitive_ranges(&prim)?;
    Ok(prim)
}

/// Checks a valid primitive's numbers against [`dmp::ranges`] and [`TAU_RANGE`](crate::check::TAU_RANGE) (the
/// start and goal against the workspace are the server's): `alpha`, `N`, `K`, `D`, the weights and `tau`. Stored
/// primitives written before these ranges are checked again with it when they are used.
fn check_primitive_ranges(p: &dmp::Primitive) -> Result<(), WireError> {
    check_range("alpha", p.alpha, &ranges::ALPHA, "")?;
    check_count("n_basis", p.n_basis, &ranges::N_BASIS)?;
    check_each("k", &p.k, &ranges::STIFFNESS, "")?;
    check_each("d", &p.d, &ranges::DAMPING, "")?;
    for (row, w) in p.weights.iter().enumerate() {
        if let Some(i) = w.iter().position(|w| !(w.is_finite() && ranges::WEIGHT.contains(w))) {
            // Named as the message's flat, row-major index.
            let field = format!("weights[{}]", row * (p.n_basis + 1) + i);
            check_range(&field, w[i], &ranges::WEIGHT, "")?;
        }
    }
    check_tau("tau", p.tau)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn learned() -> dmp::Primitive {
        let t: Vec<f64> = (0..=100).map(|k| k as f64 / 100.0).collect();
        let x: Vec<Vec<f64>> = t.iter().map(|t| vec![t.sin(), t * t, 1.0 - t]).collect();
        let demo = dmp::Demonstration::new(t, x).unwrap();
        dmp::learn(&demo, &dmp::LearnConfig { n_basis: 7, ..dmp::LearnConfig::paper() }).unwrap()
    }

    #[test]
    fn primitives_round_trip_through_the_message() {
        let p = learned();
        let m = primitive_to_proto(&p);
        assert_eq!(m.weights.len(), 3 * 8);
        // Row-major: row p holds the N + 1 weights of dimension p.
        assert_eq!(m.weights[8..16], p.weights[1][..]);
        assert_eq!(primitive_from_proto(&m).unwrap(), p);
        // And through the bytes.
        let bytes = crate::codec::encode(&m);
        let back: v1::Primitive = crate::codec::decode(&bytes).unwrap();
        assert_eq!(primitive_from_proto(&back).unwrap(), p);
    }

    #[test]
    fn bad_primitive_messages_name_the_field() {
        let mut m = primitive_to_proto(&learned());
        m.weights.pop();
        assert!(primitive_from_proto(&m).unwrap_err().to_string().contains("weights"));
        let mut m = primitive_to_proto(&learned());
        m.k[2] = -1.0;
        assert!(primitive_from_proto(&m).unwrap_err().to_string().contains("k[2]"));
        let mut m = primitive_to_proto(&learned());
        m.dim = 0;
        assert!(primitive_from_proto(&m).unwrap_err().to_string().contains("dim"));
    }

    #[test]
    fn numbers_out_of_their_ranges_are_refused_with_the_range() {
        type Break = fn(&mut v1::Primitive);
        let cases: [(Break, &str, &str); 5] = [
            (|m| m.alpha = 1e-300, "alpha", "between 0.01 and 100"),
            (|m| m.tau = 1e-300, "tau", "between 1e-3 and 1e4"),
            (|m| m.k[1] = 1e300, "k[1]", "between 0.001 and 1e8"),
            (|m| m.d[0] = 1e6, "d[0]", "between 0 and 1e5"),
            (|m| m.weights[9] = -1e200, "weights[9]", "between -10000 and 10000"),
        ];
        for (break_it, field, range) in cases {
            let mut m = primitive_to_proto(&learned());
            break_it(&mut m);
            let e = primitive_from_proto(&m).unwrap_err();
            assert_eq!(e.field, field);
            assert!(e.rule.contains(range), "{e}");
        }
    }
}
