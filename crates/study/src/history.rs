//! The iteration history of an identification as CSV (`history.csv`): one line per accepted
//! iterate, written and flushed as soon as the optimizer reports it (an interrupted run
//! loses nothing), and read back to resume a run from its last line.
//!
//! Columns: `iteration`, the law's parameters in its order (physical units, fixed ones
//! included), `J` (N^2), `grad_norm` (norm of the projected gradient in scaled variables,
//! N^2), cumulative `forward_solves`, `adjoint_solves`, `sensitivity_solves`, and `seconds`
//! since the start of the run. Numbers are written in their shortest exact form, so that a
//! resumed run restarts from the very same parameters.

use std::fs::{File, OpenOptions};
use std::io::{BufRead, BufReader, Write};
use std::path::{Path, PathBuf};

use anyhow::{Context, Result, anyhow, bail};
use indentify_identify::IterationRecord;

/// `fields` as one CSV line (no newline), quoted where needed, by the `csv` crate.
fn csv_line<I: IntoIterator<Item = String>>(fields: I) -> String {
    let mut w = csv::WriterBuilder::new()
        .terminator(csv::Terminator::Any(b'\n'))
        .from_writer(Vec::new());
    let fields: Vec<String> = fields.into_iter().collect();
    w.write_record(&fields).expect("writing to memory");
    let bytes = w.into_inner().expect("writing to memory");
    String::from_utf8(bytes)
        .expect("the fields are text")
        .trim_end_matches('\n')
        .to_string()
}

/// The header line for a law with parameters `names`.
pub fn header(names: &[&str]) -> String {
    let mut cols = vec!["iteration".to_string()];
    cols.extend(names.iter().map(|n| n.to_string()));
    cols.extend(
        [
            "J",
            "grad_norm",
            "forward_solves",
            "adjoint_solves",
            "sensitivity_solves",
            "seconds",
        ]
        .map(String::from),
    );
    csv_line(cols)
}

/// One record as a CSV line (no newline).
pub fn line(r: &IterationRecord) -> String {
    let mut cols = vec![r.iteration.to_string()];
    cols.extend(r.params.iter().map(|v| v.to_string()));
    cols.push(r.cost.to_string());
    cols.push(r.grad_norm.to_string());
    cols.push(r.forward_solves.to_string());
    cols.push(r.adjoint_solves.to_string());
    cols.push(r.sensitivity_solves.to_string());
    cols.push(r.seconds.to_string());
    csv_line(cols)
}

/// Every complete line of the history file `path` for `n_params` parameters (an
/// unreadable file or a cut line gives fewer records, never an error: the history is a
/// report here, not a resume point).
pub fn read_all(path: &Path, n_params: usize) -> Vec<IterationRecord> {
    std::fs::read_to_string(path)
        .map(|text| {
            text.lines()
                .skip(1)
                .filter_map(|l| parse_line(l, n_params))
                .collect()
        })
        .unwrap_or_default()
}

/// Parses a line written by [`line`] for `n_params` parameters (`None` for anything
/// else, e.g. a line cut short by an interruption).
fn parse_line(text: &str, n_params: usize) -> Option<IterationRecord> {
    let record = csv::ReaderBuilder::new()
        .has_headers(false)
        .flexible(true)
        .trim(csv::Trim::All)
        .from_reader(text.as_bytes())
        .records()
        .next()?
        .ok()?;
    let f: Vec<&str> = record.iter().collect();
    if f.len() != n_params + 7 {
        return None;
    }
    let num = |s: &str| s.parse::<f64>().ok();
    let int = |s: &str| s.parse::<usize>().ok();
    let params = f[1..=n_params]
        .iter()
        .map(|s| num(s))
        .collect::<Option<Vec<f64>>>()?;
    let k = n_params + 1;
    Some(IterationRecord {
        iteration: int(f[0])?,
        params,
        cost: num(f[k])?,
        grad_norm: num(f[k + 1])?,
        forward_solves: int(f[k + 2])?,
        adjoint_solves: int(f[k + 3])?,
        sensitivity_solves: int(f[k + 4])?,
        seconds: num(f[k + 5])?,
    })
}

/// The history file being written.
#[derive(Debug)]
pub struct HistoryWriter {
    path: PathBuf,
    file: File,
    /// Records at or before this iteration are already in the file (resume).
    skip_through: Option<usize>,
    /// Lines in the file, header excluded.
    pub lines: usize,
}

impl HistoryWriter {
    /// Creates (truncates) `path` and writes the header.
    ///
    /// # Errors
    /// The file cannot be created or written.
    pub fn create(path: &Path, names: &[&str]) -> Result<HistoryWriter> {
        let mut file = File::create(path)
            .with_context(|| format!("cannot create the history file `{}`", path.display()))?;
        writeln!(file, "{}", header(names))
            .with_context(|| format!("cannot write `{}`", path.display()))?;
        Ok(HistoryWriter {
            path: path.to_path_buf(),
            file,
            skip_through: None,
            lines: 0,
        })
    }

