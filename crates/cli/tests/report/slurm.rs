//! A report on a real Slurm cluster: a one-node cluster of its own (munged, slurmctld and
//! slurmd from a generated `slurm.conf` in a scratch folder), `scripts/slurm/report.sbatch`
//! submitted as an array job of three shards, whose first task submits the merge after
//! them, and the merged report
//! checked against the same matrix run unsharded: every workload, bit-identical images, the
//! same counts. Also the array script's refusal of an array that is not `1-N`, which needs
//! no cluster.
//!
//! The cluster test is skipped, saying why, where Slurm or munge is not installed (Debian:
//! `slurm-wlm munge`), except under `CI=true`, where it fails.

use crate::common::{self, assert_clean_error, merge, raybench_ok, results};
use serde_json::Value;
use std::collections::BTreeMap;
use std::fs;
use std::io::Read as _;
use std::net::TcpListener;
use std::os::unix::fs::PermissionsExt as _;
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Output, Stdio};
use std::time::Duration;

/// The programs the cluster test runs.
const TOOLS: [&str; 7] = [
    "munged",
    "slurmctld",
    "slurmd",
    "sbatch",
    "squeue",
    "sinfo",
    "scancel",
];

/// How long the cluster may take to come up, and the jobs to run.
const STARTUP: Duration = Duration::from_secs(30);
const JOBS: Duration = Duration::from_secs(120);

/// How many polls `pause` apart make a wait of `limit`: waits are bounded by counting
/// pauses, not by reading a clock (the time between polls adds a little to the bound).
fn polls(limit: Duration, pause: Duration) -> u128 {
    limit.as_millis() / pause.as_millis()
}

/// The repository root, where `scripts/slurm` is and the jobs are submitted from.
fn repo_root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
}

/// `tool` on `PATH` or in the system folders a daemon lives in (`/usr/sbin` is not on every
/// user's `PATH`).
fn find(tool: &str) -> Option<PathBuf> {
    let path = std::env::var_os("PATH").unwrap_or_default();
    std::env::split_paths(&path)
        .chain(["/usr/sbin", "/usr/local/sbin", "/sbin"].map(PathBuf::from))
        .map(|d| d.join(tool))
        .find(|p| p.is_file())
}

/// The matrix every run of the test measures: three self-contained scenes, one shard each.
#[rustfmt::skip]
const MATRIX: [&str; 15] = [
    "--scenes", "spheres,whitted,csg", "--backends", "naive,bvh", "--modes", "cast",
    "--rays", "primary", "--size", "64", "--repeat", "1", "--min-sample", "0", "--no-scaling",
];

