//! The schedule flags of `stream`: `--goal-at T=X,Y[,Z]`, `--tau-at T=TAU`, `--stop-at T`, each at the run's time T
//! in seconds.

use std::str::FromStr;

/// A finite number, for `what`.
pub(crate) fn finite_number(s: &str, what: &str) -> Result<f64, String> {
    match s.trim().parse::<f64>() {
        Ok(x) if x.is_finite() => Ok(x),
        _ => Err(format!("{what} `{s}` is not a finite number")),
    }
}

/// A finite number greater than zero, for `what`.
pub(crate) fn positive_number(s: &str, what: &str) -> Result<f64, String> {
    match finite_number(s, what)? {
        x if x > 0.0 => Ok(x),
        _ => Err(format!("{what} `{s}` must be greater than zero")),
    }
}

/// `T=VALUE` of a schedule flag: the time and the value's text.
fn time_and_value<'a>(s: &'a str, example: &str) -> Result<(f64, &'a str), String> {
    let (t, v) = s.split_once('=').ok_or_else(|| format!("`{s}` is not T=VALUE, e.g. `{example}`"))?;
    let t = finite_number(t, "the time")?;
    if t < 0.0 {
        return Err(format!("the time `{t}` must be >= 0"));
    }
    Ok((t, v))
}

/// `--goal-at T=X,Y[,Z...]`: at the run's time T (seconds), the goal becomes (X, Y, ...).
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct GoalAt(pub(crate) f64, pub(crate) Vec<f64>);

impl FromStr for GoalAt {
    type Err = String;

    fn from_str(s: &str) -> Result<Self, String> {
        let (t, v) = time_and_value(s, "0.5=1,0.2")?;
        let g = v
            .split(',')
            .enumerate()
            .map(|(i, x)| finite_number(x, &format!("coordinate {}", i + 1)))
            .collect::<Result<Vec<_>, _>>()?;
        Ok(GoalAt(t, g))
    }
}

/// `--tau-at T=TAU`: at the run's time T (seconds), tau becomes TAU.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct TauAt(pub(crate) f64, pub(crate) f64);

impl FromStr for TauAt {
    type Err = String;

    fn from_str(s: &str) -> Result<Self, String> {
        let (t, v) = time_and_value(s, "0.5=2")?;
        Ok(TauAt(t, positive_number(v, "tau")?))
    }
}

/// `--stop-at T`: a time, seconds, zero or more.
pub(crate) fn stop_time(s: &str) -> Result<f64, String> {
    match finite_number(s, "the time")? {
        t if t >= 0.0 => Ok(t),
        t => Err(format!("the time `{t}` must be >= 0")),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn schedule_flags_parse_time_and_value() {
        assert_eq!("0.5=1,0.2".parse::<GoalAt>(), Ok(GoalAt(0.5, vec![1.0, 0.2])));
        assert_eq!("1=2".parse::<TauAt>(), Ok(TauAt(1.0, 2.0)));
        assert!("1,2".parse::<GoalAt>().unwrap_err().contains("T=VALUE"));
        assert!("-1=2".parse::<TauAt>().unwrap_err().contains(">= 0"));
        assert!("1=0".parse::<TauAt>().unwrap_err().contains("greater than zero"));
        assert_eq!(stop_time("0.7"), Ok(0.7));
    }
}
