//! Demonstrations from CSV files (`dmpctl learn --csv FILE`).
//!
//! The first column is the time, the others are positions. An optional header names the columns (`t,x1,x2` or any
//! names after `t`); when it has columns named `x1..xd` (e.g. a `trajectory.csv` written by `dmpctl`, whose other
//! columns are velocities and accelerations), only those are read. Blank lines and lines starting with `#` are
//! skipped. A header with the columns `qx,qy,qz,qw` (wherever they sit) gives an orientation per sample, a unit
//! quaternion, for a pose primitive; they are not positions.

use std::path::Path;

use crate::error::DmpctlError;

/// Sample times and one row of positions per sample.
#[derive(Debug, Clone, PartialEq)]
pub struct CsvDemonstration {
    /// Times, as written (the server checks that they increase).
    pub t: Vec<f64>,
    /// Positions, one row per time.
    pub x: Vec<Vec<f64>>,
    /// Orientations `[x, y, z, w]`, one per time, or none.
    pub q: Vec<[f64; 4]>,
}

/// The quaternion columns' names, in the wire's order.
const QUATERNION_COLUMNS: [&str; 4] = ["qx", "qy", "qz", "qw"];

/// Parses CSV text; `path` only names the source in errors, which give the line and column (from 1).
pub fn parse_demonstration_csv(text: &str, path: &Path) -> Result<CsvDemonstration, DmpctlError> {
    let err = |field: String, message: String| DmpctlError::Parse {
        path: path.to_path_buf(),
        position: None,
        field,
        message,
    };
    let mut lines = text
        .lines()
        .enumerate()
        .map(|(i, l)| (i + 1, l.trim()))
        .filter(|(_, l)| !l.is_empty() && !l.starts_with('#'))
        .peekable();
    // Which columns hold positions: all after the first, or the header's `x1..xd`.
    let mut columns: Option<Vec<usize>> = None;
    let mut q_columns: Option<[usize; 4]> = None;
    let mut width = None;
    if let Some(&(n, first)) = lines.peek() {
        if let Some(message) = not_comma_separated(first) {
            return Err(err(format!("line {n}"), message));
        }
        let cells: Vec<&str> = first.split(',').map(str::trim).collect();
        if cells[0].parse::<f64>().is_err() {
            lines.next();
            if cells.len() < 2 {
                return Err(err(
                    format!("line {n}"),
                    "the header needs a time column and at least one position".into(),
                ));
            }
            // Orientation columns: all four or none.
            let q: Vec<Option<usize>> =
                QUATERNION_COLUMNS.iter().map(|name| cells.iter().position(|c| c == name)).collect();
            match q.iter().filter(|c| c.is_some()).count() {
                0 => {}
                4 => q_columns = Some([0, 1, 2, 3].map(|i| q[i].unwrap_or_default())),
                _ => {
                    return Err(err(
                        format!("line {n}"),
                        "an orientation needs all four columns qx, qy, qz, qw".into(),
                    ));
                }
            }
            let is_q = |c: usize| q_columns.is_some_and(|qc| qc.contains(&c));
            // Columns named x1, x2, ... (in that order of names, wherever they sit), else all after the time
            // that are not the orientation's.
            let xs: Vec<usize> = (1..)
                .map_while(|j| cells[1..].iter().position(|c| *c == format!("x{j}")).map(|i| i + 1))
                .collect();
            columns = Some(if xs.is_empty() { (1..cells.len()).filter(|&c| !is_q(c)).collect() } else { xs });
            if columns.as_ref().is_some_and(Vec::is_empty) {
                return Err(err(format!("line {n}"), "the header names no position column".into()));
            }
            width = Some(cells.len());
        }
    }
    let (mut t, mut x, mut q) = (Vec::new(), Vec::new(), Vec::new());
    let mut first_sample = None;
    for (n, line) in lines {
        first_sample.get_or_insert(n);
        if let Some(message) = not_comma_separated(line) {
            return Err(err(format!("line {n}"), message));
        }
        let cells: Vec<&str> = line.split(',').map(str::trim).collect();
        let w = *width.get_or_insert(cells.len());
        if cells.len() != w {
            return Err(err(format!("line {n}"), format!("has {} columns, expected {w}", cells.len())));
        }
        if w < 2 {
            return Err(err(format!("line {n}"), "needs a time column and at least one position".into()));
        }
        let mut values = Vec::with_capacity(w);
        for (c, cell) in cells.iter().enumerate() {
            let v: f64 = cell.parse().map_err(|_| {
                err(format!("line {n}, column {}", c + 1), format!("`{cell}` is not a number"))
            })?;
            if !v.is_finite() {
                return Err(err(format!("line {n}, column {}", c + 1), "must be a finite number".into()));
            }
            values.push(v);
        }
        t.push(values[0]);
        let cols = columns.get_or_insert_with(|| (1..w).collect());
        x.push(cols.iter().map(|&c| values[c]).collect());
        if let Some(qc) = q_columns {
            q.push(qc.map(|c| values[c]));
        }
    }
    if t.len() < 2 {
        return Err(err("(document)".into(), format!("needs at least 2 samples, found {}", t.len())));
    }
    if let Some(message) = time_unit_problem(&t) {
        return Err(err(format!("line {}, column 1", first_sample.unwrap_or(1)), message));
    }
    Ok(CsvDemonstration { t, x, q })
}

