//! The layout shows the architecture: no two top-level modules of src/ use
//! each other, directly or through others (`crate::X` paths in the code,
//! comments left out), and the environment core uses nothing of the
//! training stack.

use std::collections::{BTreeMap, BTreeSet};
use std::path::Path;

/// Top-level module -> the top-level modules its code names as `crate::X`.
fn module_graph() -> BTreeMap<String, BTreeSet<String>> {
    fn walk(dir: &Path, files: &mut Vec<std::path::PathBuf>) {
        for e in std::fs::read_dir(dir).unwrap() {
            let p = e.unwrap().path();
            if p.is_dir() {
                walk(&p, files);
            } else if p.extension().is_some_and(|x| x == "rs") {
                files.push(p);
            }
        }
    }
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let mut files = Vec::new();
    walk(&src, &mut files);
    let mut graph: BTreeMap<String, BTreeSet<String>> = BTreeMap::new();
    for f in files {
        let rel = f.strip_prefix(&src).unwrap();
        let top = rel.iter().next().unwrap().to_string_lossy().trim_end_matches(".rs").to_owned();
        if top == "lib" || top == "main" {
            continue;
        }
        let code: String = std::fs::read_to_string(&f)
            .unwrap()
            .lines()
            .map(|l| l.split("//").next().unwrap_or(""))
            .collect::<Vec<_>>()
            .join("\n");
        let deps = graph.entry(top.clone()).or_default();
        for (i, _) in code.match_indices("crate::") {
            let name: String = code[i + 7..].chars().take_while(|c| c.is_ascii_alphanumeric() || *c == '_').collect();
            if !name.is_empty() && name != top {
                deps.insert(name);
            }
        }
    }
    graph
}

/// Every module `from` reaches.
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

#[test]
fn the_module_graph_has_no_cycle() {
    let graph = module_graph();
    assert!(graph.contains_key("saved") && graph.contains_key("zoo"), "{graph:?}");
    let cycles: Vec<String> = graph
        .iter()
        .flat_map(|(a, deps)| deps.iter().map(move |b| (a, b)))
        .filter(|(a, b)| reach(&graph, b).contains(*a))
        .map(|(a, b)| format!("{a} -> {b} -> ... -> {a}"))
        .collect();
    assert!(cycles.is_empty(), "module cycles: {cycles:#?}");
}

#[test]
fn the_environment_core_uses_nothing_of_the_training_stack() {
    let graph = module_graph();
    let core = [
        "actor",
        "align",
        "check",
        "diff",
        "env",
        "evaluate",
        "hindsight",
        "io",
        "limits",
        "load",
        "math",
        "mj",
        "outcome",
        "policy",
        "progress",
        "provenance",
        "results",
        "rollout",
        "rules",
        "saved",
        "scene",
        "stream",
        "suite",
        "task",
        "zoo",
    ];
    let stack = ["agents", "bench", "blas", "cli", "table", "train", "render"];
    for m in core {
        let bad: Vec<_> = reach(&graph, m).into_iter().filter(|d| stack.contains(&d.as_str())).collect();
        assert!(bad.is_empty(), "the core module {m} uses {bad:?}");
    }
}

/// Inside agents/, imports go one way: the interface (algorithm.rs) and the shared settings
/// (shared.rs) name no algorithm, the algorithm files do not name the list of them
/// (registry.rs), and the list names every algorithm file.
#[test]
fn the_algorithm_interface_knows_no_algorithm_and_no_algorithm_knows_the_list() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("src/agents");
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
            // SAC exports its mean action as the core's tanh actor (crate::actor), not DDPG's learner.
            assert!(!names(&text, other), "{a}.rs names {other}");
        }
    }
}
