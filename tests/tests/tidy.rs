//! Invariants of the code's layout that a reader relies on and a compiler does not check, in
//! the spirit of rust-analyzer's `tidy` tests: the crates' dependencies (the geometry's, the
//! core's, the backends'; only the GPU backend knows wgpu), the code map of ARCHITECTURE.md
//! covering every source file, no module cycles, and the WGSL kernels naming the Rust
//! routines they port. Each check is tested on a planted example that must fail it.

mod workspace;

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};
use workspace::{LAYERS, backend_crates, crate_dirs, dependencies, manifest};

/// The workspace root.
fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .parent()
        .expect("tests/ sits in the workspace")
        .to_path_buf()
}

fn read(path: &Path) -> String {
    std::fs::read_to_string(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()))
}

#[test]
fn the_geometry_crate_depends_on_glam_only() {
    let manifest = read(&root().join("crates/geometry/Cargo.toml"));
    assert_eq!(dependencies(&manifest, "[dependencies]"), ["glam"]);
    assert!(!manifest.contains("[build-dependencies]"));
}

/// Every CPU backend crate ([`workspace::backend_crates`]: the crates under `crates/` that
/// are not [`LAYERS`] and do not name `wgpu`) depends on `raybench-geometry` and not on the
/// rendering core or the scene loader: a structure sees the geometry, never the scene.
#[test]
fn cpu_backends_see_the_geometry_not_the_scene() {
    let backends = backend_crates(&root());
    assert!(
        backends.iter().any(|b| !b.gpu),
        "no CPU backend crate found"
    );
    assert!(backends.iter().any(|b| b.gpu), "no GPU backend crate found");
    for b in backends.iter().filter(|b| !b.gpu) {
        let deps = dependencies(&manifest(&root(), &b.dir), "[dependencies]");
        assert!(
            deps.iter().any(|d| d == "raybench-geometry"),
            "crates/{} must depend on raybench-geometry",
            b.dir
        );
        assert!(
            !deps
                .iter()
                .any(|d| d == "raybench-core" || d == "raybench-scene"),
            "crates/{} depends on the rendering core or the scene loader: {deps:?}",
            b.dir
        );
    }
}

/// The names the core section of ARCHITECTURE.md allows as the core's dependencies: the
/// backticked names of its sentence "it depends on `a` and `b` only".
fn allowed_core_dependencies(map: &str) -> Vec<String> {
    let Some(core) = section(map, "### `crates/core`") else {
        return Vec::new();
    };
    let flat = core.split_whitespace().collect::<Vec<_>>().join(" ");
    let Some(start) = flat.find("depends on ") else {
        return Vec::new();
    };
    let rest = &flat[start + "depends on ".len()..];
    let Some(end) = rest.find(" only") else {
        return Vec::new();
    };
    rest[..end]
        .split('`')
        .skip(1)
        .step_by(2)
        .map(str::to_owned)
        .collect()
}

/// The core's `[dependencies]` are exactly what ARCHITECTURE.md's core section allows ("it
/// depends on `raybench-geometry` and `glam` only": no rayon, no wgpu, nothing that times or
/// threads), and it has no build script dependencies.
#[test]
fn the_core_depends_on_what_the_architecture_allows() {
    let root = root();
    let allowed = allowed_core_dependencies(&read(&root.join("ARCHITECTURE.md")));
    assert!(
        !allowed.is_empty(),
        "ARCHITECTURE.md's section ### `crates/core` no longer says \"it depends on `..` and \
         `..` only\""
    );
    let manifest = manifest(&root, "core");
    let mut deps = dependencies(&manifest, "[dependencies]");
    deps.sort();
    let mut allowed = allowed;
    allowed.sort();
    assert_eq!(
        deps, allowed,
        "crates/core/Cargo.toml against ARCHITECTURE.md"
    );
    assert!(!manifest.contains("[build-dependencies]"));
}

/// The paths of the standard library the core may not name: no clock, threads, files,
/// processes, environment, network or SIMD intrinsics.
const OUTSIDE_THE_CORE: [&str; 9] = [
    "std::time",
    "Instant",
    "std::thread",
    "std::fs",
    "std::io",
    "std::process",
    "std::env",
    "std::net",
    "arch::",
];

/// Which of `files` (path, text) name, in code (comments and literals aside), one of
/// [`OUTSIDE_THE_CORE`], each with the name it uses.
fn outside_the_core(files: &[(String, String)]) -> Vec<String> {
    files
        .iter()
        .flat_map(|(path, text)| {
            let code = strip_comments_and_literals(text);
            OUTSIDE_THE_CORE
                .iter()
                .filter(move |name| code.contains(*name))
                .map(move |name| format!("{path}: {name}"))
        })
        .collect()
}

