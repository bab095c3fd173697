//! `cargo xtask tidy`: the repository's own rules, checked as text (run by `.ci/run`).
//!
//! Five checks, each a function over the files below the workspace root so that a test can
//! run it on a tree it makes:
//! - [`layers`]: every crate's `indentify-*` dependencies are among those ARCHITECTURE.md
//!   allows it (the table between `<!-- tidy:layers -->` markers);
//! - [`unused_dependencies`]: every `[dependencies]` entry of a crate is named in its sources
//!   (or listed under `[package.metadata.tidy] used-without-path` with the reason beside it);
//! - [`doc_lines`]: every Rust file opens with a `//!` line;
//! - [`outside_references`]: no code or document cites a file outside the repository or a
//!   tracker number;
//! - [`function_lengths`]: no function over the budget (150 lines in `study` and the front
//!   ends, 250 in the libraries; tests, benches and examples are not counted).

use std::collections::{BTreeMap, BTreeSet};
use std::fmt;
use std::path::{Path, PathBuf};

/// One broken rule, with the place that breaks it.
#[derive(Debug, Clone, PartialEq, Eq, PartialOrd, Ord)]
pub struct Finding {
    /// The file, relative to the root.
    pub file: PathBuf,
    /// 1-based line, 0 when the finding is about the whole file.
    pub line: usize,
    /// The check that found it.
    pub check: &'static str,
    /// What is wrong, and what the rule is.
    pub message: String,
}

impl fmt::Display for Finding {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        if self.line > 0 {
            write!(
                f,
                "{}:{}: [{}] {}",
                self.file.display(),
                self.line,
                self.check,
                self.message
            )
        } else {
            write!(
                f,
                "{}: [{}] {}",
                self.file.display(),
                self.check,
                self.message
            )
        }
    }
}

/// Crates whose functions may be at most [`FRONT_END_BUDGET`] lines: the application layer and
/// the front ends. Every other crate is a library with [`LIBRARY_BUDGET`].
pub const FRONT_ENDS: &[&str] = &["study", "cli", "python", "xtask", "server"];
/// Longest function allowed in `study` and the front ends, in lines.
pub const FRONT_END_BUDGET: usize = 150;
/// Longest function allowed in the numerical and reader libraries, in lines.
pub const LIBRARY_BUDGET: usize = 250;

/// Runs every check on the workspace at `root`; findings sorted by file and line.
///
/// # Errors
/// A file or folder that cannot be read, or an ARCHITECTURE.md without its layer table.
pub fn run(root: &Path) -> std::io::Result<Vec<Finding>> {
    let crates = workspace_crates(root)?;
    let mut all = Vec::new();
    all.extend(layers(root, &crates)?);
    all.extend(unused_dependencies(root, &crates)?);
    let rust = files_with(root, &["rs"])?;
    all.extend(doc_lines(root, &rust)?);
    all.extend(function_lengths(root, &crates, &rust)?);
    let text = files_with(
        root,
        &["rs", "md", "toml", "py", "pyi", "sh", "ron", "html", "js"],
    )?;
    all.extend(outside_references(root, &text)?);
    all.sort();
    Ok(all)
}

/// A member of the workspace: its short name (`fe`, `cli`, `xtask`), folder and manifest.
#[derive(Debug, Clone)]
pub struct Member {
    /// The folder's name, which is the name ARCHITECTURE.md uses.
    pub short: String,
    /// The folder, relative to the root.
    pub dir: PathBuf,
    /// The `[dependencies]` entries: package name and line in Cargo.toml.
    pub dependencies: Vec<(String, usize)>,
    /// Dependencies the sources never name, with a reason in the manifest.
    pub used_without_path: BTreeSet<String>,
}

