//! The layout shows the architecture: `src/` is one folder per layer, bottom to top as `lib.rs`
//! lists them, and a module uses only its own layer and the layers below (`crate::X` paths in the
//! code, comments left out); within a layer, no two modules use each other, directly or through
//! others.

use std::collections::{BTreeMap, BTreeSet};
use std::path::Path;

/// The layers, bottom to top.
const LAYERS: [&str; 11] =
    ["support", "sim", "task", "env", "policy", "episode", "benchmark", "render", "serve", "learn", "cli"];
/// The layers that are folders of modules (the others are one module each).
const GROUPS: [&str; 5] = ["support", "sim", "episode", "benchmark", "learn"];

/// The unit a path `X::Y::...` under `crate::` (or a file's path under src/) names: `X::Y` in a
/// layer of modules, else `X`.
fn unit(parts: &[String]) -> String {
    match parts {
        [layer, module, ..] if GROUPS.contains(&layer.as_str()) => format!("{layer}::{module}"),
        [first, ..] => first.clone(),
        [] => String::new(),
    }
}

/// Every .rs file under `dir`.
fn rust_files(dir: &Path) -> Vec<std::path::PathBuf> {
    let mut out = Vec::new();
    for e in std::fs::read_dir(dir).unwrap() {
        let p = e.unwrap().path();
        if p.is_dir() {
            out.extend(rust_files(&p));
        } else if p.extension().is_some_and(|x| x == "rs") {
            out.push(p);
        }
    }
    out
}

/// Each file's unit -> the units its code names as `crate::X::Y`.
fn module_graph() -> BTreeMap<String, BTreeSet<String>> {
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let files = rust_files(&src);
    let mut graph: BTreeMap<String, BTreeSet<String>> = BTreeMap::new();
    for f in files {
        let rel: Vec<String> = f
            .strip_prefix(&src)
            .unwrap()
            .iter()
            .map(|c| c.to_string_lossy().trim_end_matches(".rs").to_owned())
            .filter(|c| c != "mod")
            .collect();
        if rel[0] == "lib" || rel[0] == "main" {
            continue;
        }
        let me = unit(&rel);
        let code: String = std::fs::read_to_string(&f)
            .unwrap()
            .lines()
            .map(|l| l.split("//").next().unwrap_or(""))
            .collect::<Vec<_>>()
            .join("\n");
        let deps = graph.entry(me.clone()).or_default();
        for (i, _) in code.match_indices("crate::") {
            let path: String =
                code[i + 7..].chars().take_while(|c| c.is_ascii_alphanumeric() || *c == '_' || *c == ':').collect();
            let parts: Vec<String> = path.split("::").filter(|p| !p.is_empty()).map(str::to_owned).collect();
            let to = unit(&parts);
            if !to.is_empty() && to != me {
                deps.insert(to);
            }
        }
    }
    graph
}

/// Every unit `from` reaches.
fn reach(graph: &BTreeMap<String, BTreeSet<String>>, from: &str) -> BTreeSet<String> {
    let (mut seen, mut todo) = (BTreeSet::new(), vec![from.to_owned()]);
    while let Some(m) = todo.pop() {
        for d in graph.get(&m).into_iter().flatten() {
            if seen.insert(d.clone()) {
                todo.push(d.clone());
            }
        }
    }
    seen
}

/// The layer of a unit (`benchmark::zoo` -> benchmark).
fn layer(unit: &str) -> usize {
    let top = unit.split("::").next().unwrap();
    LAYERS.iter().position(|l| *l == top).unwrap_or_else(|| panic!("{unit} is in no layer of {LAYERS:?}"))
}

#[test]
fn lib_lists_the_layers_bottom_to_top_and_src_holds_nothing_else() {
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let lib = std::fs::read_to_string(src.join("lib.rs")).unwrap();
    let listed: Vec<&str> =
        lib.lines().filter_map(|l| l.strip_prefix("pub mod ").and_then(|m| m.strip_suffix(';'))).collect();
    assert_eq!(listed, LAYERS, "lib.rs lists the layers in order");
    let mut top: Vec<String> =
        std::fs::read_dir(&src).unwrap().map(|e| e.unwrap().file_name().to_string_lossy().into_owned()).collect();
    top.sort();
    let mut want: Vec<String> =
        LAYERS.iter().map(|l| l.to_string()).chain(["lib.rs".into(), "main.rs".into(), "bin".into()]).collect();
    want.sort();
    assert_eq!(top, want, "src/ holds the layers' folders, lib.rs, main.rs and bin/");
    // bin/ holds the other binary, the training half of the command line (src/cli/halves.rs).
    let bins: Vec<String> = std::fs::read_dir(src.join("bin"))
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    assert_eq!(bins, ["blockpuzzle-train.rs"], "src/bin/ holds the training half's main");
    // Each layer's mod.rs opens with its part of the map: its number and name as ARCHITECTURE.md has
    // them, then a table with a row for each of its modules.
    for (i, l) in LAYERS.iter().enumerate() {
        let text = std::fs::read_to_string(src.join(l).join("mod.rs")).unwrap();
        let opening = format!("//! Layer {}, {l}", i + 1);
        assert!(text.starts_with(&opening), "src/{l}/mod.rs opens with `{opening}`");
        let doc: Vec<&str> = text.lines().take_while(|l| l.starts_with("//!")).collect();
        let modules = text.lines().filter_map(|line| {
            let line = line.trim_start_matches("pub(crate) ").trim_start_matches("pub ");
            line.strip_prefix("mod ").and_then(|m| m.strip_suffix(';'))
        });
        for m in modules {
            let row = doc
                .iter()
                .any(|d| d.starts_with("//! |") && d.split('|').nth(1).is_some_and(|c| c.contains(&format!("`{m}`"))));
            assert!(row, "src/{l}/mod.rs: its map has no row for module `{m}`");
        }
    }
}