/// ARCHITECTURE.md: the core knows nothing of timing, threads, I/O, SIMD intrinsics or GPUs
/// (the clock lives in the harness: `raybench_registry::TimedRenderer`).
#[test]
fn the_core_knows_no_clock_threads_or_io() {
    let root = root();
    let dir = root.join("crates/core");
    let files: Vec<(String, String)> = rust_files(&dir)
        .into_iter()
        .map(|f| (format!("crates/core/{}", f.display()), read(&dir.join(&f))))
        .collect();
    assert!(files.len() > 20, "found only {} files", files.len());
    let found = outside_the_core(&files);
    assert!(found.is_empty(), "the core names:\n{}", found.join("\n"));
}

/// Which files of `files` (path, text) name the `wgpu` crate: a Cargo.toml with a `wgpu`
/// dependency key in any section, or Rust code (comments and literals aside) with a path
/// `wgpu::` that is not the end of a longer name (`raybench_wgpu::` is not `wgpu::`).
fn names_wgpu(files: &[(String, String)]) -> Vec<String> {
    files
        .iter()
        .filter(|(path, text)| {
            if path.ends_with("Cargo.toml") {
                text.lines().any(|l| {
                    l.split_once('=')
                        .is_some_and(|(k, _)| k.trim() == "wgpu" && !l.trim().starts_with('#'))
                })
            } else {
                let code = strip_comments_and_literals(text);
                code.match_indices("wgpu::").any(|(i, _)| {
                    !code[..i]
                        .chars()
                        .next_back()
                        .is_some_and(|c| c.is_alphanumeric() || c == '_')
                })
            }
        })
        .map(|(path, _)| path.clone())
        .collect()
}

/// ARCHITECTURE.md: `crates/wgpu` is the only crate that knows wgpu. No other crate's
/// Cargo.toml (nor `tests/`'s) names the `wgpu` crate, and no other Rust source (under
/// `crates/`, `tests/`, `fuzz/`) has a `wgpu::` path. The workspace's own Cargo.toml declares
/// the version in `[workspace.dependencies]`, which is no use of it.
#[test]
fn only_the_gpu_backend_knows_wgpu() {
    let root = root();
    let mut files = Vec::new();
    for dir in crate_dirs(&root) {
        if dir == "wgpu" {
            continue;
        }
        files.push((format!("crates/{dir}/Cargo.toml"), manifest(&root, &dir)));
        for f in rust_files(&root.join("crates").join(&dir)) {
            let path = format!("crates/{dir}/{}", f.display());
            files.push((path, read(&root.join("crates").join(&dir).join(&f))));
        }
    }
    files.push((
        "tests/Cargo.toml".into(),
        read(&root.join("tests/Cargo.toml")),
    ));
    for dir in ["tests", "fuzz"] {
        if root.join(dir).is_dir() {
            for f in rust_files(&root.join(dir)) {
                let path = format!("{dir}/{}", f.display());
                files.push((path, read(&root.join(dir).join(&f))));
            }
        }
    }
    assert!(files.len() > 50, "found only {} files", files.len());
    let found = names_wgpu(&files);
    assert!(
        found.is_empty(),
        "only crates/wgpu knows wgpu; these name it:\n{}",
        found.join("\n")
    );
}

#[test]
fn the_dependency_checks_can_fail() {
    let map = "### `crates/core` (x)\n\nText. It\ndepends on `raybench-geometry` and `glam`\nonly.\n\
               ### `crates/scene`\nit depends on `toml` only.\n";
    assert_eq!(
        allowed_core_dependencies(map),
        ["raybench-geometry", "glam"]
    );
    assert!(allowed_core_dependencies("### `crates/scene`\n").is_empty());
    let files = [
        (
            "a/Cargo.toml".to_owned(),
            "[dependencies]\nwgpu = 1\n".to_owned(),
        ),
        (
            "b/Cargo.toml".to_owned(),
            "[dependencies]\nraybench-wgpu = 1\n# wgpu = 1\n".to_owned(),
        ),
        ("c.rs".to_owned(), "fn f(_: wgpu::Device) {}\n".to_owned()),
        (
            "d.rs".to_owned(),
            "// wgpu::Device\nuse raybench_wgpu::X;\nconst S: &str = \"wgpu::\";\n".to_owned(),
        ),
    ];
    assert_eq!(names_wgpu(&files), ["a/Cargo.toml", "c.rs"]);
    let core = [
        (
            "e.rs".to_owned(),
            "fn f() { let t = std::time::Instant::now(); }\n".to_owned(),
        ),
        (
            "f.rs".to_owned(),
            "// std::fs\nconst S: &str = \"std::io\";\n".to_owned(),
        ),
    ];
    assert_eq!(
        outside_the_core(&core),
        ["e.rs: std::time", "e.rs: Instant"]
    );
    assert!(LAYERS.iter().any(|(l, _)| *l == "core"));
}

