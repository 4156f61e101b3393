//! `cargo xtask tidy`: checks the invariants that ARCHITECTURE.md states, by reading them from
//! ARCHITECTURE.md itself and by *parsing* the sources (with `syn`), not by substring search.
//!
//! The invariants live in ARCHITECTURE.md as fenced blocks tagged `tidy` so that the document and
//! the check cannot drift apart:
//!
//! - `layers`: one line per workspace crate, `crate: dep, dep | external, external`; the crate's
//!   normal (non-dev, non-build) dependencies on workspace crates must be among the first list,
//!   and, when a `|` part is present, its external normal dependencies among the second.
//! - `libraries`: the crates that do no I/O and form no dense N×N matrix on the solve path.
//! - `constants`: `crate::NAME = value` lines; each named constant must exist in the crate's
//!   sources with exactly that value, so the numbers the document quotes are the code's.
//!
//! Checks:
//! 1. **Layering** (`cargo metadata`).
//! 2. **No I/O in libraries**: outside `#[cfg(test)]` items, no path through `std::fs`,
//!    `std::io`, `std::net`, `std::process` or `std::env` (in `use` trees too, so
//!    `use std::{fs, io}` is caught), no `File`/`Stdin`/`Stdout`, and no printing macros.
//! 3. **No dense N×N matrix on the solve path**: in the libraries' non-test code, no nalgebra
//!    dynamic matrix type (`DMatrix`, `DVector`, `OMatrix`, `Dyn`) outside files named `dense.rs`
//!    or items gated by `#[cfg(feature = "dense")]`, and no square nested `vec![vec![x; n]; n]`.
//! 4. **No duplicate crate** in any library's runtime dependency graph (`cargo tree -d`,
//!    normal edges, proc-macros excluded): one nalgebra, one num-traits, ….
//! 5. **Flat, structured public surfaces**: a library's root re-exports no glob (`pub use x::*`),
//!    and it has exactly one public error enum `Error`, `#[non_exhaustive]`.
//! 6. **Files a reader can hold**: no source file over [`MAX_LINES`] lines unless its module
//!    docs contain a paragraph starting `One piece:` that says why.
//! 7. **Documented numbers are the code's** (the `constants` block).
//! 8. **Every saved proptest case is replayed**: each `crates/C/proptest-regressions/P.txt`
//!    (proptest's file beside the source, `FileFailurePersistence::SourceParallel`) belongs to a
//!    source file `crates/C/src/P.rs`, and each `crates/C/tests/X.proptest-regressions` to
//!    `crates/C/tests/X.rs`, that holds a `proptest!` block. A test module moved to another file
//!    leaves its saved cases behind, where proptest no longer reads them.

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

use syn::visit::Visit;

/// Longest source file (lines) without a `One piece:` paragraph in its module docs.
const MAX_LINES: usize = 1200;

/// The `tidy` blocks of ARCHITECTURE.md.
struct Invariants {
    /// crate → (allowed workspace deps, allowed external deps if restricted).
    layers: BTreeMap<String, (BTreeSet<String>, Option<BTreeSet<String>>)>,
    libraries: Vec<String>,
    /// (crate, constant, value as written).
    constants: Vec<(String, String, String)>,
}

pub fn run(_args: &[String]) -> anyhow::Result<bool> {
    let doc = std::fs::read_to_string("ARCHITECTURE.md")?;
    let inv = parse_invariants(&doc)?;
    let mut problems = Vec::new();
    check_layers(&inv, &mut problems)?;
    for lib in &inv.libraries {
        let src = Path::new("crates").join(lib).join("src");
        anyhow::ensure!(
            src.is_dir(),
            "ARCHITECTURE.md names library {lib}, but {src:?} is missing"
        );
        walk_modules(&src.join("lib.rs"), true, &mut problems)?;
        check_root(lib, &src.join("lib.rs"), &mut problems)?;
        check_duplicates(lib, &mut problems)?;
    }
    check_sizes(&mut problems)?;
    check_constants(&inv, &mut problems)?;
    check_regressions(Path::new("crates"), &mut problems)?;
    for p in &problems {
        println!("tidy: {p}");
    }
    println!("tidy: {} problem(s)", problems.len());
    Ok(problems.is_empty())
}

