//! Outputs written whole or not at all: every file goes to a temporary sibling and is
//! renamed onto its name once complete, so an interrupted or refused run never leaves a
//! truncated file and never destroys the previous complete one.

use std::io::Write as _;
use std::path::{Path, PathBuf};

use anyhow::{Context, Result};

/// The temporary sibling of `path`: `.NAME.tmp-PID-N` in the same folder (same filesystem,
/// so the rename is atomic).
fn temporary(path: &Path) -> PathBuf {
    static COUNTER: std::sync::atomic::AtomicU64 = std::sync::atomic::AtomicU64::new(0);
    let n = COUNTER.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
    let name = path
        .file_name()
        .map_or_else(|| "out".into(), |n| n.to_string_lossy().into_owned());
    path.with_file_name(format!(".{name}.tmp-{}-{n}", std::process::id()))
}

/// Writes `bytes` to `path` atomically (temporary sibling, flush to disk, rename).
///
/// # Errors
/// A folder that does not exist or cannot be written; the temporary file is removed.
pub fn write(path: &Path, bytes: impl AsRef<[u8]>) -> Result<()> {
    let tmp = temporary(path);
    let result = (|| -> std::io::Result<()> {
        let mut f = std::fs::File::create(&tmp)?;
        f.write_all(bytes.as_ref())?;
        f.sync_all()?;
        std::fs::rename(&tmp, path)
    })();
    if result.is_err() {
        let _ = std::fs::remove_file(&tmp);
    }
    result.with_context(|| format!("cannot write `{}`", path.display()))
}

/// Checks, before any solve, that files can be created in `dir` (creating it if needed),
/// by writing and removing a probe.
///
/// # Errors
/// A folder that cannot be created or written, named.
pub fn ensure_writable_dir(dir: &Path) -> Result<()> {
    std::fs::create_dir_all(dir)
        .with_context(|| format!("cannot create the directory `{}`", dir.display()))?;
    let probe = temporary(&dir.join("probe"));
    std::fs::write(&probe, b"")
        .with_context(|| format!("cannot write in the directory `{}`", dir.display()))?;
    let _ = std::fs::remove_file(&probe);
    Ok(())
}

/// Checks, before any solve and without creating anything, that the folder `dir` (which
/// does not exist yet) could be created: its nearest existing ancestor is a writable
/// folder.
///
/// # Errors
/// An ancestor that is a file, or a folder that cannot be written, named.
pub fn check_creatable_dir(dir: &Path) -> Result<()> {
    let absolute = std::path::absolute(dir).unwrap_or_else(|_| dir.to_path_buf());
    let Some(existing) = absolute.ancestors().skip(1).find(|a| a.exists()) else {
        anyhow::bail!(
            "cannot create the directory `{}`: no existing parent",
            dir.display()
        );
    };
    anyhow::ensure!(
        existing.is_dir(),
        "cannot create the directory `{}`: `{}` is a file",
        dir.display(),
        existing.display()
    );
    let probe = temporary(&existing.join("probe"));
    std::fs::write(&probe, b"").with_context(|| {
        format!(
            "cannot create the directory `{}`: cannot write in `{}`",
            dir.display(),
            existing.display()
        )
    })?;
    let _ = std::fs::remove_file(&probe);
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_failed_write_keeps_the_previous_file_and_leaves_no_temporary() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("result.json");
        write(&p, "first").unwrap();
        write(&p, "second").unwrap();
        assert_eq!(std::fs::read_to_string(&p).unwrap(), "second");
        // a path whose folder does not exist fails and writes nothing
        assert!(write(&dir.path().join("missing/x.json"), "x").is_err());
        let names: Vec<_> = std::fs::read_dir(dir.path())
            .unwrap()
            .map(|e| e.unwrap().file_name())
            .collect();
        assert_eq!(names, ["result.json"]);
        assert!(check_creatable_dir(&dir.path().join("c/d")).is_ok());
        assert!(!dir.path().join("c").exists(), "checked, not created");
        let e = check_creatable_dir(&p.join("sub")).unwrap_err().to_string();
        assert!(e.contains("is a file"), "{e}");
        assert!(ensure_writable_dir(&dir.path().join("a/b")).is_ok());
    }
}