/// The workspace members below `crates/`, plus `xtask`, `python` and `tests` where present.
///
/// # Errors
/// A manifest that cannot be read.
pub fn workspace_crates(root: &Path) -> std::io::Result<Vec<Member>> {
    let mut dirs = Vec::new();
    if let Ok(entries) = std::fs::read_dir(root.join("crates")) {
        for e in entries {
            let p = e?.path();
            if p.join("Cargo.toml").is_file() {
                dirs.push(p.strip_prefix(root).unwrap_or(&p).to_path_buf());
            }
        }
    }
    for extra in ["xtask", "python", "tests"] {
        if root.join(extra).join("Cargo.toml").is_file() {
            dirs.push(PathBuf::from(extra));
        }
    }
    dirs.sort();
    dirs.into_iter()
        .map(|dir| {
            let text = std::fs::read_to_string(root.join(&dir).join("Cargo.toml"))?;
            let (dependencies, used_without_path) = parse_manifest(&text);
            let short = dir
                .file_name()
                .map(|n| n.to_string_lossy().into_owned())
                .unwrap_or_default();
            Ok(Member {
                short,
                dir,
                dependencies,
                used_without_path,
            })
        })
        .collect()
}

/// The `[dependencies]` names (with their lines) and the `used-without-path` list of a manifest.
fn parse_manifest(text: &str) -> (Vec<(String, usize)>, BTreeSet<String>) {
    let mut section = String::new();
    let mut deps = Vec::new();
    let mut without = BTreeSet::new();
    let mut in_list = false;
    for (i, raw) in text.lines().enumerate() {
        let line = raw.trim();
        if line.starts_with('[') {
            section = line
                .trim_matches(|c| c == '[' || c == ']')
                .trim()
                .to_string();
            in_list = false;
            continue;
        }
        if line.is_empty() || line.starts_with('#') {
            continue;
        }
        if section == "dependencies" {
            if let Some(name) = line.split(['=', '.', ' ']).next() {
                deps.push((name.trim().trim_matches('"').to_string(), i + 1));
            }
        } else if section == "package.metadata.tidy" {
            if line.starts_with("used-without-path") {
                in_list = true;
            }
            if in_list {
                for part in line.split('"').skip(1).step_by(2) {
                    without.insert(part.to_string());
                }
                if line.contains(']') {
                    in_list = false;
                }
            }
        }
    }
    (deps, without)
}

/// The allowed `indentify-*` dependencies of each crate, from ARCHITECTURE.md's layer table.
///
/// # Errors
/// ARCHITECTURE.md missing or without the table.
pub fn allowed_layers(root: &Path) -> std::io::Result<BTreeMap<String, BTreeSet<String>>> {
    let text = std::fs::read_to_string(root.join("ARCHITECTURE.md"))?;
    let start = text.find("<!-- tidy:layers -->");
    let end = text.find("<!-- /tidy:layers -->");
    let (Some(start), Some(end)) = (start, end) else {
        return Err(std::io::Error::other(
            "ARCHITECTURE.md has no table between <!-- tidy:layers --> and <!-- /tidy:layers -->",
        ));
    };
    let mut table = BTreeMap::new();
    for line in text[start..end].lines() {
        let cells: Vec<&str> = line
            .trim()
            .trim_matches('|')
            .split('|')
            .map(str::trim)
            .collect();
        if cells.len() != 2
            || cells[0].is_empty()
            || cells[0].starts_with("---")
            || cells[0] == "crate"
        {
            continue;
        }
        let name = cells[0].trim_matches('`').to_string();
        let allowed = cells[1]
            .split(',')
            .map(|s| s.trim().trim_matches('`').to_string())
            .filter(|s| !s.is_empty() && s != "-" && s != "nothing")
            .collect();
        table.insert(name, allowed);
    }
    Ok(table)
}

