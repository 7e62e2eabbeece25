//! Finds the built-in scenes: every `bench-scenes/NAME.toml` with its `[benchmark]` table,
//! written into `$OUT_DIR/builtin_scenes.rs` as the `BUILTIN_SCENES` table (`src/builtin.rs`
//! includes it), so that adding a built-in scene is adding one file. A malformed
//! `[benchmark]` table fails the build, naming the file and the key: nothing a user loads
//! can reach it.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

/// The keys of a `[benchmark]` table (documented in `docs/scene-format.md`).
const KEYS: [&str; 7] = [
    "description",
    "order",
    "matrix",
    "purpose",
    "modes",
    "experiments",
    "heavy",
];

fn main() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../bench-scenes");
    println!("cargo:rerun-if-changed={}", dir.display());
    let mut files: Vec<PathBuf> = std::fs::read_dir(&dir)
        .unwrap_or_else(|e| panic!("cannot read {}: {e}", dir.display()))
        .map(|entry| entry.expect("a readable directory entry").path())
        .filter(|p| p.extension().is_some_and(|e| e == "toml"))
        .collect();
    files.sort();
    let mut scenes: Vec<(i64, String)> = files
        .iter()
        .map(|p| {
            scene(p).unwrap_or_else(|why| {
                let file = p.file_name().unwrap_or_default().to_string_lossy();
                panic!("bench-scenes/{file}: {why}")
            })
        })
        .collect();
    scenes.sort_by_key(|(order, _)| *order);
    for pair in scenes.windows(2) {
        assert!(
            pair[0].0 != pair[1].0,
            "bench-scenes: two scenes have [benchmark] order = {}",
            pair[0].0
        );
    }
    let mut out = String::from("&[\n");
    for (_, entry) in &scenes {
        out.push_str(entry);
    }
    out.push_str("]\n");
    let target =
        Path::new(&std::env::var("OUT_DIR").expect("cargo sets OUT_DIR")).join("builtin_scenes.rs");
    std::fs::write(&target, out).unwrap_or_else(|e| panic!("cannot write {target:?}: {e}"));
}

/// The `order` of the scene in `path` and its `BuiltinScene { .. }` expression, or what is
/// wrong with it.
fn scene(path: &Path) -> Result<(i64, String), String> {
    let name = path
        .file_stem()
        .and_then(|s| s.to_str())
        .ok_or("the file name is not UTF-8")?;
    let text = std::fs::read_to_string(path).map_err(|e| e.to_string())?;
    let table: toml::Table = text.parse().map_err(|e| format!("{e}"))?;
    if table.get("name").and_then(|v| v.as_str()) != Some(name) {
        return Err(format!("`name` must be \"{name}\", the file's name"));
    }
    let meta = table
        .get("benchmark")
        .and_then(|v| v.as_table())
        .ok_or("a built-in scene needs a [benchmark] table (docs/scene-format.md)")?;
    if let Some(unknown) = meta.keys().find(|k| !KEYS.contains(&k.as_str())) {
        return Err(format!(
            "[benchmark]: unknown key `{unknown}` (known: {})",
            KEYS.join(", ")
        ));
    }
    let string = |key: &str| -> Result<Option<&str>, String> {
        meta.get(key)
            .map(|v| {
                v.as_str()
                    .ok_or_else(|| format!("[benchmark] {key} must be a string"))
            })
            .transpose()
    };
    let strings = |key: &str| -> Result<Vec<&str>, String> {
        meta.get(key).map_or(Ok(Vec::new()), |v| {
            v.as_array()
                .and_then(|a| {
                    a.iter()
                        .map(toml::Value::as_str)
                        .collect::<Option<Vec<_>>>()
                })
                .ok_or_else(|| format!("[benchmark] {key} must be a list of strings"))
        })
    };
    let description = string("description")?
        .filter(|d| !d.is_empty())
        .ok_or("[benchmark] needs a description")?;
    let order = meta
        .get("order")
        .ok_or("[benchmark] needs an order (its place in listings)")?
        .as_integer()
        .ok_or("[benchmark] order must be an integer")?;
    let matrix = match string("matrix")?.unwrap_or("none") {
        "quick" => "Quick",
        "full" => "Full",
        "none" => "None",
        other => {
            return Err(format!(
                "[benchmark] matrix = \"{other}\": must be \"quick\", \"full\" or \"none\""
            ));
        }
    };
    let purpose = match string("purpose")? {
        Some("performance") => "Performance",
        Some("coverage") => "Coverage",
        Some(other) => {
            return Err(format!(
                "[benchmark] purpose = \"{other}\": must be \"performance\" or \"coverage\""
            ));
        }
        None => {
            return Err("[benchmark] needs a purpose (\"performance\" or \"coverage\")".into());
        }
    };
    let heavy = match meta.get("heavy") {
        None => false,
        Some(v) => v
            .as_bool()
            .ok_or("[benchmark] heavy must be true or false")?,
    };
    // The files the scene needs from the assets folder: its objects' `path` (meshes) and
    // `file` (Bezier patches), and a `source` that is a file rather than a generator spec.
    let mut assets: Vec<&str> = Vec::new();
    for array in ["object", "volume"] {
        for t in table
            .get(array)
            .and_then(|v| v.as_array())
            .into_iter()
            .flatten()
            .filter_map(toml::Value::as_table)
        {
            for key in ["path", "file", "source"] {
                if let Some(p) = t.get(key).and_then(|v| v.as_str())
                    && (key != "source" || !p.contains(':'))
                    && !assets.contains(&p)
                {
                    assets.push(p);
                }
            }
        }
    }
    let list = |v: &[&str]| -> String {
        v.iter()
            .map(|s| format!("{s:?}"))
            .collect::<Vec<_>>()
            .join(", ")
    };
    let source = path.canonicalize().map_err(|e| e.to_string())?;
    let mut entry = String::new();
    let _ = write!(
        entry,
        "    BuiltinScene {{\n        name: {name:?},\n        description: {description:?},\n        \
         assets: &[{}],\n        source: include_str!({:?}),\n        benchmark: Benchmark {{\n            \
         order: {order},\n            matrix: Matrix::{matrix},\n            purpose: Purpose::{purpose},\n            modes: &[{}],\n            \
         experiments: &[{}],\n            heavy: {heavy},\n        }},\n    }},\n",
        list(&assets),
        source.display().to_string(),
        list(&strings("modes")?),
        list(&strings("experiments")?),
    );
    Ok((order, entry))
}