/// Reads the fenced ```` ```tidy <name> ```` blocks of ARCHITECTURE.md.
fn parse_invariants(doc: &str) -> anyhow::Result<Invariants> {
    let mut blocks: BTreeMap<String, Vec<String>> = BTreeMap::new();
    let mut current: Option<String> = None;
    for line in doc.lines() {
        let t = line.trim();
        if let Some(name) = current.as_ref() {
            if t.starts_with("```") {
                current = None;
            } else if !t.is_empty() && !t.starts_with('#') {
                blocks.get_mut(name).expect("block").push(t.to_string());
            }
        } else if let Some(rest) = t.strip_prefix("```tidy ") {
            let name = rest.trim().to_string();
            blocks.entry(name.clone()).or_default();
            current = Some(name);
        }
    }
    let set = |s: &str| -> BTreeSet<String> {
        s.split(',')
            .map(str::trim)
            .filter(|x| !x.is_empty() && *x != "-")
            .map(String::from)
            .collect()
    };
    let mut layers = BTreeMap::new();
    for line in blocks.get("layers").into_iter().flatten() {
        let (name, rest) = line
            .split_once(':')
            .ok_or_else(|| anyhow::anyhow!("ARCHITECTURE.md layers: bad line {line:?}"))?;
        let (internal, external) = match rest.split_once('|') {
            Some((a, b)) => (set(a), Some(set(b))),
            None => (set(rest), None),
        };
        layers.insert(name.trim().to_string(), (internal, external));
    }
    let libraries = blocks
        .get("libraries")
        .into_iter()
        .flatten()
        .flat_map(|l| set(l))
        .collect::<Vec<_>>();
    let mut constants = Vec::new();
    for line in blocks.get("constants").into_iter().flatten() {
        let (path, value) = line
            .split_once('=')
            .ok_or_else(|| anyhow::anyhow!("ARCHITECTURE.md constants: bad line {line:?}"))?;
        let (krate, name) = path
            .trim()
            .split_once("::")
            .ok_or_else(|| anyhow::anyhow!("ARCHITECTURE.md constants: bad path {path:?}"))?;
        constants.push((
            krate.to_string(),
            name.to_string(),
            value.trim().to_string(),
        ));
    }
    anyhow::ensure!(
        !layers.is_empty(),
        "ARCHITECTURE.md has no ```tidy layers block"
    );
    anyhow::ensure!(
        !libraries.is_empty(),
        "ARCHITECTURE.md has no ```tidy libraries block"
    );
    Ok(Invariants {
        layers,
        libraries,
        constants,
    })
}

fn cargo() -> std::process::Command {
    std::process::Command::new(std::env::var("CARGO").unwrap_or_else(|_| "cargo".into()))
}

fn check_layers(inv: &Invariants, problems: &mut Vec<String>) -> anyhow::Result<()> {
    let out = cargo()
        .args(["metadata", "--format-version", "1", "--no-deps"])
        .output()?;
    anyhow::ensure!(out.status.success(), "cargo metadata failed");
    let meta: serde_json::Value = serde_json::from_slice(&out.stdout)?;
    let members: BTreeSet<String> = meta["packages"]
        .as_array()
        .into_iter()
        .flatten()
        .filter_map(|p| p["name"].as_str().map(String::from))
        .collect();
    for pkg in meta["packages"].as_array().into_iter().flatten() {
        let name = pkg["name"].as_str().unwrap_or("");
        let Some((internal, external)) = inv.layers.get(name) else {
            problems.push(format!(
                "layering: workspace crate {name} is not in ARCHITECTURE.md's layers block"
            ));
            continue;
        };
        for dep in pkg["dependencies"].as_array().into_iter().flatten() {
            let dname = dep["name"].as_str().unwrap_or("");
            if !dep["kind"].is_null() {
                continue; // dev- and build-dependencies are not layering
            }
            if members.contains(dname) {
                if !internal.contains(dname) {
                    problems.push(format!("layering: {name} must not depend on {dname}"));
                }
            } else if let Some(ext) = external {
                if !ext.contains(dname) {
                    problems.push(format!(
                        "layering: {name} must not depend on the external crate {dname}"
                    ));
                }
            }
        }
    }
    for name in inv.layers.keys() {
        if !members.contains(name) {
            problems.push(format!(
                "layering: ARCHITECTURE.md names {name}, which is not a workspace crate"
            ));
        }
    }
    Ok(())
}

