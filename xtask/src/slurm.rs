//! `cargo xtask slurm-check [--keep] [--array N] [--timeout S] [--indentify PATH]`: proves
//! `indentify batch slurm` on a real, single-node Slurm started on this machine: installs
//! Debian's `slurm-wlm` when `slurmctld` is missing, starts munged, slurmctld and slurmd
//! on loopback from a throw-away configuration in a temporary folder, runs a synthetic map
//! once locally and once as a job array, merges the shards and checks that both
//! `results.csv` agree bit for bit but for the `seconds` column (wall time). The daemons it
//! started are always stopped by their PIDs, and the temporary folder is removed unless
//! `--keep` is given.

use std::fs;
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant, SystemTime, UNIX_EPOCH};

use anyhow::{Context, Result, anyhow, bail};
use indentify_study::synthetic::{MapOptions, make_map};

/// Where Debian puts the daemons (root's PATH may lack the sbin folders).
const SEARCH: [&str; 5] = [
    "/usr/sbin",
    "/usr/bin",
    "/usr/local/sbin",
    "/usr/local/bin",
    "/sbin",
];

struct Options {
    keep: bool,
    array: usize,
    timeout: Duration,
    indentify: Option<PathBuf>,
}

pub fn run(args: &[String]) -> Result<()> {
    let o = parse_options(args)?;
    if o.array == 0 {
        bail!("--array must be at least 1");
    }
    let clock = Instant::now();
    if effective_uid() != Some(0) {
        bail!(
            "slurm-check runs as root: it installs packages and starts slurmd, which runs jobs \
             as their owner (sudo cargo xtask slurm-check)"
        );
    }
    let tools = ensure_installed()?;
    let version = output(Command::new(&tools.slurmctld).arg("-V"))
        .unwrap_or_else(|e| format!("unknown ({e})"));
    println!("slurm-check: {}", version.trim());

    let indentify = match &o.indentify {
        Some(p) => std::path::absolute(p)?,
        None => build_indentify()?,
    };
    if !indentify.is_file() {
        bail!("no indentify executable at {}", indentify.display());
    }
    println!("slurm-check: indentify = {}", indentify.display());

    // dropped last: after the daemons are stopped
    let tmp = TempDir::new(o.keep)?;
    let dir = tmp.path.clone();
    println!("slurm-check: working in {}", dir.display());

    let host = short_hostname()?;
    let (cpus, memory, topology) = node_size(&tools.slurmd);
    let conf = write_config(&dir, &host, cpus, memory, &topology)?;
    println!(
        "slurm-check: wrote {} (node {host}: {cpus} CPUs, {memory} MB)",
        conf.display()
    );

    let mut daemons = Daemons {
        children: Vec::new(),
        conf: conf.clone(),
    };
    start_daemons(&tools, &dir, &conf, &host, &mut daemons)?;
    let slurm = Slurm {
        conf: conf.clone(),
        tools: &tools,
    };
    wait_for_node(&slurm, &host, &dir, &mut daemons)?;

    // the map
    let map_dir = dir.join("map");
    let map = make_map(
        &map_dir,
        &MapOptions {
            n: 3,
            coarse: true,
            noise: 0.01,
            ..MapOptions::default()
        },
    )?;
    println!(
        "slurm-check: synthetic map of {} indents in {}",
        map.indents.len(),
        map_dir.display()
    );

    // the same batch on this machine
    let local = dir.join("local");
    let local_seconds = local_batch(&indentify, &map, &local)?;

    // as a Slurm job array
    let shared = dir.join("slurm");
    write_scripts(&indentify, &map, &shared, o.array)?;
    let script = shared.join("batch.sbatch");
    let t0 = Instant::now();
    let job = slurm.submit(&script, &shared)?;
    println!("slurm-check: submitted job array {job} ({} tasks)", o.array);
    let tasks = match slurm.wait(&job, o.timeout) {
        Ok(t) => t,
        Err(e) => {
            let _ = slurm.command("scancel").arg(&job).status();
            print_logs(&dir);
            return Err(e);
        }
    };
    let slurm_seconds = t0.elapsed().as_secs_f64();
    println!(
        "slurm-check: job array {job} done in {slurm_seconds:.1} s; tasks (scontrol show job):"
    );
    for t in &tasks {
        println!("  {t}");
    }
    // the node is idle again once every task's step has ended
    wait_for_node(&slurm, &host, &dir, &mut daemons)?;
    print_task_logs(&shared)?;
    let text = run_checked(
        Command::new(&indentify)
            .arg("batch")
            .arg("merge")
            .arg(&shared),
        "indentify batch merge",
    )?;
    print_indented("batch merge", &text);

    // the comparison
    let (ta, tb) = read_results(&local, &shared)?;
    let problems = problems(&ta, &tb, map.indents.len(), &tasks, o.array);
    let counts = status_counts(&ta);

    drop(daemons);
    println!("slurm-check summary:");
    println!("  slurm:      {}", version.trim());
    println!(
        "  map:        {} indents; statuses {:?}",
        map.indents.len(),
        counts
    );
    println!("  local:      indentify batch, {local_seconds:.1} s");
    println!(
        "  slurm:      {} array tasks, submit to finish {slurm_seconds:.1} s, then batch merge",
        o.array
    );
    if problems.is_empty() {
        println!(
            "  results:    the merged results.csv equals the local one bit for bit except the \
             `seconds` column ({} rows x {} columns compared)",
            ta.rows.len(),
            ta.header.len() - 1
        );
        println!("  PASSED in {:.1} s", clock.elapsed().as_secs_f64());
        Ok(())
    } else {
        for p in &problems {
            println!("  MISMATCH: {p}");
        }
        println!("  FAILED in {:.1} s", clock.elapsed().as_secs_f64());
        bail!(
            "slurm-check failed: {} problem(s); rerun with --keep to inspect {}",
            problems.len(),
            dir.display()
        )
    }
}

