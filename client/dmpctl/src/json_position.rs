//! Where a value is in a JSON text: the line and column (from 1) of the value at a field path such as
//! `obstacles[0].semi_axes[1]`, so that an error about a value can point at it in the file, whichever check found
//! it (the parser, a type, or a rule checked after parsing).

/// A parser's message without its trailing ` at line L column C` (the position is given apart).
pub(crate) fn without_position(message: &str) -> String {
    match message.rfind(" at line ") {
        Some(i) if message[i..].contains(" column ") => message[..i].to_string(),
        _ => message.to_string(),
    }
}

/// One step of a field path.
#[derive(Debug, PartialEq)]
enum Step<'a> {
    Key(&'a str),
    Index(usize),
}

/// The steps of `obstacles[0].semi_axes[1]`; None when the path is not of that form (e.g. `(document)`).
fn steps(path: &str) -> Option<Vec<Step<'_>>> {
    let mut out = Vec::new();
    for part in path.split('.') {
        let (key, mut rest) = part.split_once('[').map_or((part, ""), |(k, r)| (k, r));
        if !key.is_empty() {
            out.push(Step::Key(key));
        }
        while !rest.is_empty() {
            let (index, after) = rest.split_once(']')?;
            out.push(Step::Index(index.parse().ok()?));
            rest = after.strip_prefix('[').unwrap_or(after);
            if !after.is_empty() && !after.starts_with('[') {
                return None;
            }
        }
    }
    (!out.is_empty()).then_some(out)
}

/// A cursor over the text that skips whitespace and whole values.
struct Cursor<'t> {
    bytes: &'t [u8],
    at: usize,
}

impl Cursor<'_> {
    fn skip_ws(&mut self) {
        while self.at < self.bytes.len() && self.bytes[self.at].is_ascii_whitespace() {
            self.at += 1;
        }
    }

    fn eat(&mut self, b: u8) -> Option<()> {
        self.skip_ws();
        (self.bytes.get(self.at) == Some(&b)).then(|| self.at += 1)
    }

    /// A string's content (escapes kept as written), the cursor after its closing quote.
    fn string(&mut self) -> Option<&str> {
        self.eat(b'"')?;
        let start = self.at;
        while *self.bytes.get(self.at)? != b'"' {
            self.at += if self.bytes[self.at] == b'\\' { 2 } else { 1 };
        }
        self.at += 1;
        std::str::from_utf8(&self.bytes[start..self.at - 1]).ok()
    }

    /// Skips one value of any kind.
    fn skip_value(&mut self) -> Option<()> {
        self.skip_ws();
        match *self.bytes.get(self.at)? {
            b'"' => self.string().map(drop),
            open @ (b'{' | b'[') => {
                let close = if open == b'{' { b'}' } else { b']' };
                self.at += 1;
                loop {
                    self.skip_ws();
                    if self.bytes.get(self.at) == Some(&close) {
                        self.at += 1;
                        return Some(());
                    }
                    if open == b'{' {
                        self.string()?;
                        self.eat(b':')?;
                    }
                    self.skip_value()?;
                    self.skip_ws();
                    if self.bytes.get(self.at) == Some(&b',') {
                        self.at += 1;
                    }
                }
            }
            _ => {
                // A number or a literal (true, false, null, NaN ...): up to the next delimiter.
                let start = self.at;
                while self.at < self.bytes.len() && !b",]} \t\r\n".contains(&self.bytes[self.at]) {
                    self.at += 1;
                }
                (self.at > start).then_some(())
            }
        }
    }

    /// Moves to the value of `step` inside the container at the cursor.
    fn enter(&mut self, step: &Step<'_>) -> Option<()> {
        match step {
            Step::Key(key) => {
                self.eat(b'{')?;
                loop {
                    let k = self.string()?.to_owned();
                    self.eat(b':')?;
                    if k == *key {
                        self.skip_ws();
                        return Some(());
                    }
                    self.skip_value()?;
                    self.eat(b',')?;
                }
            }
            Step::Index(i) => {
                self.eat(b'[')?;
                for _ in 0..*i {
                    self.skip_value()?;
                    self.eat(b',')?;
                }
                self.skip_ws();
                Some(())
            }
        }
    }
}

/// The line and column (from 1, the column in characters) where the value at `field` starts in `text`; None when
/// the path has no such value or the text is not plain JSON there.
pub(crate) fn locate(text: &str, field: &str) -> Option<(usize, usize)> {
    let mut c = Cursor { bytes: text.as_bytes(), at: 0 };
    for step in steps(field)? {
        c.enter(&step)?;
    }
    let before = &text[..c.at];
    let line = before.matches('\n').count() + 1;
    let column = before.rsplit('\n').next().map_or(0, |l| l.chars().count()) + 1;
    Some((line, column))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn values_are_found_by_their_path() {
        let text = "{\n  \"name\": \"a\",\n  \"obstacles\": [\n    {\"id\": \"o\", \"semi_axes\": [0.3, \"wide\"]}\n  ]\n}";
        assert_eq!(locate(text, "obstacles[0].semi_axes[1]"), Some((4, 36)));
        assert_eq!(locate(text, "obstacles[0]"), Some((4, 5)));
        assert_eq!(locate(text, "name"), Some((2, 11)));
        assert_eq!(locate(text, "obstacles[1]"), None);
        assert_eq!(locate(text, "missing"), None);
        assert_eq!(locate(text, "(document)"), None);
        assert_eq!(
            steps("a[2][3].b"),
            Some(vec![Step::Key("a"), Step::Index(2), Step::Index(3), Step::Key("b")])
        );
    }
}