/// Every `.rs` file below `dir` (build outputs and hidden folders aside), relative to it,
/// sorted.
fn rust_files(dir: &Path) -> Vec<PathBuf> {
    let mut out = Vec::new();
    let mut todo = vec![dir.to_path_buf()];
    while let Some(d) = todo.pop() {
        for entry in std::fs::read_dir(&d).unwrap_or_else(|e| panic!("{}: {e}", d.display())) {
            let path = entry.expect("a directory entry").path();
            let name = path.file_name().map(|n| n.to_string_lossy().into_owned());
            if path.is_dir() {
                // Build outputs and hidden folders hold no sources of ours.
                if name.is_some_and(|n| n != "target" && !n.starts_with('.')) {
                    todo.push(path);
                }
            } else if path.extension().is_some_and(|e| e == "rs") {
                out.push(path.strip_prefix(dir).expect("below dir").to_path_buf());
            }
        }
    }
    out.sort();
    out
}

/// The text of the code-map section whose heading starts with `heading`.
fn section<'a>(map: &'a str, heading: &str) -> Option<&'a str> {
    let start = map.find(heading)?;
    let rest = &map[start + heading.len()..];
    Some(&rest[..rest.find("\n### ").unwrap_or(rest.len())])
}

/// How a file is named in its crate's section: `lib.rs` and `main.rs` by the section itself,
/// `X/mod.rs` as the folder `` `X/` ``, anything else by its file name (or its path).
fn mentioned(section: &str, file: &Path) -> bool {
    let name = file.file_name().and_then(|n| n.to_str()).unwrap_or("");
    let path = file.to_string_lossy().replace('\\', "/");
    match name {
        "lib.rs" | "main.rs" => true,
        "mod.rs" => {
            let folder = file
                .parent()
                .map(|p| p.to_string_lossy().replace('\\', "/"));
            folder.is_some_and(|f| section.contains(&format!("`{f}/`")))
        }
        _ => section.contains(&format!("`{name}`")) || section.contains(&path),
    }
}

#[test]
fn the_code_map_names_every_source_file() {
    let root = root();
    let map = read(&root.join("ARCHITECTURE.md"));
    let mut missing = Vec::new();
    let mut crates: Vec<(String, PathBuf)> = crate_dirs(&root)
        .into_iter()
        .map(|name| {
            let src = root.join("crates").join(&name).join("src");
            (format!("### `crates/{name}`"), src)
        })
        .collect();
    crates.push(("### `tests`".into(), root.join("tests/src")));
    crates.sort();
    for (heading, src) in crates {
        let Some(text) = section(&map, &heading) else {
            missing.push(format!("no section {heading}"));
            continue;
        };
        for file in rust_files(&src) {
            if !mentioned(text, &file) {
                missing.push(format!("{heading}: {}", file.display()));
            }
        }
    }
    assert!(
        missing.is_empty(),
        "ARCHITECTURE.md's code map does not name:\n{}",
        missing.join("\n")
    );
}

#[test]
fn the_code_map_check_can_fail() {
    let section = "`bvh.rs` and `csg/` and `report/results.rs`";
    assert!(mentioned(section, Path::new("bvh.rs")));
    assert!(mentioned(section, Path::new("csg/mod.rs")));
    assert!(mentioned(section, Path::new("report/results.rs")));
    assert!(!mentioned(section, Path::new("grid.rs")));
    assert!(!mentioned(section, Path::new("report/mod.rs")));
    assert_eq!(
        dependencies(
            "[dependencies]\nglam = 1\n# c\n[dev-dependencies]\nx = 2\n",
            "[dependencies]"
        ),
        ["glam"]
    );
}

// ---------------------------------------------------------------------------------------
// Module cycles.
// ---------------------------------------------------------------------------------------