#[test]
fn a_module_uses_only_its_own_layer_and_the_ones_below() {
    let graph = module_graph();
    assert!(graph.contains_key("benchmark::saved") && graph.contains_key("benchmark::zoo"), "{graph:?}");
    let upward: Vec<String> = graph
        .iter()
        .flat_map(|(a, deps)| deps.iter().map(move |b| (a, b)))
        .filter(|(a, b)| layer(b) > layer(a))
        .map(|(a, b)| format!("{a} (layer {}) uses {b} (layer {})", LAYERS[layer(a)], LAYERS[layer(b)]))
        .collect();
    assert!(upward.is_empty(), "imports that run up a layer: {upward:#?}");
}

#[test]
fn the_module_graph_has_no_cycle() {
    let graph = module_graph();
    let cycles: Vec<String> = graph
        .iter()
        .flat_map(|(a, deps)| deps.iter().map(move |b| (a, b)))
        .filter(|(a, b)| reach(&graph, b).contains(*a))
        .map(|(a, b)| format!("{a} -> {b} -> ... -> {a}"))
        .collect();
    assert!(cycles.is_empty(), "module cycles: {cycles:#?}");
}

/// Inside agents/, imports go one way: the interface (algorithm.rs) and the shared settings
/// (shared.rs) name no algorithm, the algorithm files do not name the list of them
/// (registry.rs), and the list names every algorithm file.
#[test]
fn the_algorithm_interface_knows_no_algorithm_and_no_algorithm_knows_the_list() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("src/learn/agents");
    let read = |f: &str| std::fs::read_to_string(dir.join(f)).unwrap();
    let registry = read("registry.rs");
    let files = ["ddpg", "pggd", "sac", "bc", "dagger"];
    let algorithms: Vec<&str> =
        files.into_iter().filter(|a| registry.contains(&format!("{a}: super::{a}::"))).collect();
    assert_eq!(algorithms, files, "registry.rs lists every algorithm file");
    let names = |text: &str, module: &str| {
        text.contains(&format!("super::{module}::")) || text.contains(&format!("agents::{module}::"))
    };
    for interface in ["algorithm.rs", "shared.rs"] {
        let text = read(interface);
        for a in algorithms.iter().copied().chain(["registry"]) {
            assert!(!names(&text, a), "{interface} names {a}");
        }
    }
    for a in &algorithms {
        let text = read(&format!("{a}.rs"));
        assert!(!names(&text, "registry"), "{a}.rs names the registry");
        for other in algorithms.iter().filter(|o| *o != a) {
            // SAC exports its mean action as the core's tanh actor (crate::policy::actor), not DDPG's learner.
            assert!(!names(&text, other), "{a}.rs names {other}");
        }
    }
}

/// One path per type: outside lib.rs (the crate's public face), a `pub use` only presents an item
/// of a private file of the same folder (`mod x;` beside `pub use x::...`), so nothing is reachable
/// under two public paths; an alias of another module's item (`pub use crate::...`) is refused.
#[test]
fn no_type_has_two_public_paths() {
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let files = rust_files(&src);
    let mut bad = Vec::new();
    for f in files.iter().filter(|f| !f.ends_with("src/lib.rs")) {
        let text = std::fs::read_to_string(f).unwrap();
        for line in text.lines().map(str::trim_start).filter(|l| l.starts_with("pub use ")) {
            let from = line["pub use ".len()..].split("::").next().unwrap_or("");
            let private = text.lines().any(|l| l.trim() == format!("mod {from};"));
            if !private {
                bad.push(format!("{}: {line}", f.strip_prefix(&src).unwrap().display()));
            }
        }
    }
    assert!(bad.is_empty(), "re-exports that give an item a second public path: {bad:#?}");
}
