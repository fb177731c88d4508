//! What learning takes on the wire, both ways: a demonstration and the learning parameters.

use dmp::scenario::DmpSpec;

use crate::WireError;
use crate::v1;

/// The message of a demonstration: times `t` and one row of positions per time, all rows of one dimension.
pub fn demonstration_to_proto(t: &[f64], rows: &[Vec<f64>]) -> Result<v1::Demonstration, WireError> {
    pose_demonstration_to_proto(t, rows, &[])
}

/// The message of a pose demonstration: [`demonstration_to_proto`] with one orientation `[x, y, z, w]` per time
/// (none for a position-only demonstration).
pub fn pose_demonstration_to_proto(
    t: &[f64],
    rows: &[Vec<f64>],
    orientations: &[[f64; 4]],
) -> Result<v1::Demonstration, WireError> {
    if !orientations.is_empty() && orientations.len() != t.len() {
        return Err(WireError::new(
            "demonstration.orientations",
            format!("has {} orientations for {} times", orientations.len(), t.len()),
        ));
    }
    let dim = rows.first().map_or(0, Vec::len);
    if t.len() != rows.len() {
        return Err(WireError::new(
            "demonstration.t",
            format!("has {} times for {} rows of positions", t.len(), rows.len()),
        ));
    }
    if let Some(i) = rows.iter().position(|r| r.len() != dim) {
        return Err(WireError::new(
            format!("demonstration.x[{i}]"),
            format!("has {} coordinates, expected {dim} like the first row", rows[i].len()),
        ));
    }
    Ok(v1::Demonstration {
        t: t.to_vec(),
        positions: rows.iter().flatten().copied().collect(),
        dim: dim as u32,
        orientations: orientations.iter().flatten().copied().collect(),
    })
}

/// The orientations of a demonstration message, checked (unit quaternions, one per time); `None` without any.
/// (Feature `orientation`.)
#[cfg(feature = "orientation")]
pub fn orientations_from_proto(
    d: &v1::Demonstration,
) -> Result<Option<dmp::OrientationDemonstration>, WireError> {
    if d.orientations.is_empty() {
        return Ok(None);
    }
    if d.orientations.len() != 4 * d.t.len() {
        return Err(WireError::new(
            "demonstration.orientations",
            format!(
                "must have 4 values (x, y, z, w) per time, {} entries, found {}",
                4 * d.t.len(),
                d.orientations.len()
            ),
        ));
    }
    let q = d.orientations.chunks_exact(4).map(|q| [q[0], q[1], q[2], q[3]]).collect();
    dmp::OrientationDemonstration::new(d.t.clone(), q).map(Some).map_err(|e| {
        // The engine names the samples `demonstration.q[i]`; on the wire they are the orientation rows.
        let e = WireError::from(e);
        WireError::new(e.field.replacen("demonstration.q", "demonstration.orientations", 1), e.rule)
    })
}

/// The engine's demonstration of a message (positions row-major, `dim` per time), validated by the engine.
pub fn demonstration_from_proto(d: &v1::Demonstration) -> Result<dmp::Demonstration, WireError> {
    let dim = d.dim as usize;
    if dim == 0 {
        return Err(WireError::new("demonstration.dim", "must be at least 1"));
    }
    if d.positions.len() != d.t.len() * dim {
        return Err(WireError::new(
            "demonstration.positions",
            format!("must have t.len() x dim = {} entries, found {}", d.t.len() * dim, d.positions.len()),
        ));
    }
    let rows = d.positions.chunks(dim).map(<[f64]>::to_vec).collect();
    Ok(dmp::Demonstration::new(d.t.clone(), rows)?)
}

/// The learning parameters of a scenario's `dmp` section (`D = null` sends no damping: critical).
pub fn learn_parameters_to_proto(spec: &DmpSpec) -> v1::LearnParameters {
    v1::LearnParameters {
        n_basis: spec.n as u32,
        k: spec.k.to_vec(),
        d: spec.d.as_ref().map(|d| d.to_vec()).unwrap_or_default(),
        alpha: spec.alpha,
    }
}

/// The learning configuration of a message: the paper's ([`dmp::LearnConfig::paper`]) where a field is unset
/// (0 or empty).
pub fn learn_config_from_proto(p: Option<&v1::LearnParameters>) -> dmp::LearnConfig {
    let mut c = dmp::LearnConfig::paper();
    if let Some(p) = p {
        if p.n_basis > 0 {
            c.n_basis = p.n_basis as usize;
        }
        if !p.k.is_empty() {
            c.k = p.k.clone();
        }
        if !p.d.is_empty() {
            c.d = Some(p.d.clone());
        }
        if p.alpha != 0.0 {
            c.alpha = p.alpha;
        }
    }
    c
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn demonstrations_round_trip_through_the_message() {
        let t = vec![0.0, 0.5, 1.0];
        let rows = vec![vec![0.0, 1.0], vec![0.5, 1.5], vec![1.0, 2.0]];
        let m = demonstration_to_proto(&t, &rows).unwrap();
        assert_eq!((m.dim, m.positions[2]), (2, 0.5));
        assert_eq!(demonstration_from_proto(&m).unwrap(), dmp::Demonstration::new(t.clone(), rows).unwrap());

        let ragged = vec![vec![0.0, 1.0], vec![0.5], vec![1.0, 2.0]];
        assert_eq!(demonstration_to_proto(&t, &ragged).unwrap_err().field, "demonstration.x[1]");
        assert_eq!(demonstration_to_proto(&t[..2], &m_rows()).unwrap_err().field, "demonstration.t");
        let short = v1::Demonstration { positions: vec![0.0; 5], ..m.clone() };
        assert_eq!(demonstration_from_proto(&short).unwrap_err().field, "demonstration.positions");
        let flat = v1::Demonstration { dim: 0, ..m };
        assert_eq!(demonstration_from_proto(&flat).unwrap_err().field, "demonstration.dim");
    }

    fn m_rows() -> Vec<Vec<f64>> {
        vec![vec![0.0]; 3]
    }

    #[test]
    fn learn_parameters_map_to_the_configuration() {
        let spec: DmpSpec =
            serde_json::from_value(serde_json::json!({"N": 7, "K": [10, 20], "D": null, "alpha": 3}))
                .unwrap();
        let c = learn_config_from_proto(Some(&learn_parameters_to_proto(&spec)));
        assert_eq!((c.n_basis, c.k.clone(), c.d.clone(), c.alpha), (7, vec![10.0, 20.0], None, 3.0));
        let paper = dmp::LearnConfig::paper();
        let unset = learn_config_from_proto(Some(&v1::LearnParameters::default()));
        assert_eq!((unset.n_basis, unset.k, unset.alpha), (paper.n_basis, paper.k, paper.alpha));
    }
}