/// `cargo tree -d` of one library, normal edges without proc-macros: one version of each crate.
fn check_duplicates(lib: &str, problems: &mut Vec<String>) -> anyhow::Result<()> {
    let out = cargo()
        .args([
            "tree",
            "-d",
            "-p",
            lib,
            "-e",
            "normal,no-proc-macro",
            "--prefix",
            "none",
        ])
        .output()?;
    anyhow::ensure!(out.status.success(), "cargo tree -d -p {lib} failed");
    let text = String::from_utf8_lossy(&out.stdout);
    for line in text.lines() {
        let line = line.trim();
        if !line.is_empty() && !line.starts_with("nothing to print") {
            problems.push(format!(
                "duplicates: {lib}'s dependency graph holds two versions of {line}"
            ));
        }
    }
    Ok(())
}

/// The root of a library: no glob re-export, exactly one `#[non_exhaustive]` public `Error`.
fn check_root(lib: &str, lib_rs: &Path, problems: &mut Vec<String>) -> anyhow::Result<()> {
    let file = syn::parse_file(&std::fs::read_to_string(lib_rs)?)?;
    for item in &file.items {
        if let syn::Item::Use(u) = item {
            if matches!(u.vis, syn::Visibility::Public(_)) && has_glob(&u.tree) {
                problems.push(format!(
                    "{}: `pub use …::*` at the root of {lib} (re-export names, not globs)",
                    lib_rs.display()
                ));
            }
        }
    }
    // Find `pub enum Error` anywhere in the crate and check it is non_exhaustive.
    let mut found = 0;
    for path in rust_files(lib_rs.parent().expect("src"))? {
        let file = syn::parse_file(&std::fs::read_to_string(&path)?)?;
        for item in &file.items {
            if let syn::Item::Enum(e) = item {
                if e.ident == "Error" && matches!(e.vis, syn::Visibility::Public(_)) {
                    found += 1;
                    if !e.attrs.iter().any(|a| a.path().is_ident("non_exhaustive")) {
                        problems.push(format!(
                            "{}: {lib}'s Error is not #[non_exhaustive]",
                            path.display()
                        ));
                    }
                }
            }
        }
    }
    if found != 1 {
        problems.push(format!(
            "{lib}: {found} public `enum Error` (one per library crate)"
        ));
    }
    Ok(())
}

fn has_glob(t: &syn::UseTree) -> bool {
    match t {
        syn::UseTree::Glob(_) => true,
        syn::UseTree::Path(p) => has_glob(&p.tree),
        syn::UseTree::Group(g) => g.items.iter().any(has_glob),
        _ => false,
    }
}

/// Every `.rs` file under `crates/*/src`, `xtask/src` and `tests/` longer than [`MAX_LINES`]
/// must say why in its module docs (`One piece: …`).
fn check_sizes(problems: &mut Vec<String>) -> anyhow::Result<()> {
    let mut files = Vec::new();
    for entry in std::fs::read_dir("crates")? {
        let src = entry?.path().join("src");
        if src.is_dir() {
            files.extend(rust_files(&src)?);
        }
    }
    files.extend(rust_files(Path::new("xtask/src"))?);
    for path in files {
        let text = std::fs::read_to_string(&path)?;
        let lines = text.lines().count();
        if lines <= MAX_LINES {
            continue;
        }
        let says_why = syn::parse_file(&text).is_ok_and(|f| {
            f.attrs
                .iter()
                .filter_map(doc_text)
                .any(|l| l.trim_start().starts_with("One piece:"))
        });
        if !says_why {
            problems.push(format!(
                "{}: {lines} lines; split it along its concepts or say why it is one piece \
                 (a module-doc paragraph starting `One piece:`)",
                path.display()
            ));
        }
    }
    Ok(())
}