/// The map's batch on this machine, into `local`; its wall time (s).
fn local_batch(
    indentify: &Path,
    map: &indentify_study::synthetic::MapFiles,
    local: &Path,
) -> Result<f64> {
    let t0 = Instant::now();
    let text = run_checked(
        Command::new(indentify)
            .arg("batch")
            .arg(&map.manifest)
            .arg("--out")
            .arg(local)
            .arg("--config")
            .arg(&map.base)
            .arg("--quiet"),
        "indentify batch (local)",
    )?;
    let seconds = t0.elapsed().as_secs_f64();
    print_indented("local batch", &text);
    Ok(seconds)
}

/// `indentify batch slurm`: the job array's scripts for `array` tasks, into `shared`.
fn write_scripts(
    indentify: &Path,
    map: &indentify_study::synthetic::MapFiles,
    shared: &Path,
    array: usize,
) -> Result<()> {
    let text = run_checked(
        Command::new(indentify)
            .arg("batch")
            .arg("slurm")
            .arg(&map.manifest)
            .arg("--out")
            .arg(shared)
            .arg("--config")
            .arg(&map.base)
            .arg("--array")
            .arg(array.to_string())
            .arg("--partition")
            .arg("check")
            .arg("--time")
            .arg("00:15:00"),
        "indentify batch slurm",
    )?;
    print_indented("batch slurm", &text);
    Ok(())
}

/// Prints every array task's log (`slurm-*` in `shared`).
fn print_task_logs(shared: &Path) -> Result<()> {
    println!("slurm-check: per-task logs:");
    let mut logs: Vec<PathBuf> = fs::read_dir(shared)?
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| {
            p.file_name()
                .is_some_and(|n| n.to_string_lossy().starts_with("slurm-"))
        })
        .collect();
    logs.sort();
    for p in &logs {
        let name = p.file_name().unwrap_or_default().to_string_lossy();
        let text = fs::read_to_string(p).unwrap_or_default();
        if text.trim().is_empty() {
            println!("  {name}: (empty)");
        }
        for line in text.lines() {
            println!("  {name}: {line}");
        }
    }
    Ok(())
}

/// The options of `cargo xtask slurm-check`.
fn parse_options(args: &[String]) -> Result<Options> {
    let mut o = Options {
        keep: false,
        array: 4,
        timeout: Duration::from_secs(600),
        indentify: None,
    };
    let mut it = args.iter();
    while let Some(a) = it.next() {
        let mut val = || {
            it.next()
                .cloned()
                .ok_or_else(|| anyhow!("{a} needs a value"))
        };
        match a.as_str() {
            "--keep" => o.keep = true,
            "--array" => o.array = val()?.parse().context("--array N")?,
            "--timeout" => {
                o.timeout = Duration::from_secs(val()?.parse().context("--timeout SECONDS")?);
            }
            "--indentify" => o.indentify = Some(PathBuf::from(val()?)),
            other => bail!(
                "unknown option {other} (cargo xtask slurm-check [--keep] [--array N] \
                 [--timeout SECONDS] [--indentify PATH])"
            ),
        }
    }
    Ok(o)
}