/// Blanks out the comments, string literals and character literals of Rust source `src`
/// (each replaced by spaces; newlines are kept), so that what is left is code: `crate::`
/// in a doc comment or a message is not a dependency. Handles nested block comments,
/// escapes, raw strings (`r#"..."#`, `br"..."`) and tells character literals (`'a'`,
/// `'\n'`) from lifetimes (`'a`).
fn strip_comments_and_literals(src: &str) -> String {
    let s: Vec<char> = src.chars().collect();
    let mut out = String::with_capacity(src.len());
    let blank = |out: &mut String, c: char| out.push(if c == '\n' { '\n' } else { ' ' });
    let mut i = 0;
    while i < s.len() {
        let c = s[i];
        let next = s.get(i + 1).copied();
        let ident_before = i > 0 && (s[i - 1].is_alphanumeric() || s[i - 1] == '_');
        if c == '/' && next == Some('/') {
            while i < s.len() && s[i] != '\n' {
                i += 1;
            }
        } else if c == '/' && next == Some('*') {
            let mut depth = 0;
            while i < s.len() {
                if s[i] == '/' && s.get(i + 1) == Some(&'*') {
                    depth += 1;
                    i += 2;
                } else if s[i] == '*' && s.get(i + 1) == Some(&'/') {
                    depth -= 1;
                    i += 2;
                    if depth == 0 {
                        break;
                    }
                } else {
                    blank(&mut out, s[i]);
                    i += 1;
                }
            }
        } else if !ident_before && (c == 'r' || (c == 'b' && next == Some('r'))) && {
            let mut j = i + if c == 'b' { 2 } else { 1 };
            while s.get(j) == Some(&'#') {
                j += 1;
            }
            s.get(j) == Some(&'"')
        } {
            // A raw string: `r`, some hashes, a quote; it ends at a quote and as many hashes.
            i += if c == 'b' { 2 } else { 1 };
            let mut hashes = 0;
            while s[i] == '#' {
                hashes += 1;
                i += 1;
            }
            i += 1;
            while i < s.len() {
                if s[i] == '"' && (1..=hashes).all(|k| s.get(i + k) == Some(&'#')) {
                    i += 1 + hashes;
                    break;
                }
                blank(&mut out, s[i]);
                i += 1;
            }
        } else if c == '"' {
            i += 1;
            while i < s.len() && s[i] != '"' {
                if s[i] == '\\' {
                    blank(&mut out, s[i]);
                    i += 1;
                }
                if i < s.len() {
                    blank(&mut out, s[i]);
                    i += 1;
                }
            }
            i += 1;
        } else if c == '\'' && next == Some('\\') {
            // An escaped character literal: up to the closing quote.
            i += 2;
            while i < s.len() && s[i] != '\'' {
                i += 1;
            }
            i += 1;
        } else if c == '\'' && s.get(i + 2) == Some(&'\'') {
            i += 3;
        } else {
            out.push(c);
            i += 1;
        }
    }
    out
}

/// A token of stripped source: an identifier (or keyword, or number), `::`, or one other
/// character.
#[derive(Clone, Debug, PartialEq)]
enum Token {
    Ident(String),
    Path,
    Punct(char),
}

/// The tokens of stripped source (whitespace dropped).
fn tokens(code: &str) -> Vec<Token> {
    let s: Vec<char> = code.chars().collect();
    let mut out = Vec::new();
    let mut i = 0;
    while i < s.len() {
        let c = s[i];
        if c.is_alphanumeric() || c == '_' {
            let start = i;
            while i < s.len() && (s[i].is_alphanumeric() || s[i] == '_') {
                i += 1;
            }
            out.push(Token::Ident(s[start..i].iter().collect()));
        } else if c == ':' && s.get(i + 1) == Some(&':') {
            out.push(Token::Path);
            i += 2;
        } else {
            if !c.is_whitespace() {
                out.push(Token::Punct(c));
            }
            i += 1;
        }
    }
    out
}

/// A module path from the crate root (`[]` is the root, `["format", "mesh"]` is
/// `crate::format::mesh`).
type ModPath = Vec<String>;

/// What one module's source says about others: the modules it declares (`mod x;` and
/// inline `mod x { .. }`), its imports (`use` trees, by the name they bring into scope),
/// and every path it names (each `use` path and each `a::b` path in its code).
#[derive(Default, Debug)]
struct ModuleSource {
    /// The file the module is in (an inline module is in its parent's file).
    file: String,
    /// Children declared by `mod x;`, to be found as files.
    file_children: Vec<String>,
    /// Imports: the name in scope (the last segment, or the `as` name) and the full path.
    imports: Vec<(String, Vec<String>)>,
    /// Every path named: `use` paths (a glob's without the `*`) and code paths.
    paths: Vec<Vec<String>>,
}

/// Parses one `use` tree from `toks[*i]` (just after `use`) up to its `;`, pushing
/// `(name in scope, full path)` pairs; a glob is pushed with the name `*`.
fn parse_use_tree(
    toks: &[Token],
    i: &mut usize,
    prefix: &[String],
    out: &mut Vec<(String, Vec<String>)>,
) {
    let mut path = prefix.to_vec();
    while *i < toks.len() {
        match &toks[*i] {
            Token::Ident(name) if name == "as" => {
                *i += 1;
                if let Some(Token::Ident(alias)) = toks.get(*i) {
                    out.push((alias.clone(), path.clone()));
                    *i += 1;
                }
                return;
            }
            Token::Ident(name)
                if name == "self" && path.len() == prefix.len() && !prefix.is_empty() =>
            {
                // `a::{self, ..}`: the module `a` itself.
                *i += 1;
                if let Some(Token::Ident(kw)) = toks.get(*i)
                    && kw == "as"
                {
                    *i += 1;
                    if let Some(Token::Ident(alias)) = toks.get(*i) {
                        out.push((alias.clone(), path.clone()));
                        *i += 1;
                    }
                    return;
                }
                out.push((path.last().cloned().unwrap_or_default(), path.clone()));
                return;
            }
            Token::Ident(name) => {
                path.push(name.clone());
                *i += 1;
            }
            Token::Path => *i += 1,
            Token::Punct('*') => {
                out.push(("*".into(), path.clone()));
                *i += 1;
                return;
            }
            Token::Punct('{') => {
                *i += 1;
                loop {
                    match toks.get(*i) {
                        None => return,
                        Some(Token::Punct('}')) => {
                            *i += 1;
                            return;
                        }
                        Some(Token::Punct(',')) => *i += 1,
                        Some(_) => {
                            let before = *i;
                            parse_use_tree(toks, i, &path, out);
                            // Something a use tree does not hold (a macro's `$x`): skip it.
                            if *i == before {
                                *i += 1;
                            }
                        }
                    }
                }
            }
            _ => {
                if let Some(last) = path.last()
                    && path.len() > prefix.len()
                {
                    out.push((last.clone(), path.clone()));
                }
                return;
            }
        }
    }
}

