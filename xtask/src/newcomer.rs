//! `cargo xtask newcomer-walk`: every command of README.md and docs/tutorial*.md, in order,
//! in a fresh clone of the repository's committed HEAD, as a newcomer would type them;
//! each command's exit status and wall time are reported.
//!
//! Commands are the lines of fenced blocks tagged `sh`, `bash`, `shell` or `console` (in a
//! `console` block only the `$ ` lines), and the lines starting with `indentify ` or
//! `cargo ` in untagged blocks (the tutorials show a command above its output); blocks
//! tagged otherwise (`text`, `ron`, `python`) are not run, which is how a document shows
//! commands too long for the walk (hours of fits) without running them. Comment
//! lines are dropped, a trailing ` # comment` is cut (` # exit N` there states the exit
//! status the document promises, 0 otherwise: a fit that ends with undetermined parameters
//! exits 3 on purpose), `\` continues a line. `indentify` is
//! what the README says it is: `cargo run --release -p indentify-cli --`. Python blocks
//! are not run (the Python package's tests run them: python/tests/test_readme.py).

use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::Instant;

use anyhow::{Context, Result, bail};

/// One command found in a document.
#[derive(Clone, Debug, PartialEq)]
pub struct Step {
    /// `README.md:54`.
    pub at: String,
    /// The command as written.
    pub command: String,
    /// The exit status the document states (a trailing ` # exit N`), 0 otherwise.
    pub expect: i32,
}

/// The commands of one Markdown document, in order.
pub fn extract(doc: &str, text: &str) -> Vec<Step> {
    let mut steps = Vec::new();
    let mut fence: Option<String> = None;
    let mut pending: Option<(usize, String)> = None;
    for (k, raw) in text.lines().enumerate() {
        let line = raw.trim_end();
        if let Some(tag) = line.trim_start().strip_prefix("```") {
            fence = match fence {
                None => Some(tag.trim().to_string()),
                Some(_) => None,
            };
            pending = None;
            continue;
        }
        let Some(tag) = &fence else { continue };
        let shell = matches!(tag.as_str(), "sh" | "bash" | "shell");
        let console = tag == "console";
        let mut body = line.trim_start().to_string();
        if pending.is_none() {
            if console {
                match body.strip_prefix("$ ") {
                    Some(c) => body = c.to_string(),
                    None => continue,
                }
            } else if !shell
                && !(tag.is_empty()
                    && (body.starts_with("indentify ") || body.starts_with("cargo ")))
            {
                continue;
            }
            if body.is_empty() || body.starts_with('#') {
                continue;
            }
        }
        let (body, expect) = (strip_comment(&body), expected_status(&body));
        let (start, mut command) = pending.take().unwrap_or((k + 1, String::new()));
        match body.strip_suffix('\\') {
            Some(head) => {
                command.push_str(head.trim_end());
                command.push(' ');
                pending = Some((start, command));
            }
            None => {
                command.push_str(body.trim());
                steps.push(Step {
                    at: format!("{doc}:{start}"),
                    command,
                    expect,
                });
            }
        }
    }
    steps
}

/// `line` without a trailing ` # comment` outside quotes.
fn strip_comment(line: &str) -> String {
    let (mut single, mut double) = (false, false);
    let bytes: Vec<char> = line.chars().collect();
    for (i, &c) in bytes.iter().enumerate() {
        match c {
            '\'' if !double => single = !single,
            '"' if !single => double = !double,
            '#' if !single && !double && i > 0 && bytes[i - 1].is_whitespace() => {
                return bytes[..i].iter().collect::<String>().trim_end().to_string();
            }
            _ => {}
        }
    }
    line.trim_end().to_string()
}

/// The exit status a trailing ` # exit N ...` comment states, 0 without one.
fn expected_status(line: &str) -> i32 {
    let comment = &line[strip_comment(line).len()..];
    comment
        .trim_start()
        .trim_start_matches('#')
        .trim_start()
        .strip_prefix("exit ")
        .and_then(|rest| {
            let digits: String = rest.chars().take_while(char::is_ascii_digit).collect();
            digits.parse().ok()
        })
        .unwrap_or(0)
}