/// What differs between the local results `ta` and the merged ones `tb` of a map of
/// `indents` indents, and array tasks (of `array`) missing or not completed.
fn problems(ta: &Table, tb: &Table, indents: usize, tasks: &[String], array: usize) -> Vec<String> {
    let failed_tasks: Vec<&String> = tasks
        .iter()
        .filter(|t| !t.contains("JobState=COMPLETED") || !t.contains("ExitCode=0:0"))
        .collect();
    let mut problems = compare(ta, tb);
    if ta.rows.len() != indents {
        problems.push(format!(
            "the local results.csv has {} rows for {} indents",
            ta.rows.len(),
            indents
        ));
    }
    if tasks.len() != array {
        problems.push(format!(
            "scontrol reported {} array tasks, not {}",
            tasks.len(),
            array
        ));
    }
    if !failed_tasks.is_empty() {
        problems.push(format!(
            "{} array tasks did not complete",
            failed_tasks.len()
        ));
    }
    problems
}

/// The executables the check needs.
struct Tools {
    slurmctld: PathBuf,
    slurmd: PathBuf,
    munged: PathBuf,
    mungekey: Option<PathBuf>,
    sbatch: PathBuf,
}

/// The effective user id, from /proc.
fn effective_uid() -> Option<u32> {
    fs::read_to_string("/proc/self/status")
        .ok()?
        .lines()
        .find_map(|l| l.strip_prefix("Uid:"))?
        .split_whitespace()
        .nth(1)?
        .parse()
        .ok()
}

fn find(name: &str) -> Option<PathBuf> {
    let path = std::env::var_os("PATH").unwrap_or_default();
    std::env::split_paths(&path)
        .chain(SEARCH.iter().map(PathBuf::from))
        .map(|d| d.join(name))
        .find(|p| p.is_file())
}

/// Finds Slurm and munge, installing Debian's packages when slurmctld or munged is missing.
fn ensure_installed() -> Result<Tools> {
    let mut missing = Vec::new();
    if find("slurmctld").is_none() || find("slurmd").is_none() || find("sbatch").is_none() {
        missing.push("slurm-wlm");
    }
    if find("munged").is_none() {
        missing.push("munge");
    }
    if !missing.is_empty() {
        println!(
            "slurm-check: {} not installed: installing Debian's {}",
            if missing.contains(&"slurm-wlm") {
                "slurmctld/slurmd/sbatch"
            } else {
                "munged"
            },
            missing.join(" and ")
        );
        let Some(apt) = find("apt-get") else {
            bail!(
                "Slurm is not installed and apt-get is not available: install slurmctld, slurmd, \
                 the Slurm client (sbatch, squeue, scontrol) and munge, then rerun"
            );
        };
        let install = |update: bool| -> Result<bool> {
            if update {
                println!("slurm-check: apt-get update");
                let s = Command::new(&apt)
                    .arg("update")
                    .env("DEBIAN_FRONTEND", "noninteractive")
                    .stdout(Stdio::null())
                    .status()
                    .context("running apt-get update")?;
                if !s.success() {
                    bail!("apt-get update failed ({s}): are you root, with the package mirror?");
                }
            }
            println!("slurm-check: apt-get install -y {}", missing.join(" "));
            let s = Command::new(&apt)
                .args(["install", "-y", "--no-install-recommends"])
                .args(&missing)
                .env("DEBIAN_FRONTEND", "noninteractive")
                .stdout(Stdio::null())
                .status()
                .context("running apt-get install")?;
            Ok(s.success())
        };
        if !install(false)? && !install(true)? {
            bail!(
                "apt-get install {} failed: install Slurm and munge by hand (as root), then rerun",
                missing.join(" ")
            );
        }
    }
    let need = |name: &str| {
        find(name).ok_or_else(|| anyhow!("`{name}` is still missing after the installation"))
    };
    for n in ["squeue", "scontrol", "scancel", "sinfo"] {
        need(n)?;
    }
    Ok(Tools {
        slurmctld: need("slurmctld")?,
        slurmd: need("slurmd")?,
        munged: need("munged")?,
        mungekey: find("mungekey"),
        sbatch: need("sbatch")?,
    })
}