/// Reads the modules of one file whose module path is `path`: the file's own module and
/// its inline modules (except `mod tests { .. }`, which may use anything), into `out`.
fn scan_file(file: &str, path: &ModPath, src: &str, out: &mut BTreeMap<ModPath, ModuleSource>) {
    let toks = tokens(&strip_comments_and_literals(src));
    // The inline modules open at each brace depth: (depth inside, module path).
    let mut scopes: Vec<(usize, ModPath)> = vec![(0, path.clone())];
    let mut depth = 0;
    let entry = |out: &mut BTreeMap<ModPath, ModuleSource>, m: &ModPath| {
        out.entry(m.clone()).or_insert_with(|| ModuleSource {
            file: file.to_owned(),
            ..ModuleSource::default()
        });
    };
    entry(out, path);
    let mut i = 0;
    while i < toks.len() {
        let here = scopes.last().expect("the file's module").1.clone();
        match &toks[i] {
            Token::Punct('{') => {
                depth += 1;
                i += 1;
            }
            Token::Punct('}') => {
                if scopes.len() > 1 && scopes.last().is_some_and(|(d, _)| *d == depth) {
                    scopes.pop();
                }
                depth = depth.saturating_sub(1);
                i += 1;
            }
            Token::Ident(kw) if kw == "mod" => {
                // `mod $name { .. }` in a macro is an inline module too.
                let (name, i_name) = match (toks.get(i + 1), toks.get(i + 2)) {
                    (Some(Token::Ident(name)), _) => (name.clone(), i + 1),
                    (Some(Token::Punct('$')), Some(Token::Ident(name))) => {
                        (format!("${name}"), i + 2)
                    }
                    _ => {
                        i += 1;
                        continue;
                    }
                };
                // From here on `i` is where `mod` would stand right before the name.
                i = i_name - 1;
                match toks.get(i + 2) {
                    Some(Token::Punct(';')) => {
                        out.get_mut(&here)
                            .expect("scanned")
                            .file_children
                            .push(name.clone());
                        i += 3;
                    }
                    Some(Token::Punct('{')) if name == "tests" => {
                        // Skip the test module to its closing brace.
                        let mut level = 0;
                        i += 2;
                        while i < toks.len() {
                            match toks[i] {
                                Token::Punct('{') => level += 1,
                                Token::Punct('}') => {
                                    level -= 1;
                                    if level == 0 {
                                        i += 1;
                                        break;
                                    }
                                }
                                _ => {}
                            }
                            i += 1;
                        }
                    }
                    Some(Token::Punct('{')) => {
                        let mut inner = here.clone();
                        inner.push(name.clone());
                        entry(out, &inner);
                        depth += 1;
                        scopes.push((depth, inner));
                        i += 3;
                    }
                    _ => i += 1,
                }
            }
            Token::Ident(kw) if kw == "use" => {
                i += 1;
                let mut found = Vec::new();
                parse_use_tree(&toks, &mut i, &[], &mut found);
                while i < toks.len() && toks[i] != Token::Punct(';') {
                    i += 1;
                }
                let m = out.get_mut(&here).expect("scanned");
                for (name, p) in found {
                    m.paths.push(p.clone());
                    if name != "*" && name != "_" {
                        m.imports.push((name, p));
                    }
                }
            }
            Token::Ident(first)
                if toks.get(i + 1) == Some(&Token::Path)
                    && !(i > 0 && toks[i - 1] == Token::Path)
                    && !(i > 0 && toks[i - 1] == Token::Ident("in".into())) =>
            {
                // A path in code: `a::b::c`, up to the first thing that is not a name.
                let mut p = vec![first.clone()];
                i += 1;
                while toks.get(i) == Some(&Token::Path) {
                    match toks.get(i + 1) {
                        Some(Token::Ident(n)) => {
                            p.push(n.clone());
                            i += 2;
                        }
                        _ => break,
                    }
                }
                out.get_mut(&here).expect("scanned").paths.push(p);
            }
            _ => i += 1,
        }
    }
}

