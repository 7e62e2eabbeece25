//! The manuals' statements checked against the command: the modes and defaults that
//! docs/results.md, docs/scene-format.md and docs/cli.md state, and docs/cli.md's table of
//! refused inputs, every row run as written.

use crate::common::{assert_clean_error, raybench, raybench_command};
use crate::root;
use std::path::Path;

#[test]
fn docs_state_the_modes_and_the_defaults() {
    let root = root();
    let read = |p: &str| std::fs::read_to_string(root.join(p)).unwrap();
    // Every mode a result can hold.
    let results = read("docs/results.md");
    let row = results
        .lines()
        .find(|l| l.starts_with("| `mode` |"))
        .expect("a mode row");
    for m in raybench_core::Mode::ALL {
        assert!(row.contains(&format!("`{}`", m.name())), "{row}");
    }
    // The background of a scene file that sets none, which lights `path` renders.
    let scene = raybench_scene::load_scene_str(
        "[[object]]\nkind = \"sphere\"\ncenter = [0, 0, 0]\nradius = 1\n",
        "one-sphere",
        None,
        Path::new("."),
    )
    .unwrap();
    let bg = scene.background;
    let stated = format!("default `[{}, {}, {}]`", bg.x, bg.y, bg.z);
    assert!(read("docs/scene-format.md").contains(&stated), "{stated}");
    assert!(read("docs/cli.md").contains(&stated), "{stated}");
    // The default `--max-depth` of every command that has one.
    for cmd in ["render", "compare", "info"] {
        let o = raybench(&[cmd, "--help"]);
        let help = String::from_utf8_lossy(&o.stdout);
        let option = &help[help.find("--max-depth").expect("a --max-depth option")..];
        let option = &option[..option[2..].find("--").map_or(option.len(), |i| i + 2)];
        let default = option
            .split("[default: ")
            .nth(1)
            .and_then(|d| d.split(']').next())
            .unwrap_or_else(|| panic!("{cmd}: no default in {option}"));
        assert!(
            read("docs/scene-format.md").contains(&format!("**default {default}**")),
            "{cmd}: {default}"
        );
        assert!(read("docs/cli.md").contains(&format!("`--max-depth {default}`")));
    }
}

/// The table of refused inputs in docs/cli.md stays true: every row's command is run from the
/// workspace root and must fail cleanly with one `error:` line containing the row's
/// message, and every fixture in `crates/cli/tests/bad-input/` is used by a row (or by a
/// fixture a row uses), so that the table and the files cannot drift apart.
#[test]
fn docs_bad_input_table_is_true() {
    let root = root();
    let doc = std::fs::read_to_string(root.join("docs/cli.md")).unwrap();
    let table = doc
        .split_once("<!-- bad-input-table -->")
        .and_then(|(_, rest)| rest.split_once("<!-- /bad-input-table -->"))
        .map(|(table, _)| table)
        .expect("docs/cli.md has the bad-input table between its markers");
    // A code span: `text`, or `` text `` when the text holds backticks.
    let code = |cell: &str| {
        let cell = cell.trim();
        let inner = cell
            .strip_prefix("``")
            .and_then(|c| c.strip_suffix("``"))
            .or_else(|| cell.strip_prefix('`').and_then(|c| c.strip_suffix('`')));
        inner
            .unwrap_or_else(|| panic!("cell {cell:?} is not `code`"))
            .trim()
            .to_owned()
    };
    let mut rows = 0;
    for line in table.lines().filter(|l| l.starts_with("| ")) {
        let cells: Vec<&str> = line.trim_matches('|').split(" | ").collect();
        if cells.len() != 3 || cells[0].trim() == "input" || cells[0].starts_with('-') {
            continue;
        }
        let (command, message) = (code(cells[1]), code(cells[2]));
        let mut words = command.split_whitespace().peekable();
        let mut cmd = raybench_command();
        cmd.current_dir(&root);
        while let Some((k, v)) = words.peek().and_then(|w| w.split_once('=')) {
            cmd.env(k, v);
            words.next();
        }
        assert_eq!(words.next(), Some("raybench"), "{command}");
        let out = cmd.args(words).output().expect("raybench runs");
        // `...` stands for text that varies (an absolute path): the pieces must appear in
        // order.
        let expected = message.strip_prefix("error: ").unwrap_or(&message);
        let mut pieces = expected.split("...");
        let first = pieces.next().unwrap_or_default();
        assert_clean_error(&out, first);
        let stderr = String::from_utf8_lossy(&out.stderr);
        let line = stderr
            .lines()
            .find(|l| l.starts_with("error"))
            .unwrap_or_default();
        let mut at = line.find(first).unwrap_or_default() + first.len();
        for piece in pieces {
            let found = line[at..].find(piece);
            assert!(
                found.is_some(),
                "{command}: {line:?} lacks {piece:?} (in order)"
            );
            at += found.unwrap_or_default() + piece.len();
        }
        rows += 1;
    }
    assert!(
        rows >= 30,
        "only {rows} rows in the bad-input table of docs/cli.md"
    );
    let fixtures = root.join("crates/cli/tests/bad-input");
    let used: String = std::fs::read_dir(&fixtures)
        .unwrap()
        .map(|e| std::fs::read_to_string(e.unwrap().path()).unwrap_or_default())
        .chain([table.to_owned()])
        .collect();
    for e in std::fs::read_dir(&fixtures).unwrap() {
        let name = e.unwrap().file_name().into_string().unwrap();
        assert!(
            table.contains(&format!("bad-input/{name}"))
                || used.contains(&format!("\"{name}\""))
                || used.contains(&format!(" {name}\n")),
            "fixture {name} is used by no row of the table in docs/cli.md"
        );
    }
}