/// `cargo build --release -p indentify-cli` and the path of its binary.
fn build_indentify() -> Result<PathBuf> {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"))
        .parent()
        .map(Path::to_path_buf)
        .ok_or_else(|| anyhow!("no workspace root"))?;
    let cargo = std::env::var_os("CARGO").unwrap_or_else(|| "cargo".into());
    println!("slurm-check: cargo build --release -p indentify-cli");
    let s = Command::new(cargo)
        .args(["build", "--release", "-p", "indentify-cli"])
        .current_dir(&root)
        .status()
        .context("running cargo build")?;
    if !s.success() {
        bail!("cargo build --release -p indentify-cli failed ({s})");
    }
    let target = match std::env::var_os("CARGO_TARGET_DIR") {
        Some(t) if !t.is_empty() => {
            let t = PathBuf::from(t);
            if t.is_absolute() { t } else { root.join(t) }
        }
        _ => root.join("target"),
    };
    Ok(target.join("release").join("indentify"))
}

/// A temporary folder removed on drop unless kept.
struct TempDir {
    path: PathBuf,
    keep: bool,
}

impl TempDir {
    fn new(keep: bool) -> Result<TempDir> {
        let nanos = SystemTime::now()
            .duration_since(UNIX_EPOCH)
            .map_or(0, |d| d.subsec_nanos());
        let path =
            std::env::temp_dir().join(format!("indentify-slurm-{}-{nanos:09}", std::process::id()));
        fs::create_dir(&path).with_context(|| format!("creating {}", path.display()))?;
        // munged refuses folders that others may write into
        set_mode(&path, 0o755)?;
        Ok(TempDir { path, keep })
    }
}

impl Drop for TempDir {
    fn drop(&mut self) {
        if self.keep {
            println!("slurm-check: kept {}", self.path.display());
        } else if let Err(e) = fs::remove_dir_all(&self.path) {
            eprintln!(
                "slurm-check: warning: could not remove {}: {e}",
                self.path.display()
            );
        } else {
            println!("slurm-check: removed {}", self.path.display());
        }
    }
}

fn set_mode(path: &Path, mode: u32) -> Result<()> {
    use std::os::unix::fs::PermissionsExt as _;
    fs::set_permissions(path, fs::Permissions::from_mode(mode))
        .with_context(|| format!("setting the mode of {}", path.display()))
}

