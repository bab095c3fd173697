//! One run per report folder, at every instant: an identification marks its folder with
//! `RUN-IN-PROGRESS.txt` before writing anything and removes the mark last, once every file
//! of the run is written; a run replacing an earlier one (`--force`) first moves the
//! earlier run's files into `.replaced/` (removed when the new run ends). A folder without
//! the mark holds one whole run; a folder with it holds the partial output of the run it
//! names (killed, or failed), and `.replaced/` then holds the earlier run whole
//! (docs/cli.md, "Report folders").

use std::path::{Path, PathBuf};

use anyhow::{Context, Result};

/// The mark of a folder whose run has not finished.
pub const MARKER: &str = "RUN-IN-PROGRESS.txt";

/// The folder (inside the report folder) holding the run a `--force` run replaces, until
/// the new run ends.
pub const REPLACED: &str = ".replaced";

/// Whether `name` (a file or folder directly in a report folder) belongs to an
/// identification run: its history, result, fit, report, figures (the curves, the
/// convergence, the profiles) and a joint fit's `test-K/` pages. Anything else in the
/// folder (the user's own files) is never moved or removed.
pub fn is_run_file(name: &str) -> bool {
    const FILES: [&str; 5] = [
        "history.csv",
        "result.json",
        "fit.csv",
        "report.md",
        "report.json",
    ];
    const STEMS: [&str; 3] = ["force_depth", "force_time", "convergence"];
    if FILES.contains(&name) {
        return true;
    }
    if let Some(n) = name.strip_prefix("test-") {
        return !n.is_empty() && n.bytes().all(|b| b.is_ascii_digit());
    }
    let Some((stem, ext)) = name.rsplit_once('.') else {
        return false;
    };
    (ext == "svg" || ext == "png")
        && (STEMS.contains(&stem) || stem.strip_prefix("profile_").is_some_and(|s| !s.is_empty()))
}

/// Creates `dir` if needed, marks it as holding a run in progress (written atomically)
/// and, when `replacing` an earlier run, moves that run's files into `dir/.replaced/`
/// (emptied first: a `.replaced/` left by a killed run held the run before the one
/// replaced now). Called once every input is known good, before the history is created.
///
/// # Errors
/// The mark cannot be written or a file cannot be moved.
pub fn begin(dir: &Path, replacing: bool, what: &str) -> Result<()> {
    crate::atomic::ensure_writable_dir(dir)?;
    let text = format!(
        "A run has been writing to this folder since {} (process {}): {what}.\n\
         It has not finished (it is running, or it was killed or failed). The files here are \
         its partial output, not one complete run{}.\n\
         This file is removed when the run ends; `--resume` continues the run, `--force` \
         replaces it.\n",
        timestamp(),
        std::process::id(),
        if replacing {
            "; the run it replaces is in `.replaced/`, whole, until it ends"
        } else {
            ""
        }
    );
    crate::atomic::write(&dir.join(MARKER), text)?;
    if replacing {
        let aside = dir.join(REPLACED);
        remove_any(&aside)?;
        std::fs::create_dir(&aside)
            .with_context(|| format!("cannot create `{}`", aside.display()))?;
        for name in run_files(dir)? {
            let (from, to) = (dir.join(&name), aside.join(&name));
            std::fs::rename(&from, &to).with_context(|| {
                format!(
                    "cannot move the earlier run's `{}` into `{}`",
                    from.display(),
                    aside.display()
                )
            })?;
        }
    }
    Ok(())
}

/// Ends the run in `dir`: removes `.replaced/`, then the mark (last).
///
/// # Errors
/// Either cannot be removed.
pub fn finish(dir: &Path) -> Result<()> {
    remove_any(&dir.join(REPLACED))?;
    let marker = dir.join(MARKER);
    match std::fs::remove_file(&marker) {
        Ok(()) => Ok(()),
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => Ok(()),
        Err(e) => Err(e).with_context(|| format!("cannot remove `{}`", marker.display())),
    }
}

