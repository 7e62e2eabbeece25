//! No module cycles: within each crate, the files' modules form a downward stack. A small
//! reader of Rust source (tokens, `use` trees, paths, inline modules) builds each crate's
//! module graph at file granularity; its strongly connected components are the cycles.

use crate::workspace::crate_dirs;
use crate::{root, rust_sources, strip_comments_and_literals};
use std::collections::{BTreeMap, BTreeSet};

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
            // Each file by its path from `src/`.
            let files = rust_sources(&dir)
                .into_iter()
                .map(|(path, text)| (path[dir.len() + 1..].to_owned(), text))
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