/// Check 8: the saved proptest cases under each crate's `proptest-regressions/` belong to a
/// source file with property tests (the file proptest derives their path from).
fn check_regressions(crates: &Path, problems: &mut Vec<String>) -> anyhow::Result<()> {
    for entry in std::fs::read_dir(crates)? {
        let krate = entry?.path();
        let saved = krate.join("proptest-regressions");
        let mut pairs = Vec::new();
        for file in files_with(&saved, "txt")? {
            let source = krate
                .join("src")
                .join(file.strip_prefix(&saved)?.with_extension("rs"));
            pairs.push((file, source));
        }
        // An integration test's cases sit beside it: `tests/X.proptest-regressions`.
        for file in files_with(&krate.join("tests"), "proptest-regressions")? {
            let source = file.with_extension("rs");
            pairs.push((file, source));
        }
        for (file, source) in pairs {
            let replayed =
                std::fs::read_to_string(&source).is_ok_and(|text| text.contains("proptest!"));
            if !replayed {
                problems.push(format!(
                    "{}: saved proptest cases that no test replays ({} holds no `proptest!`); \
                     move the file beside the tests' source",
                    file.display(),
                    source.display()
                ));
            }
        }
    }
    Ok(())
}

fn doc_text(a: &syn::Attribute) -> Option<String> {
    if !a.path().is_ident("doc") {
        return None;
    }
    if let syn::Meta::NameValue(nv) = &a.meta {
        if let syn::Expr::Lit(syn::ExprLit {
            lit: syn::Lit::Str(s),
            ..
        }) = &nv.value
        {
            return Some(s.value());
        }
    }
    None
}

/// Each `crate::NAME = value` of the constants block is a `const NAME` in that crate's sources
/// whose initializer is exactly `value` (compared as tokens, so `1e-9` matches `1e-9`).
fn check_constants(inv: &Invariants, problems: &mut Vec<String>) -> anyhow::Result<()> {
    for (krate, name, value) in &inv.constants {
        let src = Path::new("crates").join(krate).join("src");
        let mut found = Vec::new();
        for path in rust_files(&src)? {
            let file = syn::parse_file(&std::fs::read_to_string(&path)?)?;
            let mut v = ConstFinder {
                name,
                found: &mut found,
            };
            v.visit_file(&file);
        }
        let want: syn::Expr = syn::parse_str(value)
            .map_err(|e| anyhow::anyhow!("ARCHITECTURE.md constant {krate}::{name}: {e}"))?;
        let want = quote_tokens(&want);
        match found.as_slice() {
            [] => problems.push(format!(
                "constants: ARCHITECTURE.md quotes {krate}::{name} = {value}, but {krate} has no such constant"
            )),
            [got] if *got == want => {}
            [got] => problems.push(format!(
                "constants: ARCHITECTURE.md quotes {krate}::{name} = {value}, the code says {got}"
            )),
            _ => problems.push(format!(
                "constants: {krate} defines {name} {} times",
                found.len()
            )),
        }
    }
    Ok(())
}

fn quote_tokens(e: &syn::Expr) -> String {
    use quote::ToTokens;
    e.to_token_stream().to_string()
}

struct ConstFinder<'a> {
    name: &'a str,
    found: &'a mut Vec<String>,
}

impl<'ast> Visit<'ast> for ConstFinder<'_> {
    fn visit_item_const(&mut self, c: &'ast syn::ItemConst) {
        if c.ident == self.name {
            self.found.push(quote_tokens(&c.expr));
        }
    }
    fn visit_impl_item_const(&mut self, c: &'ast syn::ImplItemConst) {
        if c.ident == self.name {
            self.found.push(quote_tokens(&c.expr));
        }
    }
}

/// Walks one library source file, skipping test-only items.
struct SourceCheck<'a> {
    path: &'a Path,
    dense_file: bool,
    problems: Vec<String>,
}

const IO_MODULES: &[&str] = &["fs", "io", "net", "process", "env"];
const IO_TYPES: &[&str] = &["File", "Stdin", "Stdout", "Stderr", "OpenOptions"];
const PRINT_MACROS: &[&str] = &["println", "eprintln", "print", "eprint", "dbg"];
const DENSE_TYPES: &[&str] = &["DMatrix", "DVector", "OMatrix", "Dyn", "MatrixXx"];

