//! The modules of every crate form layers: no import cycle between two modules (one module a file), read from the
//! `crate::` and `super::` paths of each file's non-test code. A parent's declaration or re-export of its own child
//! is not an edge, nor a child's reach to its own parent. A cycle fails with the modules that form it.

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

/// The source folders checked, from the workspace's root.
const CRATES: [&str; 8] = [
    "dmp/src",
    "proto/src",
    "server/src",
    "client/src",
    "client/plot/src",
    "client/dmpctl/src",
    "client/sim/src",
    "ros2/src",
];

type Module = Vec<String>;

/// Every module of `src` (a file each; `mod.rs`, `lib.rs` and `main.rs` name their folder), with its file; binaries
/// and test files left out.
fn modules(src: &Path) -> BTreeMap<Module, PathBuf> {
    let mut found = BTreeMap::new();
    let mut folders = vec![src.to_path_buf()];
    while let Some(folder) = folders.pop() {
        for entry in std::fs::read_dir(&folder).expect("a readable source folder") {
            let path = entry.expect("a folder entry").path();
            if path.is_dir() {
                folders.push(path);
                continue;
            }
            if path.extension().is_none_or(|e| e != "rs") {
                continue;
            }
            let relative = path.strip_prefix(src).expect("under src").with_extension("");
            let mut module: Module = relative.iter().map(|p| p.to_string_lossy().into_owned()).collect();
            if matches!(module.last().map(String::as_str), Some("mod" | "lib" | "main")) {
                module.pop();
            }
            let test_file = module.iter().any(|p| p == "tests" || p.ends_with("_tests"));
            if module.first().is_some_and(|p| p == "bin") || test_file {
                continue;
            }
            found.insert(module, path);
        }
    }
    found
}

/// The file's code before its first `#[cfg(test)]`, without line comments.
fn code(path: &Path) -> String {
    let text = std::fs::read_to_string(path).expect("a readable source file");
    let text = text.find("#[cfg(test)]").map_or(text.as_str(), |i| &text[..i]);
    text.lines().map(|l| l.find("//").map_or(l, |i| &l[..i])).collect::<Vec<_>>().join("\n")
}

/// The `crate::a::b` and `super::a` paths of `text`, split at `::`.
fn paths(text: &str) -> Vec<Vec<String>> {
    let bytes = text.as_bytes();
    let word = |b: u8| b.is_ascii_alphanumeric() || b == b'_';
    let mut found = Vec::new();
    let mut i = 0;
    while i < bytes.len() {
        if !text.is_char_boundary(i) {
            i += 1;
            continue;
        }
        let starts = (text[i..].starts_with("crate::") || text[i..].starts_with("super::"))
            && (i == 0 || !word(bytes[i - 1]));
        if !starts {
            i += 1;
            continue;
        }
        let mut end = i;
        while end < bytes.len() && (word(bytes[end]) || text[end..].starts_with("::")) {
            end += if text[end..].starts_with("::") { 2 } else { 1 };
        }
        found.push(text[i..end].split("::").filter(|p| !p.is_empty()).map(str::to_owned).collect());
        i = end;
    }
    found
}

/// Each module's imports of other modules of its crate.
fn edges(mods: &BTreeMap<Module, PathBuf>) -> BTreeMap<Module, BTreeSet<Module>> {
    let mut edges = BTreeMap::new();
    for (module, file) in mods {
        let mut targets = BTreeSet::new();
        for path in paths(&code(file)) {
            let (mut base, mut rest) = (Vec::new(), &path[..]);
            if rest[0] == "crate" {
                rest = &rest[1..];
            } else {
                base = module.clone();
                while rest.first().is_some_and(|p| p == "super") {
                    base.pop();
                    rest = &rest[1..];
                }
            }
            let target = (0..=rest.len())
                .rev()
                .map(|k| [&base[..], &rest[..k]].concat())
                .find(|c| mods.contains_key(c));
            let Some(target) = target else { continue };
            let related = module.starts_with(&target) || target.starts_with(module);
            if !related {
                targets.insert(target);
            }
        }
        edges.insert(module.clone(), targets);
    }
    edges
}

