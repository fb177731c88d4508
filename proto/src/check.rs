//! Checks of a message's numeric fields that every conversion shares.

use crate::WireError;

/// Checks that every entry of `v` is finite (the error names the first that is not, `field[i]`).
pub fn check_finite(field: &str, v: &[f64]) -> Result<(), WireError> {
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn vectors_are_checked_entry_by_entry() {
        assert!(check_vector("goal", &[1.0, 2.0], 2).is_ok());
        assert_eq!(check_vector("goal", &[1.0], 2).unwrap_err().field, "goal");
        assert_eq!(check_vector("goal", &[1.0, f64::NAN], 2).unwrap_err().field, "goal[1]");
    }
}