/// The daemons started, stopped by PID (SIGTERM, then SIGKILL after 15 s) in reverse order
/// on drop, also on failure.
struct Daemons {
    children: Vec<(&'static str, Child)>,
    /// The configuration: slurmstepd processes started by our slurmd carry it in their
    /// environment.
    conf: PathBuf,
}

impl Drop for Daemons {
    fn drop(&mut self) {
        while let Some((name, mut child)) = self.children.pop() {
            let pid = child.id();
            if let Ok(Some(status)) = child.try_wait() {
                println!("slurm-check: {name} (pid {pid}) had already exited ({status})");
                continue;
            }
            let _ = Command::new("kill")
                .args(["-TERM", &pid.to_string()])
                .status();
            let deadline = Instant::now() + Duration::from_secs(15);
            let mut stopped = false;
            while Instant::now() < deadline {
                if let Ok(Some(_)) = child.try_wait() {
                    stopped = true;
                    break;
                }
                std::thread::sleep(Duration::from_millis(100));
            }
            if stopped {
                println!("slurm-check: stopped {name} (pid {pid})");
            } else {
                let _ = child.kill();
                let _ = child.wait();
                println!("slurm-check: killed {name} (pid {pid}): it ignored SIGTERM for 15 s");
            }
        }
        // job steps outlive slurmd by a moment: wait (at most 10 s) before the folder goes
        let deadline = Instant::now() + Duration::from_secs(10);
        let mut steps = step_daemons(&self.conf);
        if !steps.is_empty() {
            while !steps.is_empty() && Instant::now() < deadline {
                std::thread::sleep(Duration::from_millis(100));
                steps = step_daemons(&self.conf);
            }
            if steps.is_empty() {
                println!("slurm-check: the last job steps (slurmstepd) have ended");
            } else {
                eprintln!("slurm-check: warning: slurmstepd still running: pids {steps:?}");
            }
        }
    }
}

/// The PIDs of the slurmstepd processes whose environment names `conf` as `SLURM_CONF`.
fn step_daemons(conf: &Path) -> Vec<u32> {
    let needle = format!("SLURM_CONF={}", conf.display());
    let Ok(entries) = fs::read_dir("/proc") else {
        return Vec::new();
    };
    entries
        .filter_map(|e| e.ok())
        .filter_map(|e| e.file_name().to_str()?.parse::<u32>().ok())
        .filter(|pid| {
            fs::read_to_string(format!("/proc/{pid}/comm")).is_ok_and(|c| c.trim() == "slurmstepd")
                && fs::read(format!("/proc/{pid}/environ"))
                    .is_ok_and(|env| env.split(|b| *b == 0).any(|v| v == needle.as_bytes()))
        })
        .collect()
}

/// This host's short name (what slurmd calls itself).
fn short_hostname() -> Result<String> {
    let full = fs::read_to_string("/proc/sys/kernel/hostname")
        .or_else(|_| output(&mut Command::new("hostname")))
        .context("reading the host name")?;
    let short = full
        .trim()
        .split('.')
        .next()
        .unwrap_or_default()
        .to_string();
    if short.is_empty() {
        bail!("this host has no name");
    }
    Ok(short)
}

/// CPUs, memory (MB) and topology (`SocketsPerBoard=...`) as slurmd sees them (`slurmd -C`),
/// else CPUs and memory as std and /proc see them.
fn node_size(slurmd: &Path) -> (usize, u64, String) {
    let mut cpus = std::thread::available_parallelism().map_or(1, |n| n.get());
    let mut memory = fs::read_to_string("/proc/meminfo")
        .ok()
        .and_then(|t| {
            t.lines()
                .find(|l| l.starts_with("MemTotal:"))
                .and_then(|l| l.split_whitespace().nth(1))
                .and_then(|kb| kb.parse::<u64>().ok())
        })
        .map_or(1024, |kb| kb / 1024);
    let mut topology = Vec::new();
    if let Ok(text) = output(Command::new(slurmd).arg("-C")) {
        for word in text.split_whitespace() {
            if [
                "Boards=",
                "SocketsPerBoard=",
                "CoresPerSocket=",
                "ThreadsPerCore=",
            ]
            .iter()
            .any(|k| word.starts_with(k))
            {
                topology.push(word.to_string());
            }
            if let Some(v) = word.strip_prefix("CPUs=") {
                cpus = v.parse().unwrap_or(cpus);
            }
            if let Some(v) = word.strip_prefix("RealMemory=") {
                memory = v.parse().unwrap_or(memory);
            }
        }
    }
    (cpus, memory, topology.join(" "))
}

/// slurm.conf for one node on loopback, every state, spool, pid and log file in `dir`.
fn write_config(
    dir: &Path,
    host: &str,
    cpus: usize,
    memory: u64,
    topology: &str,
) -> Result<PathBuf> {
    for sub in ["state", "spool", "log", "munge"] {
        fs::create_dir_all(dir.join(sub))?;
        set_mode(&dir.join(sub), 0o755)?;
    }
    let d = dir.display();
    let text = format!(
        "# slurm.conf of `cargo xtask slurm-check`: one node on loopback, all in {d}\n\
         ClusterName=indentify-check\n\
         SlurmctldHost={host}(127.0.0.1)\n\
         SlurmctldPort=16817\n\
         SlurmdPort=16818\n\
         SlurmUser=root\n\
         SlurmdUser=root\n\
         AuthType=auth/munge\n\
         CredType=cred/munge\n\
         AuthInfo=socket={d}/munge/munge.socket\n\
         StateSaveLocation={d}/state\n\
         SlurmdSpoolDir={d}/spool\n\
         SlurmctldPidFile={d}/slurmctld.pid\n\
         SlurmdPidFile={d}/slurmd.pid\n\
         SlurmctldLogFile={d}/log/slurmctld.log\n\
         SlurmdLogFile={d}/log/slurmd.log\n\
         ProctrackType=proctrack/linuxproc\n\
         TaskPlugin=task/none\n\
         SelectType=select/cons_tres\n\
         SelectTypeParameters=CR_CPU\n\
         SchedulerType=sched/backfill\n\
         MpiDefault=none\n\
         JobAcctGatherType=jobacct_gather/none\n\
         AccountingStorageType=accounting_storage/none\n\
         JobCompType=jobcomp/none\n\
         ReturnToService=2\n\
         MinJobAge=600\n\
         NodeName={host} NodeAddr=127.0.0.1 CPUs={cpus} {topology} RealMemory={memory} State=UNKNOWN\n\
         PartitionName=check Nodes={host} Default=YES MaxTime=INFINITE State=UP\n"
    );
    let path = dir.join("slurm.conf");
    fs::write(&path, text)?;
    Ok(path)
}

/// munged (its key and socket in `dir/munge`), slurmctld and slurmd, in the foreground as
/// children of this process.
fn start_daemons(
    tools: &Tools,
    dir: &Path,
    conf: &Path,
    host: &str,
    daemons: &mut Daemons,
) -> Result<()> {
    let m = dir.join("munge");
    let key = m.join("munge.key");
    match &tools.mungekey {
        Some(mk) => {
            run_checked(
                Command::new(mk)
                    .arg("--create")
                    .arg(format!("--keyfile={}", key.display())),
                "mungekey --create",
            )?;
        }
        None => {
            // older munge: 1 KiB of random bytes
            let mut bytes = vec![0u8; 1024];
            use std::io::Read as _;
            fs::File::open("/dev/urandom")?.read_exact(&mut bytes)?;
            fs::write(&key, bytes)?;
        }
    }
    set_mode(&key, 0o600)?;
    let socket = m.join("munge.socket");
    let log = |name: &str| -> Result<Stdio> {
        Ok(Stdio::from(
            fs::File::create(dir.join("log").join(format!("{name}.out")))
                .with_context(|| format!("creating the log of {name}"))?,
        ))
    };
    let spawn = |name: &'static str, cmd: &mut Command, daemons: &mut Daemons| -> Result<()> {
        let child = cmd
            .stdin(Stdio::null())
            .stdout(log(name)?)
            .stderr(log(&format!("{name}.err"))?)
            .spawn()
            .with_context(|| format!("starting {name}"))?;
        println!("slurm-check: started {name} (pid {})", child.id());
        daemons.children.push((name, child));
        Ok(())
    };
    spawn(
        "munged",
        Command::new(&tools.munged)
            .arg("--foreground")
            .arg("--force")
            .arg(format!("--socket={}", socket.display()))
            .arg(format!("--key-file={}", key.display()))
            .arg(format!("--pid-file={}", m.join("munged.pid").display()))
            .arg(format!("--log-file={}", m.join("munged.log").display()))
            .arg(format!("--seed-file={}", m.join("munged.seed").display())),
        daemons,
    )?;
    wait_until(Duration::from_secs(20), "munged to open its socket", || {
        Ok(socket.exists())
    })
    .inspect_err(|_| print_logs(dir))?;
    check_alive(daemons).inspect_err(|_| print_logs(dir))?;
    spawn(
        "slurmctld",
        Command::new(&tools.slurmctld)
            .arg("-D")
            .arg("-i")
            .arg("-f")
            .arg(conf)
            .env("SLURM_CONF", conf),
        daemons,
    )?;
    spawn(
        "slurmd",
        Command::new(&tools.slurmd)
            .arg("-D")
            .arg("-N")
            .arg(host)
            .arg("-f")
            .arg(conf)
            .env("SLURM_CONF", conf),
        daemons,
    )?;
    Ok(())
}

