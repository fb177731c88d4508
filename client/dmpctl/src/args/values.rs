//! The values of flags that clap does not parse on its own: vectors, positive and non-negative numbers, and the
//! avoidance of the scenario format.

use std::str::FromStr;

/// A vector on the command line: comma-separated finite numbers, e.g. `0.5,-1,2e-3`.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct Vector(pub(crate) Vec<f64>);

impl FromStr for Vector {
    type Err = String;

    fn from_str(s: &str) -> Result<Self, String> {
        let mut v = Vec::new();
        for (i, part) in s.split(',').enumerate() {
            let part = part.trim();
            match part.parse::<f64>() {
                Ok(x) if x.is_finite() => v.push(x),
                _ => return Err(format!("entry {} (`{part}`) is not a finite number", i + 1)),
            }
        }
        Ok(Vector(v))
    }
}

/// A finite number greater than zero.
pub(crate) fn positive(s: &str) -> Result<f64, String> {
    match s.trim().parse::<f64>() {
        Ok(x) if x.is_finite() && x > 0.0 => Ok(x),
        _ => Err(format!("`{s}` is not a finite number greater than zero")),
    }
}

/// A finite number, zero or more.
pub(crate) fn non_negative(s: &str) -> Result<f64, String> {
    match s.trim().parse::<f64>() {
        Ok(x) if x.is_finite() && x >= 0.0 => Ok(x),
        _ => Err(format!("`{s}` is not a finite number >= 0")),
    }
}

/// The scenario format's avoidance object, or a bare method name (`none`).
pub(crate) fn parse_avoidance(s: &str) -> Result<dmp::Avoidance, String> {
    let t = s.trim();
    let json = if t.starts_with('{') { t.to_string() } else { format!("{{\"method\": \"{t}\"}}") };
    serde_json::from_str(&json).map_err(|e| e.to_string())
}