/// A line separated by `;` or tabs rather than commas (a spreadsheet's export in some locales): what to say.
fn not_comma_separated(line: &str) -> Option<String> {
    // A `;` is never in a number nor a name; with it, a comma is a decimal comma (`0,5`).
    let delimiter = if line.contains(';') {
        "`;`"
    } else if line.contains(',') {
        return None;
    } else if line.contains('\t') {
        "tabs"
    } else {
        return None;
    };
    Some(format!(
        "the delimiter must be a comma; this line is separated by {} (in a spreadsheet, export as CSV with a comma \
         and a decimal point)",
        delimiter
    ))
}

/// Times in ms, µs or ns since the Unix epoch (the first one between the years 2000 and 2100 in that unit), or
/// spanning more than a day: what to say. The times must be seconds.
fn time_unit_problem(t: &[f64]) -> Option<String> {
    /// 2000-01-01 and 2100-01-01, seconds since the Unix epoch.
    const EPOCH_SECONDS: std::ops::Range<f64> = 946_684_800.0..4_102_444_800.0;
    let first = t[0];
    for (unit, per_second) in [("milliseconds", 1e3), ("microseconds", 1e6), ("nanoseconds", 1e9)] {
        let s = first / per_second;
        if EPOCH_SECONDS.contains(&s) {
            let date = humantime::format_rfc3339_seconds(
                std::time::UNIX_EPOCH + std::time::Duration::from_secs_f64(s),
            );
            return Some(format!(
                "the times look like {unit} since the Unix epoch (the first, {first}, is {date}); give seconds, \
                 e.g. (t - t0) / {per_second:e}"
            ));
        }
    }
    let span =
        t.iter().copied().fold(f64::NEG_INFINITY, f64::max) - t.iter().copied().fold(f64::INFINITY, f64::min);
    (span > 86_400.0).then(|| {
        format!(
            "the times span {span} s, more than a day: give seconds (if they are milliseconds, microseconds or \
             nanoseconds, divide them by 1e3, 1e6 or 1e9)"
        )
    })
}