/// The cluster: its scratch folder, `slurm.conf` and the daemons it started (stopped, and
/// the folder removed, when it is dropped, whether the test passed or not).
struct Cluster {
    dir: PathBuf,
    conf: PathBuf,
    node: String,
    daemons: Vec<(&'static str, Child)>,
}

impl Cluster {
    /// Writes the munge key and `slurm.conf` into `dir` and starts munged, slurmctld and
    /// slurmd in the foreground, as this process's children; waits for the node to be idle.
    fn start(dir: PathBuf, tools: &BTreeMap<&str, PathBuf>) -> Cluster {
        let node = fs::read_to_string("/proc/sys/kernel/hostname")
            .ok()
            .and_then(|h| h.trim().split('.').next().map(str::to_string))
            .filter(|h| !h.is_empty())
            .unwrap_or_else(|| "localhost".into());
        let mut cluster = Cluster {
            conf: dir.join("slurm.conf"),
            dir,
            node,
            daemons: Vec::new(),
        };
        let d = cluster.dir.clone();
        for sub in ["state", "spool"] {
            fs::create_dir_all(d.join(sub)).unwrap();
        }
        // munged wants its key private to its user: 1024 random bytes, mode 0600.
        let mut random = vec![0_u8; 1024];
        fs::File::open("/dev/urandom")
            .and_then(|mut f| f.read_exact(&mut random))
            .expect("random bytes for the munge key");
        let key = d.join("munge.key");
        fs::write(&key, &random).unwrap();
        fs::set_permissions(&key, fs::Permissions::from_mode(0o600)).unwrap();
        let socket = d.join("munge.sock");
        let p = |name: &str| d.join(name).display().to_string();
        // --force: permissions munged would stop at (a scratch folder others may write to)
        // only warn.
        cluster.spawn(
            "munged",
            Command::new(&tools["munged"]).args([
                "--foreground",
                "--force",
                &format!("--socket={}", socket.display()),
                &format!("--key-file={}", key.display()),
                &format!("--pid-file={}", p("munged.pid")),
                &format!("--log-file={}", p("munged.log")),
                &format!("--seed-file={}", p("munged.seed")),
            ]),
        );
        cluster.wait_for(STARTUP, "munged's socket", || socket.exists());
        let user = String::from_utf8(
            Command::new("id")
                .arg("-un")
                .output()
                .expect("id runs")
                .stdout,
        )
        .unwrap()
        .trim()
        .to_string();
        let [ctld_port, d_port] = [free_port(), free_port()];
        let cpus = std::thread::available_parallelism().map_or(1, std::num::NonZero::get);
        let node = &cluster.node;
        // No cgroups (a container has none to give): processes tracked by their parents, no
        // task binding, no accounting. config_overrides: the node is what this file says,
        // whatever the hardware's sockets and cores, so it is never drained for a mismatch.
        let conf = format!(
            "ClusterName=raybench\n\
             SlurmctldHost={node}(127.0.0.1)\n\
             SlurmctldPort={ctld_port}\n\
             SlurmdPort={d_port}\n\
             SlurmUser={user}\n\
             SlurmdUser={user}\n\
             AuthType=auth/munge\n\
             AuthInfo=socket={socket}\n\
             CredType=cred/munge\n\
             MpiDefault=none\n\
             ProctrackType=proctrack/linuxproc\n\
             TaskPlugin=task/none\n\
             JobAcctGatherType=jobacct_gather/none\n\
             AccountingStorageType=accounting_storage/none\n\
             SelectType=select/cons_tres\n\
             SelectTypeParameters=CR_CPU\n\
             ReturnToService=2\n\
             SlurmdParameters=config_overrides\n\
             StateSaveLocation={state}\n\
             SlurmdSpoolDir={spool}\n\
             SlurmctldPidFile={ctld_pid}\n\
             SlurmdPidFile={d_pid}\n\
             SlurmctldLogFile={ctld_log}\n\
             SlurmdLogFile={d_log}\n\
             NodeName={node} NodeAddr=127.0.0.1 CPUs={cpus} State=UNKNOWN\n\
             PartitionName=debug Nodes={node} Default=YES MaxTime=INFINITE State=UP\n",
            socket = socket.display(),
            state = p("state"),
            spool = p("spool"),
            ctld_pid = p("slurmctld.pid"),
            d_pid = p("slurmd.pid"),
            ctld_log = p("slurmctld.log"),
            d_log = p("slurmd.log"),
        );
        fs::write(&cluster.conf, conf).unwrap();
        // -i: ignore (there is none) and start afresh from the state folder.
        let mut ctld = cluster.command(&tools["slurmctld"]);
        ctld.args(["-D", "-i"]);
        cluster.spawn("slurmctld", &mut ctld);
        let mut slurmd = cluster.command(&tools["slurmd"]);
        slurmd.args(["-D", "-N", &cluster.node.clone()]);
        cluster.spawn("slurmd", &mut slurmd);
        let (sinfo, conf) = (tools["sinfo"].clone(), cluster.conf.clone());
        cluster.wait_for(STARTUP, "the node to be idle", || {
            let mut c = Cluster::bare(&sinfo, &conf);
            c.args(["-h", "-o", "%t"]);
            c.output()
                .is_ok_and(|o| String::from_utf8_lossy(&o.stdout).trim() == "idle")
        });
        cluster
    }

