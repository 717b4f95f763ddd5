//! The layout ARCHITECTURE.md draws, checked on the source: the top-level modules of the hgym
//! crate depend on each other without cycles, and `env` and `validate` both build on `flow`,
//! never on each other.

use std::collections::{BTreeMap, BTreeSet};

mod common;
use common::{files_under, repo};

/// Every `crate::<module>` a file names (its `use` lines and inline paths).
fn named_modules(text: &str, modules: &BTreeSet<String>) -> BTreeSet<String> {
    let mut found = BTreeSet::new();
    for (i, _) in text.match_indices("crate::") {
        let rest = &text[i + "crate::".len()..];
        let name: String = rest.chars().take_while(|c| c.is_ascii_alphanumeric() || *c == '_').collect();
        if modules.contains(&name) {
            found.insert(name);
        }
    }
    found
}

/// Module -> the other top-level modules it names.
fn graph() -> BTreeMap<String, BTreeSet<String>> {
    let src = repo().join("src");
    let lib = std::fs::read_to_string(src.join("lib.rs")).unwrap();
    let modules: BTreeSet<String> = lib
        .lines()
        .filter_map(|l| l.strip_prefix("pub mod "))
        .map(|m| m.trim_end_matches(';').to_string())
        .collect();
    assert!(modules.contains("flow") && modules.contains("env"), "{modules:?}");
    let mut g = BTreeMap::new();
    for m in &modules {
        let dir = src.join(m);
        let files = if dir.is_dir() {
            files_under(&dir, &|p| p.extension().is_some_and(|x| x == "rs"))
        } else {
            vec![src.join(format!("{m}.rs"))]
        };
        let mut deps = BTreeSet::new();
        for f in files {
            deps.extend(named_modules(&std::fs::read_to_string(f).unwrap(), &modules));
        }
        deps.remove(m);
        g.insert(m.clone(), deps);
    }
    g
}

/// A cycle in `g` as `a -> b -> a`, if there is one (depth-first search with a path stack: a
/// dependency already on the stack closes a cycle).
fn find_cycle(g: &BTreeMap<String, BTreeSet<String>>) -> Option<String> {
    fn visit(m: &str, g: &BTreeMap<String, BTreeSet<String>>, stack: &mut Vec<String>, done: &mut BTreeSet<String>) -> Option<String> {
        if let Some(i) = stack.iter().position(|s| s == m) {
            return Some(format!("{} -> {m}", stack[i..].join(" -> ")));
        }
        if done.contains(m) {
            return None;
        }
        stack.push(m.to_string());
        for d in &g[m] {
            if let Some(c) = visit(d, g, stack, done) {
                return Some(c);
            }
        }
        stack.pop();
        done.insert(m.to_string());
        None
    }
    let mut done = BTreeSet::new();
    g.keys().find_map(|m| visit(m, g, &mut vec![], &mut done))
}

#[test]
fn top_level_modules_have_no_import_cycle() {
    let g = graph();
    assert_eq!(find_cycle(&g), None, "{g:#?}");
}

#[test]
fn env_and_validate_build_on_flow_and_not_on_each_other() {
    let g = graph();
    assert!(!g["env"].contains("validate"), "env imports validate: {:?}", g["env"]);
    assert!(!g["validate"].contains("env"), "validate imports env: {:?}", g["validate"]);
    assert!(g["env"].contains("flow") && g["validate"].contains("flow"));
    assert!(g["flow"].is_empty(), "flow depends on {:?}", g["flow"]);
}

/// The checker itself: a cycle planted in a synthetic graph is found.
#[test]
fn the_cycle_check_finds_a_planted_cycle() {
    let modules: BTreeSet<String> = ["a", "b", "c"].iter().map(|s| s.to_string()).collect();
    let mut g = BTreeMap::new();
    g.insert("a".to_string(), named_modules("use crate::b::X;", &modules));
    g.insert("b".to_string(), named_modules("fn f() { crate::c::y() }", &modules));
    g.insert("c".to_string(), BTreeSet::new());
    assert_eq!(find_cycle(&g), None);
    g.insert("c".to_string(), named_modules("use crate::a;", &modules));
    assert_eq!(find_cycle(&g).as_deref(), Some("a -> b -> c -> a"));
}
