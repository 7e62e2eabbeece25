//! The WGSL kernels name the Rust routines they port: every primitive kind's entry point
//! names one, and every routine a kernel's comment names exists in the Rust sources.

use crate::workspace::crate_dirs;
use crate::{read, root, rust_sources, strip_comments_and_literals};
use std::collections::BTreeSet;
use std::path::PathBuf;

/// Each WGSL function with the comment block right above it: `(line, name, comment)`.
fn wgsl_functions(wgsl: &str) -> Vec<(usize, String, String)> {
    let lines: Vec<&str> = wgsl.lines().collect();
    let mut out = Vec::new();
    for (i, line) in lines.iter().enumerate() {
        let Some(rest) = line.strip_prefix("fn ") else {
            continue;
        };
        let name: String = rest
            .chars()
            .take_while(|c| c.is_alphanumeric() || *c == '_')
            .collect();
        let mut comment = Vec::new();
        for above in lines[..i].iter().rev() {
            match above.trim_start().strip_prefix("//") {
                Some(text) => comment.push(text.trim()),
                None => break,
            }
        }
        comment.reverse();
        out.push((i + 1, name, comment.join(" ")));
    }
    out
}

/// The Rust routines a WGSL comment names: each backticked span that starts with a path of
/// two or more segments whose last begins with a lower-case letter (`Triangle::intersect`,
/// `solid::quadratic`, `bezier::control_box(..)`), as `(owner, routine)`.
fn named_routines(comment: &str) -> Vec<(String, String)> {
    comment
        .split('`')
        .skip(1)
        .step_by(2)
        .filter_map(|span| {
            let path: String = span
                .chars()
                .take_while(|c| c.is_alphanumeric() || *c == '_' || *c == ':')
                .collect();
            let (owner, routine) = path.trim_end_matches(':').rsplit_once("::")?;
            let owner = owner.rsplit("::").next()?;
            let lower = routine.chars().next()?.is_ascii_lowercase();
            (lower && !owner.is_empty()).then(|| (owner.to_owned(), routine.to_owned()))
        })
        .collect()
}

/// Whether `(owner, routine)` exists among the Rust sources `files` (path, code with
/// comments and literals stripped): a file that defines `fn routine` (or a field
/// `routine:`) and is the module `owner` (`owner.rs`, or a file in the folder `owner/`) or,
/// for an owner whose name starts with a capital, has an `impl` line naming the type
/// `owner`.
fn routine_exists(files: &[(String, String)], owner: &str, routine: &str) -> bool {
    let is_word = |line: &str, word: &str| {
        line.split(|c: char| !(c.is_alphanumeric() || c == '_'))
            .any(|w| w == word)
    };
    files.iter().any(|(path, code)| {
        let defines = code.lines().any(|l| {
            let l = l.trim_start();
            l.split(|c: char| !(c.is_alphanumeric() || c == '_'))
                .collect::<Vec<_>>()
                .windows(2)
                .any(|w| w[0] == "fn" && w[1] == routine)
                || l.strip_prefix("pub ")
                    .unwrap_or(l)
                    .strip_prefix(routine)
                    .is_some_and(|r| r.starts_with(':') && !r.starts_with("::"))
        });
        let owned = if owner.starts_with(|c: char| c.is_ascii_uppercase()) {
            code.lines()
                .any(|l| l.trim_start().starts_with("impl") && is_word(l, owner))
        } else {
            path.ends_with(&format!("/{owner}.rs")) || path.contains(&format!("/{owner}/"))
        };
        defines && owned
    })
}

/// The WGSL functions that the bodies of `prim_hit` and `prim_normal` call: each primitive
/// kind's intersection and normal (`triangle_hit`, `csg_normal`, ...).
fn dispatched(kernels: &str) -> BTreeSet<String> {
    let mut out = BTreeSet::new();
    let mut inside = false;
    for line in kernels.lines() {
        if line.starts_with("fn prim_hit(") || line.starts_with("fn prim_normal(") {
            inside = true;
        } else if line.starts_with('}') {
            inside = false;
        } else if inside {
            let code = line.split("//").next().unwrap_or("");
            for (i, _) in code.match_indices('(') {
                let name: String = code[..i]
                    .chars()
                    .rev()
                    .take_while(|c| c.is_alphanumeric() || *c == '_')
                    .collect::<Vec<_>>()
                    .into_iter()
                    .rev()
                    .collect();
                if name.ends_with("_hit") || name.ends_with("_normal") {
                    out.insert(name);
                }
            }
        }
    }
    out
}

/// The names of the kernels' own structs (`struct Hit {`): `Hit::inst` in a comment is a
/// WGSL field, not a Rust routine.
fn wgsl_structs(kernels: &str) -> BTreeSet<String> {
    kernels
        .lines()
        .filter_map(|l| l.strip_prefix("struct "))
        .map(|rest| {
            rest.chars()
                .take_while(|c| c.is_alphanumeric() || *c == '_')
                .collect()
        })
        .collect()
}