/// The module graph of one crate at file granularity, read from its sources `files`
/// (paths relative to `src/` with `/` separators, such as `lib.rs` or `format/mod.rs`)
/// starting at the crate root `root` (`lib.rs`, `main.rs` or `bin/x.rs`), following its
/// `mod x;` declarations to `x.rs` or `x/mod.rs`.
///
/// An edge goes from file A to file B when a module of A names an item of a module of B by
/// a path:
/// - `crate::a::b::Item`, `self::a::Item`, `super::Item` (resolved from the module the path
///   is written in, inline modules included), or `a::Item` where `a` is a child module;
///   in `use` declarations (grouped trees `use crate::{a, b::c}` included) and in code;
/// - the path walks down modules as far as they exist, and the rest names an item of the
///   module reached; when that module only imports the item (`pub use b::Item;`, a
///   re-export), the edge goes to where the import leads, so `crate::Item` re-exported by
///   `lib.rs` is an edge to the item's own module, and a name re-exported from another
///   crate is no edge at all;
/// - a file naming an item of its own descendants (a parent declaring, re-exporting or
///   dispatching to its children: `mod x;`, `pub use x::Item`, `x::build(..)`) is no edge,
///   as the parent is made of its children; a child naming its parent's items is an edge
///   (child to parent), so a child, its parent and a third module the parent names that
///   names the child are a cycle;
/// - a file's inline `mod tests { .. }` is ignored; paths to other crates are no edges.
///
/// Returns the files and their edges (each file to the sorted files it names).
fn module_graph(
    files: &BTreeMap<String, String>,
    root: &str,
) -> BTreeMap<String, BTreeSet<String>> {
    let mut modules: BTreeMap<ModPath, ModuleSource> = BTreeMap::new();
    let mut todo: Vec<(String, ModPath)> = vec![(root.to_owned(), Vec::new())];
    let mut file_modules: BTreeMap<ModPath, String> = BTreeMap::new();
    while let Some((file, path)) = todo.pop() {
        let Some(src) = files.get(&file) else {
            continue;
        };
        file_modules.insert(path.clone(), file.clone());
        let before: BTreeSet<ModPath> = modules.keys().cloned().collect();
        scan_file(&file, &path, src, &mut modules);
        // The folder of a file's child modules: beside `lib.rs`, `main.rs` and `mod.rs`,
        // else in the folder named after the file.
        let (dir, stem) = match file.rsplit_once('/') {
            Some((d, f)) => (format!("{d}/"), f.trim_end_matches(".rs").to_owned()),
            None => (String::new(), file.trim_end_matches(".rs").to_owned()),
        };
        let own_dir = if ["lib", "main", "mod"].contains(&stem.as_str()) || path.is_empty() {
            dir
        } else {
            format!("{dir}{stem}/")
        };
        let new: Vec<ModPath> = modules
            .keys()
            .filter(|m| !before.contains(*m))
            .cloned()
            .collect();
        for m in new {
            let inline = m[path.len()..].join("/");
            let base = if inline.is_empty() {
                own_dir.clone()
            } else {
                format!("{own_dir}{inline}/")
            };
            for child in modules[&m].file_children.clone() {
                let mut p = m.clone();
                p.push(child.clone());
                let flat = format!("{base}{child}.rs");
                let nested = format!("{base}{child}/mod.rs");
                if files.contains_key(&flat) {
                    todo.push((flat, p));
                } else if files.contains_key(&nested) {
                    todo.push((nested, p));
                }
            }
        }
    }
    let mut graph: BTreeMap<String, BTreeSet<String>> = file_modules
        .values()
        .map(|f| (f.clone(), BTreeSet::new()))
        .collect();
    let module_of: BTreeMap<&String, &ModPath> = file_modules.iter().map(|(m, f)| (f, m)).collect();
    for (m, source) in &modules {
        let own = module_of[&source.file];
        for p in &source.paths {
            let Some(target) = resolve(&modules, m, p, 0) else {
                continue;
            };
            // The file of the target: its longest prefix that is a file module.
            let (target, file) = (0..=target.len())
                .rev()
                .find_map(|k| file_modules.get_key_value(&target[..k]))
                .expect("the crate root is a file module");
            // A parent composes its children (declares, re-exports, dispatches to them):
            // an edge to a descendant is no dependency.
            let descendant = target.len() > own.len() && target[..own.len()] == own[..];
            if *file != source.file && !descendant {
                graph
                    .get_mut(&source.file)
                    .expect("a scanned file")
                    .insert(file.clone());
            }
        }
    }
    graph
}

