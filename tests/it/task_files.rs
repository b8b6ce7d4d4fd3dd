//! Bad task files: each gives a clear error with the file and line (no
//! MuJoCo needed except where a reset is involved).

use blockpuzzle::env::{BlockEnv, EnvConfig};
use blockpuzzle::task::{Task, TaskError};
use std::path::Path;

const HEADER: &str = "version = 1\nid = \"Bad-v0\"\n";

const BLUE: &str = "[[objects]]\nname = \"b\"\ncolour = \"blue\"\n";
const GREEN: &str =
    "[[objects]]\nname = \"g\"\ncolour = \"green\"\nstart = { around = \"b\", distance = [0.1, 0.1] }\n";

fn load(body: &str) -> Result<Task, TaskError> {
    Task::from_toml(&format!("{HEADER}{body}"), Some(Path::new("bad.toml")))
}

fn error(body: &str) -> TaskError {
    match load(body) {
        Err(e) => e,
        Ok(_) => panic!("accepted:\n{body}"),
    }
}

#[test]
fn a_good_minimal_file_loads() {
    let t = load(&format!("{BLUE}{GREEN}")).unwrap();
    assert_eq!(t.id(), "Bad-v0");
    assert_eq!(t.source.path.as_deref(), Some(Path::new("bad.toml")));
}

#[test]
fn malformed_toml_names_the_line() {
    let e = error(&format!("{BLUE}[[objects]\nname = \"g\"\n"));
    assert_eq!(e.line, Some(6), "{e}");
    assert!(e.to_string().starts_with("bad.toml:6: "), "{e}");
}

#[test]
fn unknown_keys_are_refused_with_their_line() {
    let e = error(&format!("{BLUE}{}", GREEN.replace("colour = \"green\"", "colour = \"green\"\ncolr = \"red\"")));
    assert!(e.message.contains("unknown field `colr`"), "{e}");
    assert_eq!(e.line, Some(9), "{e}");
    let e = error(&format!("mystery = 3\n{BLUE}{GREEN}"));
    assert!(e.message.contains("unknown field `mystery`") && e.line == Some(3), "{e}");
    let e = error(&format!("{BLUE}{}", GREEN.replace("distance", "dist")));
    assert!(e.message.contains("unknown field `dist`"), "{e}");
}

#[test]
fn a_task_needs_blue_and_green() {
    let e = error(BLUE);
    assert!(e.message.contains("green"), "{e}");
    let e = error(&GREEN.replace("around = \"b\", ", "").replace("distance = [0.1, 0.1]", "distance = [0, 0.1]"));
    assert!(e.message.contains("blue"), "{e}");
}

#[test]
fn references_to_missing_or_later_objects_are_errors() {
    let e = error(&format!("{BLUE}{}", GREEN.replace("around = \"b\", distance = [0.1, 0.1]", "on = \"ghost\"")));
    assert!(e.message.contains("\"ghost\", which is not an object") && e.line == Some(6), "{e}");
    let e = error(&format!("{}{BLUE}", GREEN));
    assert!(e.message.contains("comes later in the file"), "{e}");
    let e = error(&format!("{BLUE}{GREEN}[distributions.x.starts]\nghost = {{}}\n"));
    assert!(e.message.contains("\"ghost\", which is not an object") && e.line == Some(10), "{e}");
}

#[test]
fn too_many_objects() {
    let many: String = (0..70)
        .map(|i| format!("[[objects]]\nname = \"o{i}\"\ncolour = \"{}\"\n", if i == 0 { "blue" } else { "green" }))
        .collect();
    let e = error(&many);
    assert!(e.message.contains("too many objects: 70 (at most 61)"), "{e}");
    assert!(e.line.is_some(), "{e}");
}

#[test]
fn curriculum_expressions_must_parse_and_stay_in_range() {
    let cur = |params: &str| format!("[curriculum]\nmax_level = 5\nparams = {{ {params} }}\n{BLUE}");
    let g = |d: &str| GREEN.replace("[0.1, 0.1]", d);
    let e = error(&format!("{}{}", cur("R = \"0.08 + * level\""), g("[0.1, \"R\"]")));
    assert!(e.message.contains("does not parse: column 8") && e.line == Some(5), "{e}");
    let e = error(&format!("{}{}", cur("R = \"0.3 - 0.05 * level\""), g("[0.1, \"R\"]")));
    assert!(e.message.contains("at level 4") && e.message.contains("0 ≤ lo ≤ hi"), "{e}");
    let e = error(&format!("{}{}", cur("R = \"sqrt(0.1 - level)\""), g("[0.1, \"R\"]")));
    assert!(e.message.contains("parameter R is NaN at level 1"), "{e}");
    let e = error(&format!("{}{}", cur("R = \"Q\", Q = \"R\""), g("[0.1, \"R\"]")));
    assert!(e.message.contains("depends on itself"), "{e}");
    let e = error(&format!("{}{}", cur("R = \"0.2\""), g("[0.1, \"S\"]")));
    assert!(e.message.contains("unknown name \"S\""), "{e}");
    let e = error(&format!("{}{}", cur("R = \"level2\""), g("[0.1, \"R\"]")));
    assert!(e.message.contains("neither a parameter nor level"), "{e}");
}