/// The run files directly in `dir`, sorted.
fn run_files(dir: &Path) -> Result<Vec<String>> {
    let mut names = Vec::new();
    for entry in
        std::fs::read_dir(dir).with_context(|| format!("cannot list `{}`", dir.display()))?
    {
        let name = entry?.file_name().to_string_lossy().into_owned();
        if is_run_file(&name) {
            names.push(name);
        }
    }
    names.sort();
    Ok(names)
}

/// Removes a file or a folder (recursively) if it exists.
fn remove_any(path: &PathBuf) -> Result<()> {
    let result = match std::fs::symlink_metadata(path) {
        Err(_) => return Ok(()),
        Ok(m) if m.is_dir() => std::fs::remove_dir_all(path),
        Ok(_) => std::fs::remove_file(path),
    };
    result.with_context(|| format!("cannot remove `{}`", path.display()))
}

/// Now, as UTC date and time.
fn timestamp() -> String {
    utc(std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map_or(0, |d| d.as_secs()))
}

/// Seconds since the Unix epoch as UTC date and time (`2026-11-26 19:24:01 UTC`).
fn utc(secs: u64) -> String {
    let (days, rem) = (secs / 86_400, secs % 86_400);
    // civil date from days since 1970-01-01 (Howard Hinnant's algorithm)
    let z = days as i64 + 719_468;
    let era = z.div_euclid(146_097);
    let doe = z - era * 146_097;
    let yoe = (doe - doe / 1460 + doe / 36_524 - doe / 146_096) / 365;
    let doy = doe - (365 * yoe + yoe / 4 - yoe / 100);
    let mp = (5 * doy + 2) / 153;
    let d = doy - (153 * mp + 2) / 5 + 1;
    let m = if mp < 10 { mp + 3 } else { mp - 9 };
    let y = yoe + era * 400 + i64::from(m <= 2);
    format!(
        "{y:04}-{m:02}-{d:02} {:02}:{:02}:{:02} UTC",
        rem / 3600,
        rem % 3600 / 60,
        rem % 60
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn only_run_files_are_moved_aside_and_the_mark_goes_last() {
        let dir = tempfile::tempdir().unwrap();
        let d = dir.path();
        for f in [
            "history.csv",
            "result.json",
            "force_depth.svg",
            "profile_E.png",
        ] {
            std::fs::write(d.join(f), "earlier").unwrap();
        }
        std::fs::create_dir(d.join("test-1")).unwrap();
        std::fs::write(d.join("test-1/report.md"), "earlier").unwrap();
        // the user's own files stay
        for f in ["config.ron", "data.csv", "notes.svg", "test-x"] {
            std::fs::write(d.join(f), "mine").unwrap();
        }
        begin(d, true, "identify").unwrap();
        assert!(d.join(MARKER).is_file());
        for f in [
            "history.csv",
            "result.json",
            "force_depth.svg",
            "profile_E.png",
        ] {
            assert!(!d.join(f).exists(), "{f}");
            assert_eq!(
                std::fs::read_to_string(d.join(REPLACED).join(f)).unwrap(),
                "earlier"
            );
        }
        assert!(d.join(REPLACED).join("test-1/report.md").is_file());
        for f in ["config.ron", "data.csv", "notes.svg", "test-x"] {
            assert_eq!(std::fs::read_to_string(d.join(f)).unwrap(), "mine", "{f}");
        }
        finish(d).unwrap();
        assert!(!d.join(MARKER).exists());
        assert!(!d.join(REPLACED).exists());
        assert!(d.join("config.ron").is_file());
        assert_eq!(utc(0), "1970-01-01 00:00:00 UTC");
        assert_eq!(utc(1_795_000_000), "2026-11-18 11:06:40 UTC");
        assert_eq!(utc(951_825_600), "2000-02-29 12:00:00 UTC");
    }
}