/// The module that `path`, written in module `from`, names an item of (or names itself),
/// following imports (re-exports) up to a few steps; `None` for other crates and for
/// names that are not module paths.
fn resolve(
    modules: &BTreeMap<ModPath, ModuleSource>,
    from: &ModPath,
    path: &[String],
    steps: usize,
) -> Option<ModPath> {
    let child = |m: &ModPath, name: &str| {
        let mut c = m.clone();
        c.push(name.to_owned());
        modules.contains_key(&c).then_some(c)
    };
    let first = path.first()?;
    let (mut base, mut rest) = match first.as_str() {
        "crate" => (Vec::new(), &path[1..]),
        "self" => (from.clone(), &path[1..]),
        "super" => {
            let mut base = from.clone();
            let mut rest = path;
            while rest.first().is_some_and(|s| s == "super") {
                base.pop()?;
                rest = &rest[1..];
            }
            (base, rest)
        }
        name if child(from, name).is_some() => (from.clone(), path),
        _ => return None,
    };
    while let Some(next) = rest.first().and_then(|n| child(&base, n)) {
        base = next;
        rest = &rest[1..];
    }
    let Some(item) = rest.first() else {
        return Some(base);
    };
    if steps < 8
        && let Some((_, import)) = modules[&base].imports.iter().find(|(n, _)| n == item)
    {
        let mut through = import.clone();
        through.extend(rest[1..].iter().cloned());
        return resolve(modules, &base, &through, steps + 1);
    }
    Some(base)
}

/// The strongly connected components of `graph` with more than one file (Tarjan's
/// algorithm): each a module cycle, its files sorted.
fn cycles(graph: &BTreeMap<String, BTreeSet<String>>) -> Vec<Vec<String>> {
    struct State<'a> {
        graph: &'a BTreeMap<String, BTreeSet<String>>,
        index: BTreeMap<&'a str, usize>,
        low: BTreeMap<&'a str, usize>,
        stack: Vec<&'a str>,
        on_stack: BTreeSet<&'a str>,
        out: Vec<Vec<String>>,
    }
    fn visit<'a>(s: &mut State<'a>, v: &'a str) {
        let n = s.index.len();
        s.index.insert(v, n);
        s.low.insert(v, n);
        s.stack.push(v);
        s.on_stack.insert(v);
        for w in s.graph.get(v).into_iter().flatten() {
            let w = w.as_str();
            if !s.index.contains_key(w) {
                visit(s, w);
                let lw = s.low[w];
                let lv = s.low.get_mut(v).expect("visited");
                *lv = (*lv).min(lw);
            } else if s.on_stack.contains(w) {
                let iw = s.index[w];
                let lv = s.low.get_mut(v).expect("visited");
                *lv = (*lv).min(iw);
            }
        }
        if s.low[v] == s.index[v] {
            let mut component = Vec::new();
            while let Some(w) = s.stack.pop() {
                s.on_stack.remove(w);
                component.push(w.to_owned());
                if w == v {
                    break;
                }
            }
            if component.len() > 1 {
                component.sort();
                s.out.push(component);
            }
        }
    }
    let mut s = State {
        graph,
        index: BTreeMap::new(),
        low: BTreeMap::new(),
        stack: Vec::new(),
        on_stack: BTreeSet::new(),
        out: Vec::new(),
    };
    for v in graph.keys() {
        if !s.index.contains_key(v.as_str()) {
            visit(&mut s, v);
        }
    }
    s.out.sort();
    s.out
}

/// The module cycles of one crate's sources (see [`module_graph`] for what an edge is),
/// from every crate root among them (`lib.rs`, `main.rs`, `bin/*.rs`).
fn crate_cycles(files: &BTreeMap<String, String>) -> Vec<Vec<String>> {
    let mut out = Vec::new();
    for root in files.keys() {
        let is_root = root == "lib.rs"
            || root == "main.rs"
            || (root.starts_with("bin/") && root.matches('/').count() == 1);
        if is_root {
            out.extend(cycles(&module_graph(files, root)));
        }
    }
    out
}

/// Every crate's sources: `crates/*/src` and `tests/src`, each as its folder (relative to
/// the workspace root) and its files.
fn workspace_sources() -> Vec<(String, BTreeMap<String, String>)> {
    let root = root();
    let mut dirs: Vec<String> = crate_dirs(&root)
        .into_iter()
        .map(|c| format!("crates/{c}/src"))
        .collect();
    dirs.push("tests/src".into());
    dirs.into_iter()
        .map(|dir| {
            let files = rust_files(&root.join(&dir))
                .into_iter()
                .map(|f| {
                    let text = read(&root.join(&dir).join(&f));
                    (f.to_string_lossy().replace('\\', "/"), text)
                })
                .collect();
            (dir, files)
        })
        .collect()
}

/// ARCHITECTURE.md: "the modules form a downward stack": no crate has a module cycle
/// (files that name each other's items, directly or through others; [`module_graph`]
/// says what naming is). Two modules in a cycle are one concept split in two files, or
/// two concepts that share an item that belongs below both: move that item to a leaf
/// module. There is no allow-list.
#[test]
fn no_module_cycles() {
    let mut found = Vec::new();
    for (dir, files) in workspace_sources() {
        for cycle in crate_cycles(&files) {
            found.push(format!("{dir}: {}", cycle.join(", ")));
        }
    }
    assert!(
        found.is_empty(),
        "module cycles (move the items the files share to a module below them):\n{}",
        found.join("\n")
    );
}