/// Reads and parses a CSV demonstration.
pub(crate) fn load_demonstration_csv(path: &Path) -> Result<CsvDemonstration, DmpctlError> {
    let text = std::fs::read_to_string(path)
        .map_err(|source| DmpctlError::Io { path: path.to_path_buf(), source })?;
    parse_demonstration_csv(&text, path)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn parse(text: &str) -> Result<CsvDemonstration, DmpctlError> {
        parse_demonstration_csv(text, Path::new("demo.csv"))
    }

    #[test]
    fn header_or_not_the_first_column_is_time() {
        let d = parse("t,x1,x2\n0,0,1\n0.5,0.25,1.5\n1,1,2\n").unwrap();
        assert_eq!(d.t, vec![0.0, 0.5, 1.0]);
        assert_eq!(d.x, vec![vec![0.0, 1.0], vec![0.25, 1.5], vec![1.0, 2.0]]);
        let d = parse("time, shoulder, elbow, wrist\n0, 1, 2, 3\n0.1, 1, 2, 4\n").unwrap();
        assert_eq!(d.x[1], vec![1.0, 2.0, 4.0]);
        let d = parse("# recorded by hand\n\n0,5\n1,6\n").unwrap();
        assert_eq!((d.t, d.x), (vec![0.0, 1.0], vec![vec![5.0], vec![6.0]]));
    }

    #[test]
    fn a_trajectory_csv_reads_its_positions_only() {
        let d = parse("t,x1,x2,xd1,xd2,a1,a2\n0,0,0,0,0,9,9\n0.001,1e-6,2e-6,1,1,9,9\n").unwrap();
        assert_eq!(d.x, vec![vec![0.0, 0.0], vec![1e-6, 2e-6]]);
    }

    #[test]
    fn bad_files_name_the_line_and_column() {
        let e = parse("t,x1\n0,0\n0.1,oops\n").unwrap_err();
        assert!(e.is_bad_input());
        assert!(e.to_string().contains("line 3, column 2") && e.to_string().contains("oops"), "{e}");
        let e = parse("t,x1,x2\n0,0,0\n0.1,1\n").unwrap_err();
        assert!(e.to_string().contains("line 3") && e.to_string().contains("2 columns, expected 3"), "{e}");
        let e = parse("t,x1\n0,NaN\n1,1\n").unwrap_err();
        assert!(e.to_string().contains("finite"), "{e}");
        assert!(parse("t,x1\n0,1\n").unwrap_err().to_string().contains("at least 2 samples"));
        assert!(parse("t\n0\n1\n").is_err());
        assert!(parse("0\n1\n").is_err());
    }

    #[test]
    fn a_semicolon_separated_file_is_told_the_delimiter_must_be_a_comma() {
        let e = parse("t;x1;x2\n0;0;0\n1;1;1\n").unwrap_err().to_string();
        assert!(
            e.contains("line 1") && e.contains("the delimiter must be a comma") && e.contains("`;`"),
            "{e}"
        );
        let e = parse("# exported\n0;0,5\n1;1,5\n").unwrap_err().to_string();
        assert!(e.contains("line 2") && e.contains("`;`"), "{e}");
        let e = parse("t,x1\n0,0\n1;1\n").unwrap_err().to_string();
        assert!(e.contains("line 3") && e.contains("`;`"), "{e}");
        let e = parse("t\tx1\n0\t0\n1\t1\n").unwrap_err().to_string();
        assert!(e.contains("separated by tabs"), "{e}");
    }

    #[test]
    fn times_in_nanoseconds_since_the_epoch_are_named_as_such() {
        let e = parse("t,x1\n1795000000000000000,0\n1795000000010000000,1\n").unwrap_err().to_string();
        assert!(e.contains("line 2, column 1") && e.contains("nanoseconds since the Unix epoch"), "{e}");
        assert!(e.contains("2026-11-18"), "{e}");
        let e = parse("t,x1\n1795000000000000,0\n1795000000010000,1\n").unwrap_err().to_string();
        assert!(e.contains("microseconds since the Unix epoch"), "{e}");
        let e = parse("t,x1\n0,0\n2000000,1\n").unwrap_err().to_string();
        assert!(e.contains("more than a day"), "{e}");
        // Seconds since the epoch are seconds.
        assert!(parse("t,x1\n1795000000.0,0\n1795000001.0,1\n").is_ok());
    }
}
