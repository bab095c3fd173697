//! The workspace folder: `records/<id>/` (an uploaded file and its `record.json`) and
//! `runs/<id>/` (a run's configuration, status and the files the CLI would write). Every
//! path built from a request goes through the checks here: ids and file names are
//! validated character by character, never joined raw.

use std::path::{Component, Path, PathBuf};

use anyhow::{Context as _, Result};

/// The workspace's folders (the root canonical, so prefixes compare reliably).
#[derive(Clone, Debug)]
pub struct Workspace {
    root: PathBuf,
}

impl Workspace {
    /// Opens (creating if needed) the workspace at `dir` with its `records/` and `runs/`.
    ///
    /// # Errors
    /// A folder that cannot be created or resolved.
    pub fn open(dir: &Path) -> Result<Workspace> {
        for sub in ["records", "runs", "tips"] {
            std::fs::create_dir_all(dir.join(sub)).with_context(|| {
                format!("cannot create the workspace folder `{}`", dir.display())
            })?;
        }
        let root = dir
            .canonicalize()
            .with_context(|| format!("cannot resolve the workspace `{}`", dir.display()))?;
        Ok(Workspace { root })
    }

    /// The workspace's root (canonical).
    pub fn root(&self) -> &Path {
        &self.root
    }

    /// `records/`.
    pub fn records(&self) -> PathBuf {
        self.root.join("records")
    }

    /// `runs/`.
    pub fn runs(&self) -> PathBuf {
        self.root.join("runs")
    }

    /// `tips/` (uploaded calibrated tips).
    pub fn tips(&self) -> PathBuf {
        self.root.join("tips")
    }

    /// Whether `path` (absolute) resolves to a stored tip file `tips/<id>/tip.ron`: checked
    /// lexically and after resolving links, as [`Workspace::is_record_file`].
    pub fn is_tip_file(&self, path: &Path) -> bool {
        let tips = self.tips();
        let lexical = normalize(path);
        let shape = lexical
            .strip_prefix(&tips)
            .ok()
            .map(|r| r.components().count() == 2 && r.ends_with(crate::tips::TIP_FILE));
        if shape != Some(true) {
            return false;
        }
        match lexical.canonicalize() {
            Ok(real) => real.starts_with(&tips) && real.is_file(),
            Err(_) => false,
        }
    }

    /// `records/<id>/` for a valid id, `None` otherwise.
    pub fn record_dir(&self, id: &str) -> Option<PathBuf> {
        valid_id(id).then(|| self.records().join(id))
    }

    /// `runs/<id>/` for a valid id, `None` otherwise.
    pub fn run_dir(&self, id: &str) -> Option<PathBuf> {
        valid_id(id).then(|| self.runs().join(id))
    }

    /// Whether `path` (absolute, existing) resolves to a file inside `records/`: the path is
    /// normalized lexically first (`..` and `.`), then resolved (symbolic links) and both
    /// must stay inside.
    pub fn is_record_file(&self, path: &Path) -> bool {
        let records = self.records();
        let lexical = normalize(path);
        if !lexical.starts_with(&records) {
            return false;
        }
        match lexical.canonicalize() {
            Ok(real) => real.starts_with(&records) && real.is_file(),
            Err(_) => false,
        }
    }
}

/// Whether `id` is a record or run id: 1 to 64 characters from `a-z`, `0-9` and `-`, not
/// starting with `-`.
pub fn valid_id(id: &str) -> bool {
    !id.is_empty()
        && id.len() <= 64
        && !id.starts_with('-')
        && id
            .bytes()
            .all(|b| b.is_ascii_lowercase() || b.is_ascii_digit() || b == b'-')
}

/// A file name safe to create: the last component of `name` (after `/` or `\`), characters
/// outside `A-Z a-z 0-9 . _ -` replaced by `_`, leading dots removed, at most 100
/// characters; `record` when nothing is left.
pub fn sanitize_name(name: &str) -> String {
    let last = name.rsplit(['/', '\\']).next().unwrap_or("");
    let mut s: String = last
        .chars()
        .map(|c| {
            if c.is_ascii_alphanumeric() || matches!(c, '.' | '_' | '-') {
                c
            } else {
                '_'
            }
        })
        .collect();
    while s.starts_with('.') {
        s.remove(0);
    }
    if s.len() > 100 {
        // keep the extension
        let ext = s.rfind('.').map(|i| s[i..].to_string()).unwrap_or_default();
        let ext = if ext.len() > 12 { String::new() } else { ext };
        s = format!("{}{ext}", &s[..100 - ext.len()]);
    }
    if s.is_empty() || s.chars().all(|c| c == '_' || c == '.') {
        "record".to_string()
    } else {
        s
    }
}