/// The kernels are ports (ARCHITECTURE.md, `crates/wgpu`: "every routine names the core
/// routine it mirrors"). The rule checked, on `crates/wgpu/src/kernels/*.wgsl`:
/// - the comment right above each primitive kind's entry point, every function that
///   `prim_hit` and `prim_normal` dispatch to ([`dispatched`]), names the Rust routine it
///   ports, and
/// - every Rust routine that the comment right above any WGSL function names, written in
///   backticks as `Type::method` or `module::function` (see [`named_routines`]; names on
///   the kernels' own structs, such as `Hit::inst`, are WGSL's), exists in the workspace's
///   Rust sources ([`routine_exists`]), so a renamed or removed routine cannot leave a
///   kernel naming what is gone.
#[test]
fn the_kernels_name_the_rust_routines_they_port() {
    let root = root();
    let rust: Vec<(String, String)> = crate_dirs(&root)
        .iter()
        .flat_map(|dir| rust_sources(&format!("crates/{dir}/src")))
        .map(|(path, text)| (path, strip_comments_and_literals(&text)))
        .collect();
    let kernels = root.join("crates/wgpu/src/kernels");
    let mut problems = Vec::new();
    let mut checked = 0;
    let mut wgsl: Vec<PathBuf> = std::fs::read_dir(&kernels)
        .expect("crates/wgpu/src/kernels")
        .map(|e| e.expect("an entry").path())
        .filter(|p| p.extension().is_some_and(|e| e == "wgsl"))
        .collect();
    wgsl.sort();
    let all: String = wgsl.iter().map(|f| read(f)).collect::<Vec<_>>().join("\n");
    let entries = dispatched(&all);
    let structs = wgsl_structs(&all);
    assert!(
        entries.len() >= 8,
        "prim_hit and prim_normal dispatch to {entries:?}"
    );
    for file in wgsl {
        let name = file
            .file_name()
            .expect("a name")
            .to_string_lossy()
            .into_owned();
        for (line, function, comment) in wgsl_functions(&read(&file)) {
            let named: Vec<_> = named_routines(&comment)
                .into_iter()
                .filter(|(owner, _)| !structs.contains(owner))
                .collect();
            if entries.contains(&function) && named.is_empty() {
                problems.push(format!("{name}:{line}: {function} names no Rust routine"));
            }
            for (owner, routine) in named {
                checked += 1;
                if !routine_exists(&rust, &owner, &routine) {
                    problems.push(format!(
                        "{name}:{line}: {function} names `{owner}::{routine}`, which no Rust \
                         source defines"
                    ));
                }
            }
        }
    }
    assert!(checked > 20, "only {checked} named routines found");
    assert!(
        problems.is_empty(),
        "the kernels' comments and the Rust routines they port disagree:\n{}",
        problems.join("\n")
    );
}

#[test]
fn the_kernel_check_can_fail() {
    let wgsl = "// `Sphere::intersect` and `solid::gone`, `bezier::Newton`.\n\
                fn sphere_hit() {}\n\n// A helper.\nfn helper() {}\n";
    let functions = wgsl_functions(wgsl);
    assert_eq!(functions.len(), 2);
    assert_eq!(functions[0].1, "sphere_hit");
    let named = named_routines(&functions[0].2);
    assert_eq!(
        named,
        [
            ("Sphere".to_owned(), "intersect".to_owned()),
            ("solid".to_owned(), "gone".to_owned())
        ]
    );
    assert!(named_routines(&functions[1].2).is_empty());
    let main = "struct Hit {\n    t: f32,\n}\nfn prim_hit(r: Ray, k: u32) -> Cand {\n    \
                if k == 0u { return sphere_hit(r); } // not_hit(\n    return csg_hit(r, p);\n}\n\
                fn other() { helper_hit(r); }\n";
    assert_eq!(
        dispatched(main),
        BTreeSet::from(["sphere_hit".to_owned(), "csg_hit".to_owned()])
    );
    assert_eq!(wgsl_structs(main), BTreeSet::from(["Hit".to_owned()]));
    let rust = [
        (
            "crates/geometry/src/sphere.rs".to_owned(),
            "impl Sphere {\n    pub fn intersect(&self) {}\n}\n".to_owned(),
        ),
        (
            "crates/geometry/src/csg/solid.rs".to_owned(),
            "fn here() {}\n".to_owned(),
        ),
    ];
    assert!(routine_exists(&rust, "Sphere", "intersect"));
    assert!(!routine_exists(&rust, "solid", "gone"));
    assert!(routine_exists(&rust, "solid", "here"));
    assert!(!routine_exists(&rust, "Plane", "intersect"));
}