/// The groups of two or more modules that import each other, directly or not (Tarjan's strongly connected
/// components).
fn cycles(edges: &BTreeMap<Module, BTreeSet<Module>>) -> Vec<Vec<Module>> {
    struct Search<'a> {
        edges: &'a BTreeMap<Module, BTreeSet<Module>>,
        index: BTreeMap<&'a Module, usize>,
        low: BTreeMap<&'a Module, usize>,
        stack: Vec<&'a Module>,
        found: Vec<Vec<Module>>,
    }
    impl<'a> Search<'a> {
        fn visit(&mut self, v: &'a Module) {
            let n = self.index.len();
            self.index.insert(v, n);
            self.low.insert(v, n);
            self.stack.push(v);
            for w in &self.edges[v] {
                if !self.index.contains_key(w) {
                    self.visit(w);
                    let low = self.low[v].min(self.low[w]);
                    self.low.insert(v, low);
                } else if self.stack.contains(&w) {
                    let low = self.low[v].min(self.index[w]);
                    self.low.insert(v, low);
                }
            }
            if self.low[v] == self.index[v] {
                let mut component = Vec::new();
                while let Some(w) = self.stack.pop() {
                    component.push(w.clone());
                    if w == v {
                        break;
                    }
                }
                if component.len() > 1 {
                    component.sort();
                    self.found.push(component);
                }
            }
        }
    }
    let mut search =
        Search { edges, index: BTreeMap::new(), low: BTreeMap::new(), stack: Vec::new(), found: Vec::new() };
    for v in edges.keys() {
        if !search.index.contains_key(v) {
            search.visit(v);
        }
    }
    search.found
}

fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).parent().expect("the workspace's root").to_path_buf()
}

#[test]
fn no_crate_has_an_import_cycle_between_its_modules() {
    let mut report = Vec::new();
    for krate in CRATES {
        let mods = modules(&root().join(krate));
        assert!(mods.len() > 1, "{krate}: no modules found");
        for cycle in cycles(&edges(&mods)) {
            let names: Vec<String> = cycle.iter().map(|m| m.join("::")).collect();
            report.push(format!("{krate}: {}", names.join(", ")));
        }
    }
    assert!(report.is_empty(), "import cycles between modules:\n{}", report.join("\n"));
}

#[test]
fn a_cycle_is_found_and_a_child_reaching_its_parent_is_not_one() {
    let m = |s: &str| -> Module { s.split("::").filter(|p| !p.is_empty()).map(str::to_owned).collect() };
    let graph: BTreeMap<Module, BTreeSet<Module>> = [
        (m("a"), [m("b")].into()),
        (m("b"), [m("c")].into()),
        (m("c"), [m("a")].into()),
        (m("d"), [].into()),
    ]
    .into();
    assert_eq!(cycles(&graph), vec![vec![m("a"), m("b"), m("c")]]);
    // The paths of a file, and how they resolve: `super::` climbs, a parent is not an edge.
    assert_eq!(
        paths("use crate::x::Y; use super::super::z;"),
        vec![vec!["crate", "x", "Y"], vec!["super", "super", "z"]]
    );
    let dir = tempfile::tempdir().unwrap();
    std::fs::create_dir_all(dir.path().join("p")).unwrap();
    std::fs::write(dir.path().join("lib.rs"), "mod p;").unwrap();
    std::fs::write(dir.path().join("p/mod.rs"), "mod q; use crate::r::R;").unwrap();
    std::fs::write(dir.path().join("p/q.rs"), "use super::P; use crate::r::R;").unwrap();
    std::fs::write(dir.path().join("r.rs"), "use crate::p::q::Q;\n#[cfg(test)]\nuse crate::p::P;").unwrap();
    let e = edges(&modules(dir.path()));
    assert_eq!(e[&m("p::q")], [m("r")].into());
    assert_eq!(e[&m("r")], [m("p::q")].into(), "test code is not an edge");
    assert_eq!(cycles(&e), vec![vec![m("p::q"), m("r")]]);
}