/// The command as run: `indentify` replaced by the README's `cargo run --release -p
/// indentify-cli --`.
pub fn expand(command: &str) -> String {
    match command.strip_prefix("indentify ") {
        Some(rest) => format!("cargo run -q --release -p indentify-cli -- {rest}"),
        None => command.to_string(),
    }
}

/// The documents walked, in order: README.md, then docs/tutorial*.md by name.
fn documents(root: &Path) -> Result<Vec<PathBuf>> {
    let mut tutorials: Vec<PathBuf> = std::fs::read_dir(root.join("docs"))
        .context("listing docs/")?
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| {
            p.file_name()
                .and_then(|n| n.to_str())
                .is_some_and(|n| n.starts_with("tutorial") && n.ends_with(".md"))
        })
        .collect();
    tutorials.sort();
    let mut docs = vec![root.join("README.md")];
    docs.extend(tutorials);
    Ok(docs)
}

/// `git ARGS` in `dir`, its trimmed standard output (empty on failure).
fn git_out(dir: &Path, args: &[&str]) -> String {
    Command::new("git")
        .arg("-C")
        .arg(dir)
        .args(args)
        .output()
        .map(|o| String::from_utf8_lossy(&o.stdout).trim().to_string())
        .unwrap_or_default()
}

/// `cargo xtask newcomer-walk [--skip SUBSTRING,...] [--keep] [--timeout SECONDS]
/// [--list]`: clones HEAD into a temporary folder and runs every command there.
pub fn run(args: &[String]) -> Result<()> {
    let mut skip: Vec<String> = Vec::new();
    let (mut keep, mut list, mut timeout) = (false, false, 3600u64);
    let mut it = args.iter();
    while let Some(a) = it.next() {
        let mut val = || it.next().cloned().unwrap_or_default();
        match a.as_str() {
            "--skip" => skip.extend(val().split(',').map(str::to_string)),
            "--keep" => keep = true,
            "--list" => list = true,
            "--timeout" => timeout = val().parse()?,
            other => bail!("unknown option {other}"),
        }
    }
    let root = Path::new(env!("CARGO_MANIFEST_DIR"))
        .parent()
        .context("workspace root")?;
    let clone = std::env::temp_dir().join(format!("indentify-newcomer-{}", std::process::id()));
    let status = Command::new("git")
        .args(["clone", "--quiet", "--no-hardlinks"])
        .arg(root)
        .arg(&clone)
        .status()
        .context("running git clone")?;
    if !status.success() {
        bail!("git clone of {} failed", root.display());
    }
    let mut steps = Vec::new();
    for doc in documents(&clone)? {
        let name = doc
            .strip_prefix(&clone)
            .unwrap_or(&doc)
            .display()
            .to_string();
        let text = std::fs::read_to_string(&doc).with_context(|| format!("reading {name}"))?;
        steps.extend(extract(&name, &text));
    }
    println!(
        "newcomer walk: {} commands in a fresh clone of HEAD at {}",
        steps.len(),
        clone.display()
    );
    let log_dir = clone.join("target").join("newcomer-walk");
    std::fs::create_dir_all(&log_dir)?;
    let commit = git_out(&clone, &["rev-parse", "--short", "HEAD"]);
    let date = Command::new("date")
        .args(["-u", "+%Y-%m-%d %H:%M UTC"])
        .output()
        .map(|o| String::from_utf8_lossy(&o.stdout).trim().to_string())
        .unwrap_or_default();
    let mut table = vec![
        format!("Newcomer walk of commit {commit}, {date}:"),
        String::new(),
        "| # | where | command | exit | wall (s) |".to_string(),
        "|--:|---|---|--:|--:|".to_string(),
    ];
    let mut failed = 0;
    let wall = Instant::now();
    for (k, s) in steps.iter().enumerate() {
        if list
            || skip
                .iter()
                .any(|p| !p.is_empty() && s.command.contains(p.as_str()))
        {
            println!("{:>3}  skipped          {}  {}", k + 1, s.at, s.command);
            table.push(format!(
                "| {} | {} | `{}` | skipped | |",
                k + 1,
                s.at,
                s.command
            ));
            continue;
        }
        let log = log_dir.join(format!("{:02}.log", k + 1));
        let file = std::fs::File::create(&log)?;
        let t0 = Instant::now();
        let status = Command::new("timeout")
            .arg(timeout.to_string())
            .args(["bash", "-c", &expand(&s.command)])
            .current_dir(&clone)
            // a newcomer's clone builds into its own target/
            .env_remove("CARGO_TARGET_DIR")
            .stdout(file.try_clone()?)
            .stderr(file)
            .status()
            .context("running bash")?;
        let code = status
            .code()
            .map_or("signal".to_string(), |c| c.to_string());
        if status.code() != Some(s.expect) {
            failed += 1;
        }
        let code = if s.expect != 0 {
            format!("{code} (expected {})", s.expect)
        } else {
            code
        };
        let secs = t0.elapsed().as_secs_f64();
        println!(
            "{:>3}  exit {:>6}  {:>7.1} s  {}  {}",
            k + 1,
            code,
            secs,
            s.at,
            s.command
        );
        table.push(format!(
            "| {} | {} | `{}` | {code} | {secs:.1} |",
            k + 1,
            s.at,
            s.command
        ));
    }
    println!("\n{}\n", table.join("\n"));
    println!(
        "{} commands, {failed} failed, {:.0} s; logs in {}",
        steps.len(),
        wall.elapsed().as_secs_f64(),
        log_dir.display()
    );
    if !keep {
        let _ = std::fs::remove_dir_all(&clone);
        println!("(clone removed; --keep keeps it)");
    }
    if failed > 0 {
        bail!("{failed} of {} commands failed", steps.len());
    }
    Ok(())
}