/// Fails if a daemon has exited (the caller prints the logs).
fn check_alive(daemons: &mut Daemons) -> Result<()> {
    for (name, child) in &mut daemons.children {
        if let Ok(Some(status)) = child.try_wait() {
            bail!("{name} exited ({status}): see the daemons' logs above");
        }
    }
    Ok(())
}

/// The Slurm client commands with `SLURM_CONF` set.
struct Slurm<'a> {
    conf: PathBuf,
    tools: &'a Tools,
}

impl Slurm<'_> {
    fn command(&self, name: &str) -> Command {
        let exe = if name == "sbatch" {
            self.tools.sbatch.clone()
        } else {
            find(name).unwrap_or_else(|| PathBuf::from(name))
        };
        let mut c = Command::new(exe);
        c.env("SLURM_CONF", &self.conf);
        c
    }

    /// `sbatch --parsable SCRIPT` from `dir`: the job id.
    fn submit(&self, script: &Path, dir: &Path) -> Result<String> {
        println!(
            "slurm-check: SLURM_CONF={} sbatch --parsable {}",
            self.conf.display(),
            script.display()
        );
        let text = run_checked(
            self.command("sbatch")
                .arg("--parsable")
                .arg(script)
                .current_dir(dir),
            "sbatch",
        )?;
        let id = text
            .trim()
            .split(';')
            .next()
            .unwrap_or_default()
            .to_string();
        if id.is_empty() || !id.chars().all(|c| c.is_ascii_digit()) {
            bail!("sbatch printed no job id: `{}`", text.trim());
        }
        Ok(id)
    }

    /// Polls squeue until the array has left the queue (at most `timeout`), then one line
    /// per task from `scontrol show job`.
    fn wait(&self, job: &str, timeout: Duration) -> Result<Vec<String>> {
        let start = Instant::now();
        let mut last = String::new();
        loop {
            let q = output(
                self.command("squeue")
                    .args(["-h", "-j", job, "-o", "%i %T %R"]),
            )
            .with_context(|| format!("squeue failed while waiting for job {job}"))?;
            let q = q.trim().to_string();
            if q.is_empty() {
                break;
            }
            let summary = q.lines().collect::<Vec<_>>().join("; ");
            if summary != last {
                println!(
                    "slurm-check: [{:5.1} s] squeue: {summary}",
                    start.elapsed().as_secs_f64()
                );
                last = summary;
            }
            if start.elapsed() > timeout {
                bail!(
                    "the job array {job} did not finish within {} s (squeue: {q})",
                    timeout.as_secs()
                );
            }
            std::thread::sleep(Duration::from_secs(1));
        }
        let text = output(self.command("scontrol").args(["-o", "show", "job", job]))
            .context("scontrol show job")?;
        let keys = [
            "JobId=",
            "ArrayTaskId=",
            "JobState=",
            "ExitCode=",
            "RunTime=",
            "NodeList=",
        ];
        let mut tasks: Vec<String> = text
            .lines()
            .filter(|l| !l.trim().is_empty())
            .map(|l| {
                l.split_whitespace()
                    .filter(|w| keys.iter().any(|k| w.starts_with(k)))
                    .collect::<Vec<_>>()
                    .join(" ")
            })
            .collect();
        tasks.sort_by_key(|t| {
            t.split_whitespace()
                .find_map(|w| w.strip_prefix("ArrayTaskId="))
                .and_then(|v| v.parse::<usize>().ok())
                .unwrap_or(0)
        });
        Ok(tasks)
    }
}