impl<'a> SourceCheck<'a> {
    fn new(path: &'a Path) -> Self {
        SourceCheck {
            path,
            dense_file: path.file_name().is_some_and(|f| f == "dense.rs"),
            problems: Vec::new(),
        }
    }

    fn report(&mut self, span: proc_macro2::Span, what: String) {
        self.problems.push(format!(
            "{}:{}: {what}",
            self.path.display(),
            span.start().line
        ));
    }

    fn check_segments(&mut self, segs: &[String], span: proc_macro2::Span) {
        if segs.len() >= 2 && segs[0] == "std" && IO_MODULES.contains(&segs[1].as_str()) {
            self.report(span, format!("library does I/O (std::{})", segs[1]));
        }
        if let Some(last) = segs.last() {
            if IO_TYPES.contains(&last.as_str()) {
                self.report(span, format!("library does I/O ({last})"));
            }
            if !self.dense_file && DENSE_TYPES.contains(&last.as_str()) {
                self.report(
                    span,
                    format!("dense matrix type {last} on the solve path (allowed in dense.rs, tests, or behind the `dense` feature)"),
                );
            }
        }
    }
}

/// `#[cfg(test)]`, `#[test]`, or `#[cfg(feature = "dense")]`: not part of the solve path.
fn skipped(attrs: &[syn::Attribute]) -> bool {
    attrs.iter().any(|a| {
        if a.path().is_ident("test") {
            return true;
        }
        if !a.path().is_ident("cfg") {
            return false;
        }
        let tokens = a
            .meta
            .require_list()
            .map(|l| l.tokens.to_string())
            .unwrap_or_default();
        tokens == "test" || tokens.replace(' ', "") == "feature=\"dense\""
    })
}

fn use_paths(t: &syn::UseTree, prefix: &mut Vec<String>, out: &mut Vec<Vec<String>>) {
    match t {
        syn::UseTree::Path(p) => {
            prefix.push(p.ident.to_string());
            use_paths(&p.tree, prefix, out);
            prefix.pop();
        }
        syn::UseTree::Name(n) => {
            let mut v = prefix.clone();
            v.push(n.ident.to_string());
            out.push(v);
        }
        syn::UseTree::Rename(r) => {
            let mut v = prefix.clone();
            v.push(r.ident.to_string());
            out.push(v);
        }
        syn::UseTree::Glob(_) => out.push(prefix.clone()),
        syn::UseTree::Group(g) => {
            for i in &g.items {
                use_paths(i, prefix, out);
            }
        }
    }
}

impl<'ast> Visit<'ast> for SourceCheck<'_> {
    fn visit_item(&mut self, i: &'ast syn::Item) {
        let attrs: &[syn::Attribute] = match i {
            syn::Item::Mod(m) => &m.attrs,
            syn::Item::Fn(f) => &f.attrs,
            syn::Item::Impl(x) => &x.attrs,
            syn::Item::Use(u) => &u.attrs,
            syn::Item::Struct(s) => &s.attrs,
            syn::Item::Enum(e) => &e.attrs,
            syn::Item::Const(c) => &c.attrs,
            syn::Item::Static(s) => &s.attrs,
            syn::Item::Trait(t) => &t.attrs,
            syn::Item::Type(t) => &t.attrs,
            _ => &[],
        };
        if skipped(attrs) {
            return;
        }
        syn::visit::visit_item(self, i);
    }

    fn visit_impl_item_fn(&mut self, f: &'ast syn::ImplItemFn) {
        if !skipped(&f.attrs) {
            syn::visit::visit_impl_item_fn(self, f);
        }
    }

    fn visit_item_use(&mut self, u: &'ast syn::ItemUse) {
        let mut out = Vec::new();
        use_paths(&u.tree, &mut Vec::new(), &mut out);
        let span = u.use_token.span;
        for p in out {
            self.check_segments(&p, span);
        }
    }

    fn visit_path(&mut self, p: &'ast syn::Path) {
        let segs: Vec<String> = p.segments.iter().map(|s| s.ident.to_string()).collect();
        let span = p
            .segments
            .first()
            .map_or_else(proc_macro2::Span::call_site, |s| s.ident.span());
        self.check_segments(&segs, span);
        syn::visit::visit_path(self, p);
    }

    fn visit_macro(&mut self, m: &'ast syn::Macro) {
        let name = m
            .path
            .segments
            .last()
            .map(|s| s.ident.to_string())
            .unwrap_or_default();
        let span = m
            .path
            .segments
            .first()
            .map_or_else(proc_macro2::Span::call_site, |s| s.ident.span());
        if PRINT_MACROS.contains(&name.as_str()) {
            self.report(span, format!("library prints ({name}!)"));
        }
        if name == "vec" && !self.dense_file {
            if let Some((inner, outer)) = square_nested_vec(m) {
                self.report(
                    span,
                    format!(
                        "dense square matrix vec![vec![_; {inner}]; {outer}] on the solve path"
                    ),
                );
            }
        }
        // Paths inside macro bodies (format!, assert!, …) are tokens; check the common case of
        // a path expression parsed from the arguments.
        if let Ok(args) = m.parse_body_with(
            syn::punctuated::Punctuated::<syn::Expr, syn::Token![,]>::parse_terminated,
        ) {
            for a in &args {
                self.visit_expr(a);
            }
        }
    }
}