/// `cargo xtask doc-numbers [--cheap]`: the numbers the documents quote from the tool
/// (`crates/cli/tests/doc_numbers.rs`), the long runs (the anon-nh fit) included, checked
/// against a release build's output; `--cheap` runs only what CI runs.
pub fn doc_numbers(args: &[String]) -> Result<()> {
    let mut include_ignored = true;
    for a in args {
        match a.as_str() {
            "--cheap" => include_ignored = false,
            other => bail!("unknown option {other}"),
        }
    }
    let root = Path::new(env!("CARGO_MANIFEST_DIR"))
        .parent()
        .context("workspace root")?;
    let mut cmd = Command::new(std::env::var("CARGO").unwrap_or_else(|_| "cargo".into()));
    cmd.current_dir(root).args([
        "test",
        "--release",
        "-p",
        "indentify-cli",
        "--test",
        "doc_numbers",
        "--",
        "--nocapture",
    ]);
    if include_ignored {
        cmd.arg("--include-ignored");
    }
    let status = cmd.status().context("running cargo test")?;
    if !status.success() {
        bail!("a quoted number differs from the tool's output (above)");
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn commands_are_found_in_shell_and_console_blocks_and_tutorial_lines() {
        let md = "text\n```sh\n# a comment\ncargo run -- identify \\\n  --out x   # why\n\nscripts/test.sh\n```\n\
                  ```console\n$ indentify check a.ron\noutput line\n```\n```\nindentify identify b.ron\nnot a command\n```\n\
                  ```python\nimport indentify\n```\n```text\nindentify identify long.ron   # hours\n```\n";
        let steps = extract("R.md", md);
        let cmds: Vec<&str> = steps.iter().map(|s| s.command.as_str()).collect();
        assert_eq!(
            cmds,
            [
                "cargo run -- identify --out x",
                "scripts/test.sh",
                "indentify check a.ron",
                "indentify identify b.ron"
            ]
        );
        assert_eq!(steps[0].at, "R.md:4");
        assert_eq!(strip_comment("echo 'a # b' # c"), "echo 'a # b'");
        assert_eq!(steps.iter().map(|s| s.expect).sum::<i32>(), 0);
        let undetermined = extract(
            "T.md",
            "```\nindentify identify a.ron   # exit 3 (sY undetermined)\n```\n",
        );
        assert_eq!(undetermined[0].command, "indentify identify a.ron");
        assert_eq!(undetermined[0].expect, 3);
        assert_eq!(expected_status("echo '# exit 3'"), 0);
        assert_eq!(
            expand("indentify design x.ron"),
            "cargo run -q --release -p indentify-cli -- design x.ron"
        );
    }
}
