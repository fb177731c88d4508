//! The documentation names only what exists: every relative link in `README.md`, `BENCHMARKS.md` and `docs/*.md`
//! leads to a file or folder of the repository, and every repository path they name exists. A path is a code span
//! (or, in fenced code, a word) made of letters, digits, `_`, `-`, `.` and `/` that holds a `/` and ends with a file
//! extension or a `/`: `deploy/compose.yaml`, `dmp/src/execution/`. Code spans are read from the repository's root;
//! words of fenced code only when they begin with a folder of the root (commands name outputs and temporary files
//! too). Outputs (`out/`, `target/`) and placeholders (`<dir>/load.json`) are not the repository's and are left out.
//! Links carry no anchor: an anchor could not be checked without rendering the headings as a Markdown renderer does.
//!
//! The README's test command is the one `.ci/run` runs, verbatim.

use std::path::{Path, PathBuf};

/// The first folders of paths that a run writes, not the repository's.
const OUTPUTS: [&str; 2] = ["out", "target"];

/// The repository's root (the tests crate is `tests/`).
fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("..")
}

/// The documents checked, from the root: the README, BENCHMARKS.md and every page of `docs/`.
fn documents() -> Vec<PathBuf> {
    let mut pages: Vec<PathBuf> = std::fs::read_dir(root().join("docs"))
        .expect("the folder docs/")
        .map(|entry| entry.expect("a folder entry").path())
        .filter(|path| path.extension().is_some_and(|ext| ext == "md"))
        .map(|path| Path::new("docs").join(path.file_name().expect("a file name")))
        .collect();
    pages.sort();
    let mut documents = vec![PathBuf::from("README.md"), PathBuf::from("BENCHMARKS.md")];
    documents.extend(pages);
    documents
}

/// The text of `document` (from the root).
fn read(document: &Path) -> String {
    std::fs::read_to_string(root().join(document))
        .unwrap_or_else(|e| panic!("cannot read {}: {e}", document.display()))
}

/// What a document names, by kind.
#[derive(Debug, Default)]
struct Names {
    /// Link targets, as written (`docs/server.md`, `../BENCHMARKS.md`), with their line.
    links: Vec<(usize, String)>,
    /// Code spans of prose, with their line.
    spans: Vec<(usize, String)>,
    /// Words of fenced code, with their line.
    words: Vec<(usize, String)>,
}

/// The code spans of one line of prose: `(start, end)` byte ranges of their contents, each between two runs of
/// the same number of backticks (`` `a` ``, ``` ``a `b` c`` ```). A run without its closing run is text.
fn code_spans(line: &str) -> Vec<(usize, usize)> {
    let bytes = line.as_bytes();
    let mut runs = Vec::new();
    let mut i = 0;
    while i < bytes.len() {
        if bytes[i] == b'`' {
            let start = i;
            while i < bytes.len() && bytes[i] == b'`' {
                i += 1;
            }
            runs.push((start, i - start));
        } else {
            i += 1;
        }
    }
    let mut spans = Vec::new();
    let mut k = 0;
    while k < runs.len() {
        let (open, n) = runs[k];
        match (k + 1..runs.len()).find(|&j| runs[j].1 == n) {
            Some(j) => {
                spans.push((open + n, runs[j].0));
                k = j + 1;
            }
            None => k += 1,
        }
    }
    spans
}

/// The targets of the inline links `[text](target)` of one line of prose, code spans left out.
fn link_targets(line: &str) -> Vec<String> {
    let mut prose = line.to_owned();
    for (start, end) in code_spans(line) {
        prose.replace_range(start..end, &" ".repeat(end - start));
    }
    let mut targets = Vec::new();
    let mut rest = prose.as_str();
    while let Some(at) = rest.find("](") {
        rest = &rest[at + 2..];
        let end = rest.find(')').unwrap_or(rest.len());
        let target = rest[..end].split_whitespace().next().unwrap_or("");
        targets.push(target.to_owned());
        rest = &rest[end..];
    }
    targets
}

/// Everything `text` names: links and code spans of its prose, words of its fenced code.
fn names(text: &str) -> Names {
    let mut names = Names::default();
    let mut fenced = false;
    for (index, line) in text.lines().enumerate() {
        let number = index + 1;
        if line.trim_start().starts_with("```") {
            fenced = !fenced;
            continue;
        }
        if fenced {
            for word in line.split_whitespace() {
                let word = word.trim_matches(|c: char| "\"'`()[]{},;:".contains(c));
                names.words.push((number, word.to_owned()));
            }
            continue;
        }
        for (start, end) in code_spans(line) {
            names.spans.push((number, line[start..end].trim().to_owned()));
        }
        for target in link_targets(line) {
            names.links.push((number, target));
        }
    }
    names
}

/// Whether `word` is written as a path of a file or folder: letters, digits, `_`, `-`, `.` and `/` only, a `/`, not
/// absolute, and a file extension or a `/` at the end.
fn looks_like_path(word: &str) -> bool {
    let allowed = |c: char| c.is_ascii_alphanumeric() || "_-./".contains(c);
    if word.is_empty() || !word.chars().all(allowed) || !word.contains('/') || word.starts_with('/') {
        return false;
    }
    if word.ends_with('/') {
        return true;
    }
    let last = word.rsplit('/').next().unwrap_or("");
    match last.rsplit_once('.') {
        Some((stem, ext)) => {
            !stem.is_empty() && !ext.is_empty() && ext.chars().all(|c| c.is_ascii_alphanumeric())
        }
        None => false,
    }
}