/// Every crate's `indentify-*` dependencies against ARCHITECTURE.md's layer table.
///
/// # Errors
/// ARCHITECTURE.md missing or without the table.
pub fn layers(root: &Path, crates: &[Member]) -> std::io::Result<Vec<Finding>> {
    let table = allowed_layers(root)?;
    let mut out = Vec::new();
    for c in crates {
        let manifest = c.dir.join("Cargo.toml");
        let Some(allowed) = table.get(&c.short) else {
            out.push(Finding {
                file: manifest,
                line: 0,
                check: "layers",
                message: format!(
                    "crate `{}` has no row in ARCHITECTURE.md's layer table",
                    c.short
                ),
            });
            continue;
        };
        for (dep, line) in &c.dependencies {
            let Some(inner) = dep.strip_prefix("indentify-") else {
                continue;
            };
            if !allowed.contains(inner) {
                out.push(Finding {
                    file: manifest.clone(),
                    line: *line,
                    check: "layers",
                    message: format!(
                        "`{}` depends on `{inner}`, which ARCHITECTURE.md does not allow it (allowed: {})",
                        c.short,
                        if allowed.is_empty() { "none".to_string() } else { allowed.iter().cloned().collect::<Vec<_>>().join(", ") }
                    ),
                });
            }
        }
    }
    Ok(out)
}

/// Every `[dependencies]` entry named somewhere in the crate's own sources (`name::` or
/// `use name`, with `-` read as `_`), unless listed in `used-without-path`.
///
/// # Errors
/// A source file that cannot be read.
pub fn unused_dependencies(root: &Path, crates: &[Member]) -> std::io::Result<Vec<Finding>> {
    let mut out = Vec::new();
    for c in crates {
        let mut sources = String::new();
        for f in files_with(&root.join(&c.dir), &["rs"])? {
            sources.push_str(&std::fs::read_to_string(root.join(&c.dir).join(&f))?);
            sources.push('\n');
        }
        for (dep, line) in &c.dependencies {
            if c.used_without_path.contains(dep) {
                continue;
            }
            let ident = dep.replace('-', "_");
            let named = sources.contains(&format!("{ident}::"))
                || sources.contains(&format!("use {ident}"))
                || sources.contains(&format!("extern crate {ident}"));
            if !named {
                out.push(Finding {
                    file: c.dir.join("Cargo.toml"),
                    line: *line,
                    check: "unused-dependency",
                    message: format!(
                        "`{dep}` is never named in {}'s sources: remove it, or list it under [package.metadata.tidy] used-without-path with the reason",
                        c.short
                    ),
                });
            }
        }
    }
    Ok(out)
}

/// Every Rust file's first non-blank line is a `//!` line.
///
/// # Errors
/// A file that cannot be read.
pub fn doc_lines(root: &Path, rust: &[PathBuf]) -> std::io::Result<Vec<Finding>> {
    let mut out = Vec::new();
    for f in rust {
        let text = std::fs::read_to_string(root.join(f))?;
        let first = text.lines().find(|l| !l.trim().is_empty()).unwrap_or("");
        if !first.trim_start().starts_with("//!") {
            out.push(Finding {
                file: f.clone(),
                line: 1,
                check: "doc-line",
                message: "the file does not open with a `//!` line saying what it holds".into(),
            });
        }
    }
    Ok(out)
}

/// No citation of a document outside the repository (the design card, `../shared`) and no
/// tracker number (the word issue followed by a number): the repository's own docs must
/// stand alone.
///
/// # Errors
/// A file that cannot be read.
pub fn outside_references(root: &Path, files: &[PathBuf]) -> std::io::Result<Vec<Finding>> {
    let mut out = Vec::new();
    for f in files {
        let Ok(text) = std::fs::read_to_string(root.join(f)) else {
            continue;
        };
        for (i, line) in text.lines().enumerate() {
            if let Some(why) = outside_reference(line) {
                out.push(Finding {
                    file: f.clone(),
                    line: i + 1,
                    check: "outside-reference",
                    message: why,
                });
            }
        }
    }
    Ok(out)
}