    /// `program` talking to this cluster: `SLURM_CONF` names its file, and no Slurm setting
    /// of the environment (a CI job may itself run under Slurm) leaks in.
    fn command(&self, program: &Path) -> Command {
        Cluster::bare(program, &self.conf)
    }

    fn bare(program: &Path, conf: &Path) -> Command {
        let mut c = Command::new(program);
        for (k, _) in std::env::vars_os() {
            let k = k.to_string_lossy();
            if k.starts_with("SLURM_") || k.starts_with("SBATCH_") || k.starts_with("SQUEUE_") {
                c.env_remove(&*k);
            }
        }
        c.env("SLURM_CONF", conf);
        c
    }

    /// Starts a daemon in the foreground, its output in `NAME.out` in the folder.
    fn spawn(&mut self, name: &'static str, command: &mut Command) {
        let log = fs::File::create(self.dir.join(format!("{name}.out"))).unwrap();
        let child = command
            .stdin(Stdio::null())
            .stdout(log.try_clone().unwrap())
            .stderr(log)
            .spawn()
            .unwrap_or_else(|e| panic!("{name}: {e}"));
        self.daemons.push((name, child));
    }

    /// Waits until `ready`, failing with the daemons' logs after `limit` or when a daemon
    /// has exited.
    fn wait_for(&mut self, limit: Duration, what: &str, mut ready: impl FnMut() -> bool) {
        const PAUSE: Duration = Duration::from_millis(200);
        let mut left = polls(limit, PAUSE);
        while !ready() {
            let exited = self
                .daemons
                .iter_mut()
                .find_map(|(name, child)| child.try_wait().ok().flatten().map(|s| (*name, s)));
            if let Some((name, status)) = exited {
                panic!(
                    "{name} exited ({status}) waiting for {what}\n{}",
                    self.logs()
                );
            }
            assert!(left > 0, "no {what} after {limit:?}\n{}", self.logs());
            left -= 1;
            std::thread::sleep(PAUSE);
        }
    }

    /// The tails of the daemons' and the jobs' output, for a failure's message.
    fn logs(&self) -> String {
        let mut files: Vec<PathBuf> = fs::read_dir(&self.dir)
            .into_iter()
            .flatten()
            .chain(fs::read_dir(self.dir.join("run")).into_iter().flatten())
            .flatten()
            .map(|e| e.path())
            .filter(|p| p.extension().is_some_and(|e| e == "out" || e == "log"))
            .collect();
        files.sort();
        files
            .iter()
            .map(|f| {
                let text = fs::read_to_string(f).unwrap_or_default();
                let lines: Vec<&str> = text.lines().collect();
                format!(
                    "--- {}\n{}",
                    f.display(),
                    lines[lines.len().saturating_sub(15)..].join("\n")
                )
            })
            .collect::<Vec<_>>()
            .join("\n")
    }