    /// Opens an existing history for a resumed run: checks the header, drops a trailing
    /// line cut short by an interruption, and returns the writer (appending) with the last
    /// complete record.
    ///
    /// # Errors
    /// A missing or unreadable file, a header for other parameters, a malformed line before
    /// the last, or no iteration to resume from.
    pub fn resume(path: &Path, names: &[&str]) -> Result<(HistoryWriter, IterationRecord)> {
        let name = path.display().to_string();
        let file = File::open(path).with_context(|| {
            format!("cannot resume: cannot read the history `{name}` (run without --resume first)")
        })?;
        let lines: Vec<String> = BufReader::new(file)
            .lines()
            .collect::<std::io::Result<_>>()
            .with_context(|| format!("cannot read the history `{name}`"))?;
        let expected = header(names);
        match lines.first() {
            Some(h) if h.trim() == expected => {}
            Some(h) => bail!(
                "cannot resume from `{name}`: its header `{h}` is not the one of this law \
                 (`{expected}`); use another --out or run without --resume"
            ),
            None => bail!("cannot resume: `{name}` is empty (run without --resume)"),
        }
        let body: Vec<&String> = lines[1..].iter().filter(|l| !l.trim().is_empty()).collect();
        let mut records = Vec::new();
        for (i, l) in body.iter().enumerate() {
            match parse_line(l, names.len()) {
                Some(r) => records.push(r),
                // a line cut short by an interruption
                None if i + 1 == body.len() => {}
                None => bail!(
                    "cannot resume from `{name}`: line {} `{l}` is not a history line \
                     ({expected})",
                    i + 2
                ),
            }
        }
        let last = records.last().cloned().ok_or_else(|| {
            anyhow!("cannot resume: `{name}` holds no iteration yet (run without --resume)")
        })?;
        // rewrite header + complete records, then append
        let mut text = expected.clone();
        text.push('\n');
        for r in &records {
            text.push_str(&line(r));
            text.push('\n');
        }
        crate::atomic::write(path, text).with_context(|| format!("cannot rewrite `{name}`"))?;
        let file = OpenOptions::new()
            .append(true)
            .open(path)
            .with_context(|| format!("cannot append to `{name}`"))?;
        Ok((
            HistoryWriter {
                path: path.to_path_buf(),
                file,
                skip_through: Some(last.iteration),
                lines: records.len(),
            },
            last,
        ))
    }

    /// Appends `r` and flushes it to the operating system; returns whether it was written
    /// (a resumed run first reports the iterate it resumes from, which is already there).
    ///
    /// # Errors
    /// The file cannot be written.
    pub fn record(&mut self, r: &IterationRecord) -> Result<bool> {
        if self.skip_through.is_some_and(|k| r.iteration <= k) {
            return Ok(false);
        }
        writeln!(self.file, "{}", line(r))
            .and_then(|()| self.file.flush())
            .with_context(|| format!("cannot write the history `{}`", self.path.display()))?;
        self.lines += 1;
        Ok(true)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn rec(i: usize) -> IterationRecord {
        IterationRecord {
            iteration: i,
            params: vec![4000.0 + i as f64 * 0.1, 0.3, 1.0 / 3.0],
            cost: 1.5e6 / (i + 1) as f64,
            grad_norm: 2.0e-3,
            forward_solves: i + 1,
            adjoint_solves: i + 1,
            sensitivity_solves: 0,
            seconds: 0.25 * i as f64,
        }
    }

    #[test]
    fn lines_round_trip_exactly_and_resume_drops_a_cut_line() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("history.csv");
        let names = ["E", "nu", "eta"];
        let mut w = HistoryWriter::create(&path, &names).unwrap();
        for i in 0..3 {
            assert!(w.record(&rec(i)).unwrap());
        }
        drop(w);
        // an interrupted write
        let mut f = OpenOptions::new().append(true).open(&path).unwrap();
        write!(f, "3,4000.3,0.3").unwrap();
        drop(f);
        let (mut w, last) = HistoryWriter::resume(&path, &names).unwrap();
        assert_eq!(last, rec(2));
        assert!(
            !w.record(&rec(2)).unwrap(),
            "the resume point is not repeated"
        );
        assert!(w.record(&rec(3)).unwrap());
        let text = std::fs::read_to_string(&path).unwrap();
        assert_eq!(text.lines().count(), 5, "{text}");
        assert!(text.starts_with("iteration,E,nu,eta,J,grad_norm,"));
        let e = HistoryWriter::resume(&path, &["E", "nu"])
            .unwrap_err()
            .to_string();
        assert!(e.contains("header"), "{e}");
    }
}