/// Waits for slurmctld to answer and the node to be idle.
fn wait_for_node(slurm: &Slurm, host: &str, dir: &Path, daemons: &mut Daemons) -> Result<()> {
    let mut state = String::new();
    let r = wait_until(
        Duration::from_secs(60),
        "the node to be idle in sinfo",
        || {
            check_alive(daemons)?;
            state = output(
                slurm
                    .command("sinfo")
                    .args(["-h", "-N", "-n", host, "-o", "%T"]),
            )
            .unwrap_or_default()
            .trim()
            .to_string();
            Ok(state.starts_with("idle"))
        },
    );
    if let Err(e) = r {
        print_logs(dir);
        return Err(e.context(format!("last node state: `{state}`")));
    }
    println!("slurm-check: node {host} is {state}");
    Ok(())
}

fn wait_until(timeout: Duration, what: &str, mut done: impl FnMut() -> Result<bool>) -> Result<()> {
    let start = Instant::now();
    while start.elapsed() < timeout {
        if done()? {
            return Ok(());
        }
        std::thread::sleep(Duration::from_millis(500));
    }
    bail!("timed out after {} s waiting for {what}", timeout.as_secs())
}

/// The tails of the daemons' logs, for a failure.
fn print_logs(dir: &Path) {
    for rel in [
        "munge/munged.log",
        "log/munged.err.out",
        "log/slurmctld.log",
        "log/slurmctld.err.out",
        "log/slurmd.log",
        "log/slurmd.err.out",
    ] {
        let Ok(text) = fs::read_to_string(dir.join(rel)) else {
            continue;
        };
        let lines: Vec<&str> = text.lines().collect();
        if lines.is_empty() {
            continue;
        }
        eprintln!("--- {rel} (last lines)");
        for l in &lines[lines.len().saturating_sub(15)..] {
            eprintln!("  {l}");
        }
    }
}

/// Runs `cmd`, returning its standard output, failing with its standard error.
fn output(cmd: &mut Command) -> Result<String> {
    let out = cmd
        .stdin(Stdio::null())
        .output()
        .with_context(|| format!("running {:?}", cmd.get_program()))?;
    if !out.status.success() {
        bail!(
            "{:?} failed ({}): {}",
            cmd.get_program(),
            out.status,
            String::from_utf8_lossy(&out.stderr).trim()
        );
    }
    Ok(String::from_utf8_lossy(&out.stdout).into_owned())
}

fn run_checked(cmd: &mut Command, what: &str) -> Result<String> {
    let out = cmd
        .stdin(Stdio::null())
        .output()
        .with_context(|| format!("running {what}"))?;
    let stdout = String::from_utf8_lossy(&out.stdout).into_owned();
    if !out.status.success() {
        bail!(
            "{what} failed ({}):\n{}{}",
            out.status,
            stdout,
            String::from_utf8_lossy(&out.stderr)
        );
    }
    Ok(stdout)
}