    /// `squeue`'s job ids: those pending or running.
    fn queue(&self) -> String {
        let mut c = self.command(&find("squeue").expect("squeue"));
        c.args(["-h", "-o", "%i %T"]);
        c.output()
            .map(|o| String::from_utf8_lossy(&o.stdout).trim().to_string())
            .unwrap_or_default()
    }
}

impl Drop for Cluster {
    fn drop(&mut self) {
        // Jobs first (a failed test may leave some running), then the daemons, newest first,
        // each by its process id: a TERM, a moment to exit, then a KILL.
        if let Some(scancel) = find("scancel")
            && !self.daemons.is_empty()
        {
            let uid = Command::new("id").arg("-u").output().ok();
            if let Some(uid) = uid {
                let uid = String::from_utf8_lossy(&uid.stdout).trim().to_string();
                let _ = self
                    .command(&scancel)
                    .args(["--user", &uid])
                    .stderr(Stdio::null())
                    .status();
            }
        }
        while let Some((_, mut child)) = self.daemons.pop() {
            let _ = Command::new("kill")
                .args(["-TERM", &child.id().to_string()])
                .status();
            const PAUSE: Duration = Duration::from_millis(50);
            let mut left = polls(Duration::from_secs(5), PAUSE);
            while child.try_wait().ok().flatten().is_none() && left > 0 {
                left -= 1;
                std::thread::sleep(PAUSE);
            }
            let _ = child.kill();
            let _ = child.wait();
        }
        let _ = fs::remove_dir_all(&self.dir);
    }
}

/// A TCP port free at the moment of asking.
fn free_port() -> u16 {
    TcpListener::bind("127.0.0.1:0")
        .and_then(|l| l.local_addr())
        .expect("a free port")
        .port()
}

/// What identifies a workload's run: scene, mode, ray set, size, samples and backend.
fn key(run: &Value) -> String {
    [
        "scene", "mode", "ray_set", "width", "height", "spp", "backend",
    ]
    .map(|f| run[f].to_string())
    .join(" ")
}

/// Three shards of a small matrix, `sbatch --array=1-3 scripts/slurm/report.sbatch` on a one-node
/// Slurm cluster of the test's own, merged by the job that depends on them: the merged
/// report has every workload of the same matrix run unsharded, with bit-identical images and
/// the same counts, each shard naming the node and CPU model it ran on; and the merge
/// refuses the shards with one left out.
#[test]
fn a_slurm_array_job_runs_the_shards_and_merges_them() {
    let tools: BTreeMap<&str, PathBuf> = TOOLS
        .iter()
        .filter_map(|t| find(t).map(|p| (*t, p)))
        .collect();
    let missing: Vec<&str> = TOOLS
        .iter()
        .filter(|t| !tools.contains_key(*t))
        .copied()
        .collect();
    if !missing.is_empty() {
        let why = format!(
            "Slurm is not installed ({} not found; Debian: apt-get install slurm-wlm munge)",
            missing.join(", ")
        );
        assert!(
            std::env::var("CI").as_deref() != Ok("true"),
            "CI=true but {why}"
        );
        eprintln!("skipped: {why}");
        return;
    }
    let cluster = Cluster::start(common::tmp_dir("report", "slurm"), &tools);
    let run = cluster.dir.join("run");

    let mut submit = cluster.command(&tools["sbatch"]);
    submit
        .current_dir(repo_root())
        .args(["--array=1-3", "--cpus-per-task=1"])
        .arg(format!("--output={}/report-%a.out", run.display()))
        .arg("scripts/slurm/report.sbatch")
        .args(MATRIX)
        .env("RAYBENCH_BIN", env!("CARGO_BIN_EXE_raybench"))
        .env("RAYBENCH_SLURM_OUT", &run)
        .env_remove("RAYBENCH_SBATCH_OPTIONS")
        .env_remove("RAYBENCH_MERGE_OPTIONS");
    std::fs::create_dir_all(&run).unwrap();
    let out = submit.output().expect("sbatch runs");
    assert!(
        out.status.success(),
        "sbatch: {}\n{}",
        String::from_utf8_lossy(&out.stderr),
        cluster.logs()
    );

    // The same matrix unsharded, on one thread as each shard, while the jobs run.
    let whole = cluster.dir.join("whole");
    let mut args = vec!["report"];
    args.extend(MATRIX);
    let w = whole.to_str().unwrap();
    args.extend(["--threads", "1", "--out", w]);
    raybench_ok(&args);

    let merged = run.join("report");
    const PAUSE: Duration = Duration::from_millis(250);
    let mut left = polls(JOBS, PAUSE);
    while !(merged.join("results.json").is_file() && cluster.queue().is_empty()) {
        assert!(
            left > 0,
            "the jobs did not finish within {JOBS:?}; queue: {}\n{}",
            cluster.queue(),
            cluster.logs()
        );
        left -= 1;
        std::thread::sleep(PAUSE);
    }

    let m = results(&merged);
    let shards = m["shards"].as_array().unwrap();
    assert_eq!(shards.len(), 3, "{}", cluster.logs());
    for (i, sh) in shards.iter().enumerate() {
        assert_eq!(sh["index"], i + 1);
        assert_eq!(sh["count"], 3);
        let machine = &sh["machine"];
        let host = machine["host"].as_str().unwrap();
        assert!(
            host.split('.').next() == Some(cluster.node.as_str()),
            "{host}"
        );
        assert!(!machine["cpu"].as_str().unwrap().is_empty());
        assert_eq!(machine["threads"], 1, "--threads from SLURM_CPUS_PER_TASK");
    }
    let whole_results = results(&whole);
    let by_key = |r: &Value| -> BTreeMap<String, Value> {
        r["runs"]
            .as_array()
            .unwrap()
            .iter()
            .map(|run| (key(run), run.clone()))
            .collect()
    };
    let (mine, theirs) = (by_key(&m), by_key(&whole_results));
    assert_eq!(
        mine.keys().collect::<Vec<_>>(),
        theirs.keys().collect::<Vec<_>>()
    );
    assert_eq!(mine.len(), 3 * 2, "three scenes, two backends");
    for (k, a) in &mine {
        let b = &theirs[k];
        for field in [
            "status",
            "rays",
            "tests_per_ray",
            "visits_per_ray",
            "equality",
        ] {
            assert_eq!(a[field], b[field], "{k}: {field}");
        }
        for image in ["color", "ids_diff", "flip"] {
            assert_eq!(a["images"][image], b["images"][image], "{k}: {image}");
            if let Some(name) = a["images"][image].as_str() {
                let (x, y) = (
                    fs::read(merged.join(name)).unwrap(),
                    fs::read(whole.join(name)).unwrap(),
                );
                assert!(x == y, "{k}: {name} differs from the unsharded report's");
            }
        }
    }
    assert!(
        mine.values().any(|r| r["images"]["color"].is_string()),
        "no image compared"
    );

    // A shard left out: the merge refuses the set.
    let shard = |i: u32| run.join(format!("shards/{i}"));
    let partial = cluster.dir.join("partial");
    assert_clean_error(
        &merge(&[&shard(1), &shard(2)], &partial),
        "shards missing from the merge: 3/3 (matrix csg)",
    );
}

/// `report.sbatch` refuses to run outside an array job and in an array that is not `1-N`,
/// whose task count is not the shard count.
#[test]
fn the_array_script_refuses_an_array_not_numbered_from_one() {
    let script = repo_root().join("scripts/slurm/report.sbatch");
    let run = |env: &[(&str, &str)]| -> Output {
        let mut c = Cluster::bare(Path::new("bash"), Path::new("/nonexistent"));
        c.arg(&script)
            .env("RAYBENCH_BIN", "/nonexistent/raybench")
            .envs(env.iter().copied());
        c.output().expect("bash runs")
    };
    let refused = |out: &Output, needle: &str| {
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{stderr}");
        assert!(stderr.contains(needle), "{stderr}");
    };
    refused(&run(&[]), "not a task of an array job");
    for (min, max, count) in [("0", "2", "3"), ("2", "4", "3"), ("1", "7", "4")] {
        refused(
            &run(&[
                ("SLURM_ARRAY_TASK_ID", min),
                ("SLURM_ARRAY_TASK_MIN", min),
                ("SLURM_ARRAY_TASK_MAX", max),
                ("SLURM_ARRAY_TASK_COUNT", count),
            ]),
            &format!(
                "the array must be --array=1-N (one task per shard, numbered from 1, step 1); got tasks {min} to {max}, {count} in all"
            ),
        );
    }
}