/// What is wrong with one line, if it cites something outside the repository.
pub fn outside_reference(line: &str) -> Option<String> {
    // The names are split so that this file does not cite them itself.
    let design = ["DESIGN", ".md"].concat();
    let shared = ["..", "/shared/"].concat();
    if line.contains(&design) {
        return Some(format!(
            "cites `{design}`, which is not in the repository: cite docs/theory.md"
        ));
    }
    if line.contains(&shared) {
        return Some(format!(
            "cites `{shared}`, outside the repository: keep what is needed in the repository"
        ));
    }
    let lower = line.to_ascii_lowercase();
    for word in ["issue ", "issues ", "issue #"] {
        let mut from = 0;
        while let Some(k) = lower[from..].find(word) {
            let at = from + k;
            let before_ok = at == 0 || !lower.as_bytes()[at - 1].is_ascii_alphanumeric();
            let rest = lower[at + word.len()..].trim_start_matches('#');
            if before_ok && rest.chars().next().is_some_and(|c| c.is_ascii_digit()) {
                return Some(format!(
                    "cites a tracker number (`{}`): say what the thing is instead",
                    line[at..]
                        .chars()
                        .take(word.len() + 3)
                        .collect::<String>()
                        .trim()
                ));
            }
            from = at + word.len();
        }
    }
    None
}

/// Functions longer than the budget of their crate (tests, benches and examples excepted).
///
/// # Errors
/// A file that cannot be read.
pub fn function_lengths(
    root: &Path,
    crates: &[Member],
    rust: &[PathBuf],
) -> std::io::Result<Vec<Finding>> {
    let mut out = Vec::new();
    for f in rust {
        let in_test_dir = f.components().any(|c| {
            matches!(
                c.as_os_str().to_str(),
                Some("tests" | "benches" | "examples" | "fuzz")
            )
        });
        let Some(member) = crates
            .iter()
            .filter(|c| f.starts_with(&c.dir))
            .max_by_key(|c| c.dir.as_os_str().len())
        else {
            continue;
        };
        if in_test_dir || member.short == "tests" {
            continue;
        }
        let budget = if FRONT_ENDS.contains(&member.short.as_str()) {
            FRONT_END_BUDGET
        } else {
            LIBRARY_BUDGET
        };
        let text = std::fs::read_to_string(root.join(f))?;
        for func in functions(&text) {
            if func.lines > budget {
                out.push(Finding {
                    file: f.clone(),
                    line: func.start,
                    check: "function-length",
                    message: format!(
                        "`{}` is {} lines; the budget in `{}` is {budget}: split it",
                        func.name, func.lines, member.short
                    ),
                });
            }
        }
    }
    Ok(out)
}

/// A function found in a source text: name, first line (1-based) and length in lines.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Function {
    /// Its name.
    pub name: String,
    /// The line of its `fn`.
    pub start: usize,
    /// From the `fn` line to the closing brace, both counted.
    pub lines: usize,
}

/// The functions with a body in `text`, outside `#[cfg(test)]` modules. The scan knows
/// comments, string, raw-string and char literals well enough for rustfmt-formatted code.
pub fn functions(text: &str) -> Vec<Function> {
    let bytes = text.as_bytes();
    let code = blank_literals(bytes);
    let lines: Vec<usize> = std::iter::once(0)
        .chain(
            code.iter()
                .enumerate()
                .filter(|(_, b)| **b == b'\n')
                .map(|(i, _)| i + 1),
        )
        .collect();
    let line_of = |pos: usize| lines.partition_point(|&s| s <= pos);
    let code_str = String::from_utf8_lossy(&code).into_owned();
    let mut out = Vec::new();
    let mut i = 0;
    while let Some(k) = code_str[i..].find("fn ") {
        let at = i + k;
        i = at + 3;
        let word_start = at == 0 || !(code[at - 1].is_ascii_alphanumeric() || code[at - 1] == b'_');
        if !word_start {
            continue;
        }
        let name: String = code_str[at + 3..]
            .chars()
            .take_while(|c| c.is_alphanumeric() || *c == '_')
            .collect();
        if name.is_empty() {
            continue;
        }
        // The body opens at the first `{` before any `;` at the signature's own depth.
        let mut depth = 0i32;
        let mut open = None;
        for (j, &b) in code.iter().enumerate().skip(at) {
            match b {
                b'(' | b'[' | b'<' => depth += 1,
                b')' | b']' => depth -= 1,
                b'>' if j > 0 && code[j - 1] != b'-' && code[j - 1] != b'=' => depth -= 1,
                b';' if depth <= 0 => break,
                b'{' if depth <= 0 => {
                    open = Some(j);
                    break;
                }
                _ => {}
            }
        }
        let Some(open) = open else { continue };
        let close = matching_brace(&code, open);
        out.push(Function {
            name,
            start: line_of(at),
            lines: line_of(close) - line_of(at) + 1,
        });
    }
    // Drop the functions inside `#[cfg(test)] mod ... { }` blocks.
    let mut tests = Vec::new();
    let mut from = 0;
    while let Some(k) = code_str[from..].find("#[cfg(test)]") {
        let at = from + k;
        from = at + 1;
        let after = &code_str[at..];
        if let Some(m) = after.find("mod ") {
            if let Some(b) = after[m..].find('{') {
                let open = at + m + b;
                if after[..m + b].contains(';') {
                    continue;
                }
                tests.push((line_of(open), line_of(matching_brace(&code, open))));
            }
        }
    }
    out.retain(|f| !tests.iter().any(|(a, b)| f.start >= *a && f.start <= *b));
    out
}

