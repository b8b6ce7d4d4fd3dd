//! The facts a reader of the project's files needs and the core defines, in one JSON document: the
//! Python extension hands them to the package (`_native.facts()`), and `python/blockpuzzle/facts.json`
//! holds the same document for the package's zoo reader run without the extension (a test keeps the
//! file equal to [`facts`]), so that no value is written twice.

use crate::env::{ObsMode, ObsSpec, COLOUR_FEATURE};

/// The facts: the entities observation's colour feature and width, the colour and outcome names in
/// the core's order, the zoo formats read and written, the engines the project runs, and every
/// built-in task's content hash by id (what a zoo entry's evaluation records are checked against).
///
/// # Errors
/// A built-in task that does not parse (the tests rule that out).
pub fn facts() -> Result<serde_json::Value, crate::env::EnvError> {
    let mut tasks = serde_json::Map::new();
    for id in crate::env::registry::ids() {
        tasks.insert(id.to_owned(), crate::env::registry::task(id)?.source.hash.into());
    }
    Ok(serde_json::json!({
        "colour_feature": COLOUR_FEATURE,
        "entity_features": ObsSpec::new(ObsMode::Entities, 1).object_dim(),
        "colours": crate::sim::rules::Colour::ALL.iter().map(|c| c.name()).collect::<Vec<_>>(),
        "outcomes": crate::episode::outcome::Outcome::ALL.iter().map(|o| o.name()).collect::<Vec<_>>(),
        "zoo_formats": super::zoo::READS,
        "zoo_format": super::zoo::FORMAT,
        "engines": super::provenance::ENGINES,
        "tasks": tasks,
    }))
}

/// [`facts`] as the file `python/blockpuzzle/facts.json` holds it: pretty-printed, keys sorted,
/// a final newline.
///
/// # Errors
/// As [`facts`].
pub fn facts_file() -> Result<String, crate::env::EnvError> {
    Ok(serde_json::to_string_pretty(&facts()?).expect("JSON values serialise") + "\n")
}