fn print_indented(what: &str, text: &str) {
    println!("slurm-check: {what}:");
    for l in text.lines() {
        println!("  | {l}");
    }
}

/// A CSV table as raw field texts (quotes kept), to compare byte for byte.
struct Table {
    header: Vec<String>,
    rows: Vec<Vec<String>>,
}

impl Table {
    fn column(&self, name: &str) -> Vec<String> {
        match self.header.iter().position(|h| h == name) {
            Some(k) => self
                .rows
                .iter()
                .map(|r| r.get(k).cloned().unwrap_or_default())
                .collect(),
            None => Vec::new(),
        }
    }
}

/// Splits CSV text into records of raw fields; quoted fields may hold commas and newlines.
fn table(bytes: &[u8]) -> Result<Table> {
    let text = std::str::from_utf8(bytes).context("results.csv is not UTF-8")?;
    let mut records: Vec<Vec<String>> = Vec::new();
    let mut record = Vec::new();
    let mut field = String::new();
    let mut quoted = false;
    for c in text.chars() {
        match c {
            '"' => {
                quoted = !quoted;
                field.push(c);
            }
            ',' if !quoted => record.push(std::mem::take(&mut field)),
            '\n' if !quoted => {
                record.push(std::mem::take(&mut field));
                records.push(std::mem::take(&mut record));
            }
            _ => field.push(c),
        }
    }
    if !field.is_empty() || !record.is_empty() {
        record.push(field);
        records.push(record);
    }
    if records.is_empty() {
        bail!("results.csv is empty");
    }
    let header = records.remove(0);
    Ok(Table {
        header,
        rows: records,
    })
}

/// The differences of two results tables, ignoring the `seconds` column.
fn compare(a: &Table, b: &Table) -> Vec<String> {
    let mut problems = Vec::new();
    if a.header != b.header {
        problems.push(format!(
            "headers differ: `{}` vs `{}`",
            a.header.join(","),
            b.header.join(",")
        ));
        return problems;
    }
    let Some(skip) = a.header.iter().position(|h| h == "seconds") else {
        problems.push("results.csv has no `seconds` column".into());
        return problems;
    };
    if a.rows.len() != b.rows.len() {
        problems.push(format!(
            "{} rows locally, {} merged",
            a.rows.len(),
            b.rows.len()
        ));
    }
    for (k, (ra, rb)) in a.rows.iter().zip(&b.rows).enumerate() {
        let strip = |r: &Vec<String>| -> Vec<String> {
            r.iter()
                .enumerate()
                .filter(|(i, _)| *i != skip)
                .map(|(_, f)| f.clone())
                .collect()
        };
        let (sa, sb) = (strip(ra), strip(rb));
        if sa != sb {
            problems.push(format!(
                "row {}: `{}` vs `{}`",
                k + 1,
                sa.join(","),
                sb.join(",")
            ));
        }
    }
    problems
}

/// The local and the merged results.csv, read and their sizes printed.
fn read_results(local: &Path, shared: &Path) -> Result<(Table, Table)> {
    let a = fs::read(local.join("results.csv")).context("reading the local results.csv")?;
    let b = fs::read(shared.join("results.csv")).context("reading the merged results.csv")?;
    let (ta, tb) = (table(&a)?, table(&b)?);
    println!(
        "slurm-check: local results.csv: {} bytes, {} rows x {} columns; merged: {} bytes, {} \
         rows x {} columns",
        a.len(),
        ta.rows.len(),
        ta.header.len(),
        b.len(),
        tb.rows.len(),
        tb.header.len()
    );
    Ok((ta, tb))
}

/// How many indents ended in each status.
fn status_counts(t: &Table) -> std::collections::BTreeMap<String, usize> {
    let mut counts = std::collections::BTreeMap::new();
    for s in t.column("status") {
        *counts.entry(s).or_default() += 1;
    }
    counts
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn tables_compare_all_but_seconds() {
        let a = table(b"id,E,seconds,error\np1,2,0.100,\np2,3,1.000,\"a,\nb\"\n").unwrap();
        let b = table(b"id,E,seconds,error\np1,2,0.200,\np2,3,9.000,\"a,\nb\"\n").unwrap();
        assert_eq!(a.rows.len(), 2);
        assert!(compare(&a, &b).is_empty());
        let c = table(b"id,E,seconds,error\np1,2,0.100,\np2,3.0000001,1.000,\"a,\nb\"\n").unwrap();
        assert_eq!(compare(&a, &c).len(), 1);
    }
}