/// The position of the brace closing the one at `open` (the text's end if unclosed).
fn matching_brace(code: &[u8], open: usize) -> usize {
    let mut depth = 0i64;
    for (j, &b) in code.iter().enumerate().skip(open) {
        match b {
            b'{' => depth += 1,
            b'}' => {
                depth -= 1;
                if depth == 0 {
                    return j;
                }
            }
            _ => {}
        }
    }
    code.len().saturating_sub(1)
}

/// The text with comments and the insides of string and char literals replaced by spaces
/// (newlines kept), so that braces in them are not counted.
fn blank_literals(src: &[u8]) -> Vec<u8> {
    let mut out = src.to_vec();
    let blank = |out: &mut Vec<u8>, a: usize, b: usize| {
        for c in &mut out[a..b.min(src.len())] {
            if *c != b'\n' {
                *c = b' ';
            }
        }
    };
    let mut i = 0;
    while i < src.len() {
        let rest = &src[i..];
        if rest.starts_with(b"//") {
            let end = rest
                .iter()
                .position(|&c| c == b'\n')
                .map_or(src.len(), |p| i + p);
            blank(&mut out, i, end);
            i = end;
        } else if rest.starts_with(b"/*") {
            let mut depth = 0;
            let mut j = i;
            while j < src.len() {
                if src[j..].starts_with(b"/*") {
                    depth += 1;
                    j += 2;
                } else if src[j..].starts_with(b"*/") {
                    depth -= 1;
                    j += 2;
                    if depth == 0 {
                        break;
                    }
                } else {
                    j += 1;
                }
            }
            blank(&mut out, i, j);
            i = j;
        } else if (rest.starts_with(b"r#") || rest.starts_with(b"r\"") || rest.starts_with(b"br"))
            && (i == 0 || !(src[i - 1].is_ascii_alphanumeric() || src[i - 1] == b'_'))
        {
            let skip = usize::from(rest[0] == b'b');
            let hashes = rest[1 + skip..].iter().take_while(|&&c| c == b'#').count();
            if rest.get(1 + skip + hashes) != Some(&b'"') {
                i += 1;
                continue;
            }
            let body = i + 2 + skip + hashes;
            let mut closing = vec![b'"'];
            closing.extend(std::iter::repeat_n(b'#', hashes));
            let end = src[body..]
                .windows(closing.len())
                .position(|w| w == closing.as_slice())
                .map_or(src.len(), |p| body + p);
            blank(&mut out, body, end);
            i = end + closing.len();
        } else if rest[0] == b'"' {
            let mut j = i + 1;
            while j < src.len() && src[j] != b'"' {
                j += if src[j] == b'\\' { 2 } else { 1 };
            }
            blank(&mut out, i + 1, j);
            i = j + 1;
        } else if rest[0] == b'\'' {
            // A char literal ('x', '\n', '\u{..}') or a lifetime ('a): blank only the former.
            let end = if rest.get(1) == Some(&b'\\') {
                rest.iter()
                    .skip(2)
                    .position(|&c| c == b'\'')
                    .map(|p| i + 2 + p)
            } else if rest.get(2) == Some(&b'\'') {
                Some(i + 2)
            } else {
                std::str::from_utf8(&rest[1..rest.len().min(6)])
                    .ok()
                    .and_then(|s| s.chars().next().map(|c| (c, c.len_utf8())))
                    .filter(|(c, n)| !c.is_ascii() && rest.get(1 + n) == Some(&b'\''))
                    .map(|(_, n)| i + 1 + n)
            };
            match end {
                Some(e) => {
                    blank(&mut out, i + 1, e);
                    i = e + 1;
                }
                None => i += 1,
            }
        } else {
            i += 1;
        }
    }
    out
}

