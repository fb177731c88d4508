//! Checks of a message's numeric fields that every conversion shares.

use crate::WireError;

/// Checks that every entry of `v` is finite (the error names the first that is not, `field[i]`).
pub(crate) fn check_finite(field: &str, v: &[f64]) -> Result<(), WireError> {
    match v.iter().position(|x| !x.is_finite()) {
        Some(i) => Err(WireError::new(format!("{field}[{i}]"), "must be a finite number")),
        None => Ok(()),
    }
}

/// Checks a vector of `dim` finite entries.
pub fn check_vector(field: &str, v: &[f64], dim: usize) -> Result<(), WireError> {
    if v.len() != dim {
        return Err(WireError::new(field, format!("must have {dim} entries, found {}", v.len())));
    }
    check_finite(field, v)
}

/// The time scales a motion may have, seconds: every term of the canonical system stays finite and a run of the
/// longest fits in `max_steps` only at a coarse step (the step limit refuses the rest).
pub const TAU_RANGE: std::ops::RangeInclusive<f64> = 1e-3..=1e4;

/// Checks a time scale against [`TAU_RANGE`].
pub fn check_tau(field: &str, tau: f64) -> Result<(), WireError> {
    if tau.is_finite() && TAU_RANGE.contains(&tau) {
        Ok(())
    } else {
        Err(WireError::new(
            field,
            format!("must be between {:e} and {:e} s, found {tau}", TAU_RANGE.start(), TAU_RANGE.end()),
        ))
    }
}

/// Checks that every coordinate of `v` is finite and within the workspace box `[-half_width, half_width]` (metres),
/// naming the first one that is not (`field[i]`).
pub fn check_in_workspace(field: &str, v: &[f64], half_width: f64) -> Result<(), WireError> {
    check_finite(field, v)?;
    match v.iter().position(|x| x.abs() > half_width) {
        Some(i) => Err(WireError::new(
            format!("{field}[{i}]"),
            format!("must be within the workspace, -{half_width} to {half_width} m, found {}", v[i]),
        )),
        None => Ok(()),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn vectors_are_checked_entry_by_entry() {
        assert!(check_vector("goal", &[1.0, 2.0], 2).is_ok());
        assert_eq!(check_vector("goal", &[1.0], 2).unwrap_err().field, "goal");
        assert_eq!(check_vector("goal", &[1.0, f64::NAN], 2).unwrap_err().field, "goal[1]");
    }

    #[test]
    fn tau_and_workspace_ranges_name_the_value() {
        assert!(check_tau("tau", 1.0).is_ok());
        for bad in [0.0, 1e-300, -1.0, 1e5, f64::NAN, f64::INFINITY] {
            assert_eq!(check_tau("tau", bad).unwrap_err().field, "tau");
        }
        assert!(check_in_workspace("goal", &[1.0, -10.0], 10.0).is_ok());
        let e = check_in_workspace("goal", &[1.0, -10.5], 10.0).unwrap_err();
        assert_eq!(e.field, "goal[1]");
        assert!(e.rule.contains("-10 to 10"), "{}", e.rule);
        assert_eq!(check_in_workspace("goal", &[f64::NAN], 10.0).unwrap_err().field, "goal[0]");
    }
}