/// A relative path from a request (`report.md`, `test-1/fit.svg`), accepted only when every
/// `/`-separated part is a plain name (`A-Z a-z 0-9 . _ -`, not starting with `.`, so no
/// `..`, no hidden or temporary files) and there are at most 4 parts.
pub fn safe_relative(path: &str) -> Option<PathBuf> {
    let parts: Vec<&str> = path.split('/').collect();
    if parts.is_empty() || parts.len() > 4 {
        return None;
    }
    let mut out = PathBuf::new();
    for p in parts {
        let ok = !p.is_empty()
            && p.len() <= 200
            && !p.starts_with('.')
            && p.bytes()
                .all(|b| b.is_ascii_alphanumeric() || matches!(b, b'.' | b'_' | b'-'));
        if !ok {
            return None;
        }
        out.push(p);
    }
    Some(out)
}

/// `path` with `.` dropped and `..` applied lexically (never above the root).
pub fn normalize(path: &Path) -> PathBuf {
    let mut out = PathBuf::new();
    for c in path.components() {
        match c {
            Component::ParentDir => {
                out.pop();
            }
            Component::CurDir => {}
            other => out.push(other.as_os_str()),
        }
    }
    out
}

/// FNV-1a (64 bits) of `bytes` as 16 hex digits: a record's id (its content).
pub fn content_id(bytes: &[u8]) -> String {
    let mut h: u64 = 0xcbf2_9ce4_8422_2325;
    for &b in bytes {
        h ^= u64::from(b);
        h = h.wrapping_mul(0x0100_0000_01b3);
    }
    format!("{h:016x}")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ids_names_and_relative_paths_are_checked() {
        assert!(valid_id("r20261126-162400-1"));
        assert!(valid_id("0123456789abcdef"));
        for bad in ["", "..", "a/b", "A", "-x", "a.b", "a\\b", &"x".repeat(65)] {
            assert!(!valid_id(bad), "{bad}");
        }
        assert_eq!(sanitize_name("../../etc/passwd"), "passwd");
        assert_eq!(sanitize_name("C:\\data\\anon NI.TXT"), "anon_NI.TXT");
        assert_eq!(sanitize_name("..."), "record");
        assert_eq!(sanitize_name(".bashrc"), "bashrc");
        assert_eq!(sanitize_name(""), "record");
        assert!(sanitize_name(&format!("{}.txt", "a".repeat(300))).ends_with(".txt"));
        assert!(sanitize_name(&"a".repeat(300)).len() <= 100);
        assert_eq!(
            safe_relative("test-1/fit.svg"),
            Some(PathBuf::from("test-1/fit.svg"))
        );
        for bad in [
            "../x",
            "a/../../x",
            "/etc/passwd",
            ".x",
            "a//b",
            "",
            "a\\..\\b",
            "%2e%2e/x",
            "a/b/c/d/e",
        ] {
            assert_eq!(safe_relative(bad), None, "{bad}");
        }
        assert_eq!(
            normalize(Path::new("/w/runs/r1/../../records/a/x.txt")),
            PathBuf::from("/w/records/a/x.txt")
        );
        assert_eq!(normalize(Path::new("/../../x")), PathBuf::from("/x"));
        assert_eq!(content_id(b""), "cbf29ce484222325");
        assert_ne!(content_id(b"a"), content_id(b"b"));
    }

    #[test]
    fn only_files_inside_records_are_record_files() {
        let dir = tempfile::tempdir().unwrap();
        let ws = Workspace::open(dir.path()).unwrap();
        std::fs::create_dir_all(ws.records().join("abc")).unwrap();
        std::fs::write(ws.records().join("abc/x.txt"), "x").unwrap();
        std::fs::write(ws.root().join("secret.txt"), "s").unwrap();
        assert!(ws.is_record_file(&ws.runs().join("r1/../../records/abc/x.txt")));
        assert!(!ws.is_record_file(&ws.runs().join("r1/../../secret.txt")));
        assert!(!ws.is_record_file(&ws.records().join("abc/../../secret.txt")));
        assert!(!ws.is_record_file(&ws.records().join("abc")));
        // tips: only tips/<id>/tip.ron
        std::fs::create_dir_all(ws.tips().join("t1")).unwrap();
        std::fs::write(
            ws.tips().join("t1/tip.ron"),
            "(area: Iso(coefficients: [24.5]))",
        )
        .unwrap();
        std::fs::write(ws.tips().join("t1/other.ron"), "x").unwrap();
        assert!(ws.is_tip_file(&ws.runs().join("r1/../../tips/t1/tip.ron")));
        assert!(!ws.is_tip_file(&ws.tips().join("t1/other.ron")));
        assert!(!ws.is_tip_file(&ws.tips().join("t1/../../records/abc/x.txt")));
        assert!(!ws.is_tip_file(&ws.records().join("abc/x.txt")));
        assert!(!ws.is_tip_file(&ws.tips().join("t2/tip.ron")));
        assert!(!ws.is_record_file(Path::new("/etc/passwd")));
    }
}