/// `vec![vec![x; a]; b]` with `a` and `b` the same expression: an a × a dense matrix.
fn square_nested_vec(m: &syn::Macro) -> Option<(String, String)> {
    let tokens = m.tokens.to_string();
    let (elem, outer) = tokens.rsplit_once(';')?;
    let elem = elem.trim();
    let inner_body = elem.strip_prefix("vec !")?.trim();
    let inner_body = inner_body.strip_prefix('[')?.strip_suffix(']')?;
    let (_, inner) = inner_body.rsplit_once(';')?;
    let (inner, outer) = (inner.trim().to_string(), outer.trim().to_string());
    (inner == outer).then_some((inner, outer))
}

/// Checks one module file and, recursively, the files of the `mod x;` items it declares outside
/// test code (a `#[cfg(test)] mod tests;` file is test code and is not visited).
fn walk_modules(path: &Path, owns_dir: bool, problems: &mut Vec<String>) -> anyhow::Result<()> {
    let text =
        std::fs::read_to_string(path).map_err(|e| anyhow::anyhow!("{}: {e}", path.display()))?;
    let file = match syn::parse_file(&text) {
        Ok(f) => f,
        Err(e) => {
            problems.push(format!("{}: does not parse: {e}", path.display()));
            return Ok(());
        }
    };
    let mut v = SourceCheck::new(path);
    v.visit_file(&file);
    problems.extend(v.problems);
    // `lib.rs`/`mod.rs` own their directory; `foo.rs` owns `foo/`.
    let dir = if owns_dir {
        path.parent().expect("parent").to_path_buf()
    } else {
        path.with_extension("")
    };
    for item in &file.items {
        let syn::Item::Mod(m) = item else { continue };
        if m.content.is_some() || skipped(&m.attrs) {
            continue;
        }
        let explicit = m
            .attrs
            .iter()
            .find(|a| a.path().is_ident("path"))
            .and_then(|a| match &a.meta {
                syn::Meta::NameValue(syn::MetaNameValue {
                    value:
                        syn::Expr::Lit(syn::ExprLit {
                            lit: syn::Lit::Str(s),
                            ..
                        }),
                    ..
                }) => Some(s.value()),
                _ => None,
            });
        let name = m.ident.to_string();
        let (child, child_owns) = match explicit {
            Some(p) => (dir.join(p), false),
            None if dir.join(format!("{name}.rs")).exists() => {
                (dir.join(format!("{name}.rs")), false)
            }
            None => (dir.join(&name).join("mod.rs"), true),
        };
        walk_modules(&child, child_owns, problems)?;
    }
    Ok(())
}

fn rust_files(dir: &Path) -> anyhow::Result<Vec<PathBuf>> {
    files_with(dir, "rs")
}