/// The first folder of `path`.
fn first_folder(path: &str) -> &str {
    path.split('/').next().unwrap_or("")
}

/// Whether `path` is one a run writes (`out/...`, `target/...`).
fn is_output(path: &str) -> bool {
    OUTPUTS.contains(&first_folder(path))
}

/// What is wrong with the names of `document`: links that lead nowhere or carry an anchor, paths that do not exist.
fn problems(document: &Path, text: &str) -> Vec<String> {
    let root = root();
    let folder = document.parent().unwrap_or(Path::new(""));
    let names = names(text);
    let at = |line: &usize| format!("{}:{line}", document.display());
    let mut problems = Vec::new();
    for (line, target) in &names.links {
        if target.contains("://") || target.starts_with("mailto:") {
            continue;
        }
        if target.contains('#') {
            problems.push(format!("{}: link `{target}` has an anchor: link the page alone", at(line)));
        } else if target.is_empty() || !root.join(folder).join(target).exists() {
            problems.push(format!("{}: link `{target}` leads to no file", at(line)));
        }
    }
    for (line, span) in &names.spans {
        if looks_like_path(span) && !is_output(span) && !root.join(span).exists() {
            problems.push(format!("{}: `{span}` does not exist", at(line)));
        }
    }
    for (line, word) in &names.words {
        let of_the_repository = root.join(first_folder(word)).is_dir() && !is_output(word);
        if looks_like_path(word) && of_the_repository && !root.join(word).exists() {
            problems.push(format!("{}: `{word}` (in a command) does not exist", at(line)));
        }
    }
    problems
}

#[test]
fn every_link_and_path_of_the_documentation_exists() {
    let documents = documents();
    assert!(documents.len() > 2, "no page in docs/");
    let found: Vec<String> = documents.iter().flat_map(|d| problems(d, &read(d))).collect();
    assert!(found.is_empty(), "the documentation names what does not exist:\n{}", found.join("\n"));
}

#[test]
fn every_page_of_the_documentation_is_linked_from_the_readme() {
    let readme = names(&read(Path::new("README.md")));
    for page in documents().iter().filter(|d| d.starts_with("docs")) {
        let page = page.to_str().expect("a UTF-8 path");
        assert!(readme.links.iter().any(|(_, target)| target == page), "README.md does not link {page}");
    }
}

#[test]
fn ci_runs_the_readmes_test_command_verbatim() {
    let ci = read(Path::new(".ci/run"));
    let readme = read(Path::new("README.md"));
    let commands: Vec<&str> = readme.lines().filter(|l| l.starts_with("apt-get update")).collect();
    assert_eq!(
        commands.len(),
        1,
        "README.md should give one test command (a line starting with apt-get update)"
    );
    let ran = ci.lines().find(|l| l.starts_with("apt-get update")).expect("the test command in .ci/run");
    assert!(ran.starts_with(commands[0]), ".ci/run does not run the README's test command:\n{ran}");
    assert_eq!(
        ran[commands[0].len()..].trim(),
        "|| exit 1",
        ".ci/run adds to the README's test command:\n{ran}"
    );
}

#[test]
fn the_check_reads_code_spans_links_and_commands() {
    let text = "See [the server](server.md) and `dmp/src/lib.rs`, ``a `b` c``, `tls/<host>:7447`.\n\
                ```sh\n\
                target/release/dmpctl learn --scenario scenarios/x.json --out out/y\n\
                ```\n\
                [a link in `code](x.md)` is no link](y.md)";
    let names = names(text);
    let spans: Vec<&str> = names.spans.iter().map(|(_, s)| s.as_str()).collect();
    assert_eq!(spans, ["dmp/src/lib.rs", "a `b` c", "tls/<host>:7447", "code](x.md)"]);
    let links: Vec<&str> = names.links.iter().map(|(_, l)| l.as_str()).collect();
    assert_eq!(links, ["server.md", "y.md"]);
    assert!(names.words.iter().any(|(line, w)| *line == 3 && w == "scenarios/x.json"));
}

#[test]
fn a_path_is_a_word_with_a_slash_and_an_extension_or_a_trailing_slash() {
    for path in ["deploy/compose.yaml", "dmp/src/execution/", "deploy/zenoh-lease.json5", ".ci/run/"] {
        assert!(looks_like_path(path), "{path}");
    }
    for word in [
        "compose.yaml",
        "dmp/<cell>/obstacles/<id>",
        "tcp/127.0.0.1:7447",
        "/tmp/box.json",
        "proto/dmp/v1/*.proto",
        "out/stream",
        "m/s",
        "scenarios/paper-one-obstacle/$m.json",
    ] {
        assert!(!looks_like_path(word), "{word}");
    }
    assert!(is_output("out/stream/plot.svg") && is_output("target/release/"));
    assert!(!is_output("scenarios/bench-3d-ten-dynamic-volumetric.json"));
}

#[test]
fn a_missing_path_or_link_is_a_problem() {
    let text = "`dmp/src/no_such_file.rs` and [gone](no-such-page.md) and [anchor](server.md#cells)\n\
                `out/stream/plot.svg` and `dmp/src/` and [readme](../README.md)";
    let found = problems(Path::new("docs/page.md"), text);
    assert_eq!(found.len(), 3, "{found:?}");
    assert!(found[0].contains("no-such-page.md") && found[1].contains("anchor"), "{found:?}");
    assert!(
        found[2].contains("dmp/src/no_such_file.rs") && found[2].starts_with("docs/page.md:1"),
        "{found:?}"
    );
}