#[test]
fn version_and_shuffle_are_checked() {
    let e = Task::from_toml(&format!("version = 2\nid = \"x\"\n{BLUE}{GREEN}"), None).unwrap_err();
    assert!(e.message.contains("version = 2"), "{e}");
    let e = error(&format!(
        "shuffle = [[\"b\", \"g\"]]\n{BLUE}{}",
        GREEN.replace("colour = \"green\"", "colour = \"green\"\nmass = 1.0")
    ));
    assert!(e.message.contains("same kind, size, mass"), "{e}");
}

#[test]
fn a_tower_that_falls_at_reset_is_reported() {
    // A block balanced on a 1 cm thick, 30 cm tall pole, off centre: it cannot stand.
    let body = "[placement]\nsettle_seconds = 0.5\nmax_reset_attempts = 5\n\
         [[objects]]\nname = \"pole\"\ncolour = \"grey\"\nhalf_extents = [0.005, 0.005, 0.15]\nstart = { around = \"gripper\", distance = [0.15, 0.2] }\n\
         [[objects]]\nname = \"b\"\ncolour = \"blue\"\nstart = { on = \"pole\", offset = [0.02, 0] }\n\
         [[objects]]\nname = \"g\"\ncolour = \"green\"\nstart = { around = \"pole\", distance = [0.1, 0.15] }\n";
    let task = load(body).unwrap();
    let mut env = BlockEnv::new(EnvConfig::new(task)).unwrap();
    let err = env.reset(Some(0)).unwrap_err().to_string();
    assert!(err.contains("no valid reset state after 5 layouts") && err.contains("while settling"), "{err}");
}

#[test]
fn tables_may_be_written_any_way_toml_allows() {
    let body = "[curriculum.params]\nR = \"0.1 + 0.01 * level\"\n\
                [[objects]]\nname = \"b\"\ncolour = \"blue\"\n[objects.start]\naround = \"gripper\"\ndistance = [0, \"R\"]\n\
                [[objects]]\nname = \"g\"\ncolour = \"green\"\nstart.around = \"b\"\nstart.distance = [0.1, 0.2]\n\
                [distributions.far.params]\nR = 0.2\n";
    let t = load(body).unwrap();
    assert_eq!(t.params(0, None), vec![("R".to_owned(), 0.1)]);
    assert_eq!(t.params(0, t.distribution("far")), vec![("R".to_owned(), 0.2)]);
}

#[test]
fn lines_count_right_after_non_ascii_comments() {
    let e = error(&format!("# a comment with ≤, é and —\n{BLUE}{}", GREEN.replace("[0.1, 0.1]", "[0.2, 0.1]")));
    assert_eq!(e.line, Some(7), "{e}");
    assert!(e.message.contains("needs 0 ≤ lo ≤ hi"), "{e}");
}

#[test]
fn json_task_files_are_read_by_the_same_checks() {
    let dir = tempfile::tempdir().unwrap();
    let toml_task = Task::from_toml(&format!("{HEADER}{BLUE}{GREEN}"), None).unwrap();
    let json = dir.path().join("t.json");
    std::fs::write(&json, serde_json::to_string_pretty(&toml_task.spec).unwrap()).unwrap();
    let t = Task::from_file(&json).unwrap();
    assert_eq!(t.spec, toml_task.spec);
    assert_eq!(t.source.hash, toml_task.source.hash);
    std::fs::write(&json, "{\n \"version\": 1,\n \"id\": \"x\",\n").unwrap();
    let e = Task::from_file(&json).unwrap_err();
    assert!(e.message.starts_with("not JSON") && e.line.is_some(), "{e}");
    std::fs::write(&json, r#"{"version": 1, "id": "x", "objects": [{"name": "b", "colour": "blue", "size": 1}]}"#)
        .unwrap();
    let e = Task::from_file(&json).unwrap_err();
    assert!(e.message.contains("unknown field `size`") && e.to_string().contains("t.json"), "{e}");
}