/// The sources of a synthetic crate: `(path, text)` pairs.
fn sources(files: &[(&str, &str)]) -> BTreeMap<String, String> {
    files
        .iter()
        .map(|(p, t)| ((*p).to_owned(), (*t).to_owned()))
        .collect()
}

/// The cycle finder on planted examples: a sibling cycle through a grouped import and a
/// code path, a child using its parent's item while the parent uses the child's, and what
/// must not count (the `mod` declaration, re-exports, comments, strings, test modules).
#[test]
fn the_cycle_check_can_fail() {
    // b -> a by a grouped import, a -> b by a path in code.
    let planted = sources(&[
        ("lib.rs", "mod a;\nmod b;\n"),
        ("a.rs", "pub fn f() -> u32 { crate::b::g() }\n"),
        ("b.rs", "use crate::{a::f, c};\npub fn g() -> u32 { 1 }\n"),
    ]);
    assert_eq!(crate_cycles(&planted), [["a.rs", "b.rs"]]);
    // A child naming its parent's item, the parent naming a third module's, which names
    // the child's.
    let through_parent = sources(&[
        ("lib.rs", "mod m;\nmod o;\n"),
        ("m/mod.rs", "mod k;\nuse crate::o::O;\npub struct P(O);\n"),
        (
            "m/k.rs",
            "use super::P;\npub struct K;\nimpl K { fn p(_: P) {} }\n",
        ),
        ("o.rs", "pub struct O(crate::m::k::K);\n"),
    ]);
    assert_eq!(
        crate_cycles(&through_parent),
        [["m/k.rs", "m/mod.rs", "o.rs"]]
    );
    // A parent naming its child's items while the child names the parent's is no cycle:
    // the parent is made of its children.
    let parent = sources(&[
        ("lib.rs", "mod m;\n"),
        ("m/mod.rs", "mod k;\nuse k::K;\npub struct P(K);\n"),
        (
            "m/k.rs",
            "use super::P;\npub struct K;\nimpl K { fn p(_: P) {} }\n",
        ),
    ]);
    assert_eq!(crate_cycles(&parent), Vec::<Vec<String>>::new());
    assert_eq!(
        module_graph(&parent, "lib.rs")["m/k.rs"],
        BTreeSet::from(["m/mod.rs".to_owned()])
    );
    // `super` inside an inline module (a macro's `mod $m { .. }` too) is relative to it:
    // `x::y` uses `x`, not the root (which would close the cycle x, z, lib).
    let inline = sources(&[
        ("lib.rs", "mod x;\nmod z;\npub fn r() {}\n"),
        (
            "x.rs",
            "pub fn f() {}\nmod y { use super::f; }\nmacro_rules! m { ($n:ident) => { mod $n { use super::f; } } }\n",
        ),
        ("z.rs", "pub fn g() { crate::x::f(); crate::r(); }\n"),
    ]);
    assert_eq!(crate_cycles(&inline), Vec::<Vec<String>>::new());
    assert!(module_graph(&inline, "lib.rs")["x.rs"].is_empty());
    // No cycle: declarations, re-exports used through the root, comments, strings, raw
    // strings, lifetimes and test modules are not edges.
    let clean = sources(&[
        (
            "lib.rs",
            "mod a;\nmod b;\npub use a::A;\npub use glam::Vec3;\n",
        ),
        (
            "a.rs",
            "// crate::b::g\n/* crate::b::g */\npub struct A<'a>(&'a str);\n\
             const S: &str = \"crate::b::g\";\nconst R: &str = r#\"crate::b::g\"#;\n\
             const C: char = '\"';\n#[cfg(test)]\nmod tests { use crate::b::g; }\n",
        ),
        (
            "b.rs",
            "use crate::{A, Vec3};\npub fn g(_: A<'_>, _: Vec3) {}\n",
        ),
    ]);
    assert_eq!(crate_cycles(&clean), Vec::<Vec<String>>::new());
    assert_eq!(
        module_graph(&clean, "lib.rs")["b.rs"],
        BTreeSet::from(["a.rs".to_owned()])
    );
}

// ---------------------------------------------------------------------------------------
// The WGSL kernels name the Rust routines they port.
// ---------------------------------------------------------------------------------------

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
    let mut rust = Vec::new();
    for dir in crate_dirs(&root) {
        let src = root.join("crates").join(&dir).join("src");
        for f in rust_files(&src) {
            let path = format!(
                "crates/{dir}/src/{}",
                f.to_string_lossy().replace('\\', "/")
            );
            rust.push((path, strip_comments_and_literals(&read(&src.join(&f)))));
        }
    }
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
