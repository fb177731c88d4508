//! `NaN` and `Infinity` in a JSON file: JSON has no such values, and the parser only says "expected value". This
//! finds the token where the parser stopped and the field it is the value of, so that the error names them.

use serde_json::Value;

/// The words that are numbers to some writers (Python's `json.dumps`, JavaScript) but not in JSON.
const NON_FINITE: [&str; 6] = ["-Infinity", "Infinity", "NaN", "-inf", "inf", "nan"];

/// A number no file holds, put in place of the token to find the field it stands at.
const SENTINEL: &str = "-1.2345678901234567e-300";

/// When the parser stopped at `line`, `column` (from 1) on `NaN`, `Infinity` or `-Infinity`: the token and the
/// field path it is the value of (`obstacles[0].center[1]`, or `(document)` when it cannot be told).
pub(crate) fn non_finite_at(text: &str, line: usize, column: usize) -> Option<(String, String)> {
    let line_start: usize = text.split_inclusive('\n').take(line.saturating_sub(1)).map(str::len).sum();
    let line_text = text[line_start..].split('\n').next()?;
    // The parser's column is at or just after the token's first character; look at both, and take a `-` before.
    let (mut offset, mut token) =
        [column.saturating_sub(1), column.saturating_sub(2)].iter().find_map(|&c| {
            let rest = line_text.get(c..)?;
            NON_FINITE.iter().find(|t| rest.starts_with(*t)).map(|t| (line_start + c, t.to_string()))
        })?;
    if !token.starts_with('-') && offset > 0 && text.as_bytes()[offset - 1] == b'-' {
        offset -= 1;
        token.insert(0, '-');
    }
    let mut replaced = String::with_capacity(text.len());
    replaced.push_str(&text[..offset]);
    replaced.push_str(SENTINEL);
    replaced.push_str(&text[offset + token.len()..]);
    let field = serde_json::from_str::<Value>(&replaced)
        .ok()
        .and_then(|v| path_of_sentinel(&v, String::new()))
        .unwrap_or_else(|| "(document)".to_string());
    Some((token, field))
}

/// The error of serde_json's `e` on `text` (from `path`): at `NaN` or `Infinity`, naming the field and saying
/// that JSON has none; else the parser's words, at its line and column.
pub(crate) fn json_error(path: &std::path::Path, text: &str, e: &serde_json::Error) -> crate::DmpctlError {
    let (field, message) = match non_finite_at(text, e.line(), e.column()) {
        Some((token, field)) => (field, non_finite_message(&token)),
        None => ("(document)".to_string(), crate::json_position::without_position(&e.to_string())),
    };
    crate::DmpctlError::Parse {
        path: path.to_path_buf(),
        position: Some((e.line(), e.column())),
        field,
        message,
    }
}

/// The message for `token`.
pub(crate) fn non_finite_message(token: &str) -> String {
    format!("`{token}` is not a number in JSON (JSON has no NaN or Infinity): write a finite number")
}

/// The path of the sentinel in `v`.
fn path_of_sentinel(v: &Value, at: String) -> Option<String> {
    let sentinel: f64 = SENTINEL.parse().ok()?;
    match v {
        Value::Number(n) if n.as_f64() == Some(sentinel) => Some(at),
        Value::Array(items) => {
            items.iter().enumerate().find_map(|(i, x)| path_of_sentinel(x, format!("{at}[{i}]")))
        }
        Value::Object(map) => map.iter().find_map(|(k, x)| {
            path_of_sentinel(x, if at.is_empty() { k.clone() } else { format!("{at}.{k}") })
        }),
        _ => None,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The token and field where serde_json stops on `text`.
    fn found(text: &str) -> Option<(String, String)> {
        let e = serde_json::from_str::<Value>(text).unwrap_err();
        non_finite_at(text, e.line(), e.column())
    }

    #[test]
    fn nan_and_infinity_are_found_with_their_field() {
        let text = "{\"obstacles\": [\n  {\"id\": \"a\", \"center\": [0, NaN], \"semi_axes\": [1, 1]}\n]}";
        assert_eq!(found(text), Some(("NaN".into(), "obstacles[0].center[1]".into())));
        assert_eq!(found(r#"{"ttl_s": Infinity}"#), Some(("Infinity".into(), "ttl_s".into())));
        assert_eq!(found(r#"{"v": [-Infinity]}"#), Some(("-Infinity".into(), "v[0]".into())));
    }

    #[test]
    fn other_syntax_errors_are_not_taken_for_them() {
        assert_eq!(found(r#"{"v": [1,, 2]}"#), None);
        assert_eq!(found(r#"{"v": nope}"#), None);
    }
}