/// The files below `root` (relative paths, sorted) whose extension is one of `exts`, outside
/// build output, hidden folders, virtual environments and fetched data.
///
/// # Errors
/// A folder that cannot be read.
pub fn files_with(root: &Path, exts: &[&str]) -> std::io::Result<Vec<PathBuf>> {
    let mut out = Vec::new();
    let mut stack = vec![PathBuf::new()];
    while let Some(rel) = stack.pop() {
        for e in std::fs::read_dir(root.join(&rel))? {
            let e = e?;
            let name = e.file_name().to_string_lossy().into_owned();
            let path = rel.join(&name);
            let ty = e.file_type()?;
            if ty.is_dir() {
                let skip = name.starts_with('.')
                    || matches!(
                        name.as_str(),
                        "target" | "node_modules" | "venv" | "__pycache__" | "snapshots"
                    )
                    || name.starts_with("target-")
                    || path == Path::new("examples/data");
                if !skip {
                    stack.push(path);
                }
            } else if ty.is_file()
                && Path::new(&name)
                    .extension()
                    .and_then(|x| x.to_str())
                    .is_some_and(|x| exts.contains(&x))
            {
                out.push(path);
            }
        }
    }
    out.sort();
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn tree(files: &[(&str, &str)]) -> PathBuf {
        static NEXT: std::sync::atomic::AtomicUsize = std::sync::atomic::AtomicUsize::new(0);
        let n = NEXT.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
        let dir = std::env::temp_dir().join(format!("tidy-test-{}-{n}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        for (p, text) in files {
            let path = dir.join(p);
            std::fs::create_dir_all(path.parent().unwrap()).unwrap();
            std::fs::write(path, text).unwrap();
        }
        dir
    }

    const ARCH: &str = "# A\n<!-- tidy:layers -->\n| crate | may depend on |\n|---|---|\n| `mesh` | - |\n| `fe` | `mesh` |\n<!-- /tidy:layers -->\n";

    #[test]
    fn a_dependency_against_the_drawn_layers_is_found() {
        let root = tree(&[
            ("ARCHITECTURE.md", ARCH),
            (
                "crates/mesh/Cargo.toml",
                "[package]\nname = \"indentify-mesh\"\n[dependencies]\nindentify-fe.workspace = true\n",
            ),
            ("crates/mesh/src/lib.rs", "//! m\nuse indentify_fe::X;\n"),
            (
                "crates/fe/Cargo.toml",
                "[package]\nname = \"indentify-fe\"\n[dependencies]\nindentify-mesh.workspace = true\n",
            ),
            ("crates/fe/src/lib.rs", "//! f\nuse indentify_mesh::Y;\n"),
        ]);
        let crates = workspace_crates(&root).unwrap();
        let found = layers(&root, &crates).unwrap();
        assert_eq!(found.len(), 1, "{found:?}");
        assert!(found[0].file.ends_with("crates/mesh/Cargo.toml") && found[0].line == 4);
        assert!(found[0].message.contains("`mesh` depends on `fe`"));
        assert!(unused_dependencies(&root, &crates).unwrap().is_empty());
        std::fs::remove_dir_all(root).unwrap();
    }

    #[test]
    fn an_unnamed_dependency_is_found_unless_its_reason_is_given() {
        let manifest = "[package]\nname = \"indentify-fe\"\n[dependencies]\nserde.workspace = true\npulp = \"0.22\"\n";
        let root = tree(&[
            ("ARCHITECTURE.md", ARCH),
            ("crates/fe/Cargo.toml", manifest),
            (
                "crates/fe/src/lib.rs",
                "//! f\n#[derive(serde::Serialize)]\nstruct A;\n",
            ),
        ]);
        let crates = workspace_crates(&root).unwrap();
        let found = unused_dependencies(&root, &crates).unwrap();
        assert_eq!(found.len(), 1);
        assert!(found[0].message.contains("`pulp`") && found[0].line == 5);
        std::fs::write(
            root.join("crates/fe/Cargo.toml"),
            format!("{manifest}[package.metadata.tidy]\n# features only\nused-without-path = [\"pulp\"]\n"),
        )
        .unwrap();
        let crates = workspace_crates(&root).unwrap();
        assert!(unused_dependencies(&root, &crates).unwrap().is_empty());
        std::fs::remove_dir_all(root).unwrap();
    }

    #[test]
    fn files_without_a_doc_line_are_found() {
        let root = tree(&[
            ("a.rs", "//! ok\nfn a() {}\n"),
            ("b.rs", "\n// not a doc line\nfn b() {}\n"),
        ]);
        let found = doc_lines(&root, &files_with(&root, &["rs"]).unwrap()).unwrap();
        assert_eq!(
            found.iter().map(|f| f.file.clone()).collect::<Vec<_>>(),
            vec![PathBuf::from("b.rs")]
        );
        std::fs::remove_dir_all(root).unwrap();
    }

    #[test]
    fn outside_documents_and_tracker_numbers_are_found() {
        let design = ["DESIGN", ".md"].concat();
        assert!(outside_reference(&format!("see {design} §3")).is_some());
        assert!(outside_reference(&["see ../", "shared/data/x"].concat()).is_some());
        assert!(outside_reference(&["as iss", "ue 13 asked"].concat()).is_some());
        assert!(outside_reference(&["(Iss", "ue #12)"].concat()).is_some());
        assert!(outside_reference("the tissue 3 layer").is_none());
        assert!(outside_reference("an issue with 3 tests").is_none());
        assert!(outside_reference("docs/theory.md §3").is_none());
    }

    #[test]
    fn function_lengths_count_from_fn_to_its_closing_brace() {
        let body: String = (0..10)
            .map(|i| format!("    let x{i} = \"}}\"; // {{\n"))
            .collect();
        let text = format!(
            "//! t\npub fn long(a: Vec<u8>) -> Result<(), ()> {{\n{body}    Ok(())\n}}\ntrait T {{ fn decl(&self); }}\nfn c() {{ let c = '{{'; let l: &'static str = r#\"{{\"#; }}\n#[cfg(test)]\nmod tests {{\n    fn in_test() {{\n{body}    }}\n}}\n"
        );
        let f = functions(&text);
        assert_eq!(
            f,
            vec![
                Function {
                    name: "long".into(),
                    start: 2,
                    lines: 13
                },
                Function {
                    name: "c".into(),
                    start: 16,
                    lines: 1
                },
            ]
        );
    }

    #[test]
    fn the_repository_itself_is_tidy() {
        // The workspace this crate lives in: the rule the CI applies, run as a test too.
        let root = Path::new(env!("CARGO_MANIFEST_DIR")).parent().unwrap();
        let found = run(root).unwrap();
        let text: Vec<String> = found.iter().map(ToString::to_string).collect();
        assert!(
            found.is_empty(),
            "cargo xtask tidy finds:\n{}",
            text.join("\n")
        );
    }
}