/// The files under `dir` (recursively, sorted) whose extension is `ext`; none when `dir` does
/// not exist.
fn files_with(dir: &Path, ext: &str) -> anyhow::Result<Vec<PathBuf>> {
    let mut out = Vec::new();
    if !dir.exists() {
        return Ok(out);
    }
    let mut entries: Vec<_> = std::fs::read_dir(dir)?.collect::<Result<_, _>>()?;
    entries.sort_by_key(|e| e.path());
    for entry in entries {
        let path = entry.path();
        if path.is_dir() {
            out.extend(files_with(&path, ext)?);
        } else if path.extension().is_some_and(|e| e == ext) {
            out.push(path);
        }
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A saved case beside a source file without property tests (the tests moved away) is
    /// reported; beside one with them, or a nested module's (`a/tests.rs`), it is not.
    #[test]
    fn saved_cases_must_sit_beside_their_tests() {
        let root = std::env::temp_dir().join(format!("tidy-regressions-{}", std::process::id()));
        let krate = root.join("k");
        std::fs::create_dir_all(krate.join("src/a")).unwrap();
        std::fs::create_dir_all(krate.join("proptest-regressions/a")).unwrap();
        std::fs::write(krate.join("src/a.rs"), "mod tests;").unwrap();
        std::fs::write(krate.join("src/a/tests.rs"), "proptest! {}").unwrap();
        std::fs::write(krate.join("proptest-regressions/a/tests.txt"), "cc 1").unwrap();
        let mut problems = Vec::new();
        check_regressions(&root, &mut problems).unwrap();
        assert!(problems.is_empty(), "{problems:?}");
        std::fs::create_dir_all(krate.join("tests")).unwrap();
        std::fs::write(krate.join("tests/t.rs"), "proptest! {}").unwrap();
        std::fs::write(krate.join("tests/t.proptest-regressions"), "cc 3").unwrap();
        check_regressions(&root, &mut problems).unwrap();
        assert!(problems.is_empty(), "{problems:?}");
        std::fs::write(krate.join("proptest-regressions/a.txt"), "cc 2").unwrap();
        std::fs::write(krate.join("tests/gone.proptest-regressions"), "cc 4").unwrap();
        check_regressions(&root, &mut problems).unwrap();
        std::fs::remove_dir_all(&root).unwrap();
        assert_eq!(problems.len(), 2, "{problems:?}");
        assert!(problems[0].contains("a.txt"), "{problems:?}");
        assert!(problems[1].contains("gone.proptest"), "{problems:?}");
    }

    fn problems_in(src: &str) -> Vec<String> {
        let file = syn::parse_file(src).unwrap();
        let mut v = SourceCheck::new(Path::new("x.rs"));
        v.visit_file(&file);
        v.problems
    }

    #[test]
    fn io_is_found_through_use_groups_and_paths() {
        assert_eq!(problems_in("use std::{fs, io};").len(), 2);
        assert_eq!(
            problems_in("fn f() { let _ = std::fs::read(\"x\"); }").len(),
            1
        );
        assert_eq!(problems_in("fn f() { println!(\"x\"); }").len(), 1);
        assert!(
            problems_in("#[cfg(test)] mod t { use std::fs; fn f() { println!(); } }").is_empty()
        );
    }

    #[test]
    fn dense_matrices_are_found() {
        assert_eq!(
            problems_in("fn f(n: usize) { let a = vec![vec![0.0; n]; n]; }").len(),
            1
        );
        assert!(
            problems_in("fn f(n: usize, d: usize) { let a = vec![vec![0.0; d]; n]; }").is_empty()
        );
        assert_eq!(problems_in("use nalgebra::DMatrix;").len(), 1);
        assert!(
            problems_in("#[cfg(feature = \"dense\")] mod d { use nalgebra::DMatrix; }").is_empty()
        );
    }

    #[test]
    fn invariants_parse_from_fenced_blocks() {
        let doc = "x\n```tidy layers\na: b, c | serde\nb:\n```\n```tidy libraries\na, b\n```\n```tidy constants\na::X = 1e-9\n```\n";
        let inv = parse_invariants(doc).unwrap();
        assert_eq!(inv.layers.len(), 2);
        assert_eq!(inv.libraries, vec!["a", "b"]);
        assert_eq!(inv.constants[0].2, "1e-9");
        assert!(inv.layers["a"].1.as_ref().unwrap().contains("serde"));
    }
}
