//! Scale-out on existing engines: a tiled run (`surfcap tiles`) on the engines users already have,
//! each giving the same bytes as one process (`tiles run WORK --all` + `tiles merge`): the user
//! guide's `xargs -P` route (`docs/src/tiles.md`), the Ray driver `tools/ray/surfcap_ray.py` on a local Ray instance started
//! and stopped here (a job made to fail once is retried; a job that keeps failing is named and
//! nothing is merged), and the Slurm scripts of `tools/slurm/` run as Slurm runs an array's
//! tasks, plus `submit.sh` against a fake `sbatch` (array ranges and the `afterok` chain).
//! Ray comes from `tools/venv` (`scripts/setup`); these tests fail when it is missing.

use std::collections::BTreeMap;
use std::os::unix::fs::PermissionsExt;
use std::os::unix::process::CommandExt;
use std::path::{Path, PathBuf};
use std::process::{Command, Output, Stdio};
use std::time::{Duration, Instant};

use surfcap_builtin::{WormParams, worm_subject};
use surfcap_mesh::NoProgress;
use surfcap_testkit::{p, stderr, surfcap, workspace_root};

const SURFCAP: &str = env!("CARGO_BIN_EXE_surfcap");

/// Frames of the tiny tube per sequence (two sequences), and the tile size: several tiles
/// per stage, a whole run in seconds.
const FRAMES_PER_SEQUENCE: usize = 40;
const TILE: &str = "32";

/// The built-in tube, 240 triangles, 80 frames in two sequences, as a subject cache.
fn tiny_subject(dir: &Path, name: &str) -> PathBuf {
    let s = worm_subject(&WormParams { rings: 12, segments: 10, frames: FRAMES_PER_SEQUENCE, ..Default::default() })
        .expect("the tube builds");
    let path = dir.join(name);
    surfcap_mesh::cache::write_cache(&path, &s, false, &NoProgress).expect("the subject cache is written");
    path
}

fn ok(o: &Output, what: &str) -> String {
    assert!(o.status.success(), "{what} failed ({}):\n{}\n{}", o.status, String::from_utf8_lossy(&o.stdout), stderr(o));
    String::from_utf8_lossy(&o.stdout).into_owned()
}

/// `surfcap tiles plan SUBJECT -o WORK --tile 32`.
fn plan(subject: &Path, work: &Path) {
    ok(&surfcap!(&["--quiet", "tiles", "plan", p(subject), "-o", p(work), "--tile", TILE]), "tiles plan");
}

/// The stages of `WORK/plan.json`, in order, with their job counts.
fn stages(work: &Path) -> Vec<(String, usize)> {
    let plan: serde_json::Value = serde_json::from_slice(&std::fs::read(work.join("plan.json")).unwrap()).unwrap();
    plan["stages"]
        .as_array()
        .expect("plan.json has stages")
        .iter()
        .map(|s| (s["name"].as_str().unwrap().to_string(), s["jobs"].as_u64().unwrap() as usize))
        .collect()
}

/// The reference: the same plan computed in one process (`tiles run WORK --all`) and merged.
fn one_process(subject: &Path, dir: &Path) -> PathBuf {
    let work = dir.join("one-process.tiles");
    plan(subject, &work);
    ok(&surfcap!(&["--quiet", "tiles", "run", p(&work), "--all"]), "tiles run --all");
    ok(&surfcap!(&["--quiet", "tiles", "merge", p(&work)]), "tiles merge");
    work
}

/// Every file of the products, by path relative to the work folder: the Zarr arrays (chunks =
/// tiles) and `.npy`/JSON products of every stage and of the merge; not the plan (it names its
/// folder), the job records or `merge.json` (times and memory of this run).
fn products(work: &Path) -> BTreeMap<PathBuf, Vec<u8>> {
    fn walk(root: &Path, dir: &Path, out: &mut BTreeMap<PathBuf, Vec<u8>>) {
        for e in std::fs::read_dir(dir).unwrap() {
            let path = e.unwrap().path();
            let rel = path.strip_prefix(root).unwrap().to_path_buf();
            if ["plan.json", "merge.json", "jobs", "slurm-logs"].iter().any(|n| rel == Path::new(n)) {
                continue;
            }
            if path.is_dir() {
                walk(root, &path, out);
            } else if !rel.file_name().unwrap().to_string_lossy().starts_with('.') {
                out.insert(rel, std::fs::read(&path).unwrap());
            }
        }
    }
    assert!(work.join("merge.json").is_file(), "merge.json is missing in {}", work.display());
    let mut out = BTreeMap::new();
    walk(work, work, &mut out);
    for product in ["distances.zarr/zarr.json", "table/cost.zarr/zarr.json"] {
        assert!(out.contains_key(Path::new(product)), "{product} is missing in {}", work.display());
    }
    out
}

/// The merged products of `work` are byte for byte those of the one-process run.
fn assert_same_products(work: &Path, reference: &Path, route: &str) {
    let (got, want) = (products(work), products(reference));
    let names = |m: &BTreeMap<PathBuf, Vec<u8>>| m.keys().cloned().collect::<Vec<_>>();
    assert_eq!(names(&got), names(&want), "{route}: the merged files differ from the one-process run's");
    let chunks = want.keys().filter(|k| k.starts_with("distances.zarr") && !k.ends_with("zarr.json")).count();
    assert!(chunks > 1, "the distances have their tiles: {:?}", names(&want));
    for (name, bytes) in &want {
        assert!(&got[name] == bytes, "{route}: {} differs from the one-process run's", name.display());
    }
}

/// A fenced `sh` block of the user guide's tiles chapter: the first one after the line holding
/// `marker`.
fn guide_block(marker: &str) -> String {
    let guide = std::fs::read_to_string(workspace_root().join("docs/src/tiles.md")).unwrap();
    let after = &guide[guide.find(marker).unwrap_or_else(|| panic!("docs/src/tiles.md has no {marker}"))..];
    let start = after.find("```sh\n").expect("a sh block follows the marker") + "```sh\n".len();
    let len = after[start..].find("```").expect("the block ends");
    after[start..start + len].to_string()
}

/// PATH with the directory of the binary under test first, so `surfcap` in a script is it.
fn path_with(dirs: &[&Path]) -> String {
    let mut parts: Vec<String> = dirs.iter().map(|d| p(d).to_string()).collect();
    parts.push(std::env::var("PATH").unwrap_or_default());
    parts.join(":")
}

fn binary_dir() -> PathBuf {
    Path::new(SURFCAP).parent().unwrap().to_path_buf()
}

fn write_script(path: &Path, text: &str) {
    std::fs::write(path, text).unwrap();
    std::fs::set_permissions(path, std::fs::Permissions::from_mode(0o755)).unwrap();
}

#[test]
fn xargs_route_of_the_guide_gives_the_one_process_bytes() {
    let d = tempfile::tempdir().unwrap();
    let subject = tiny_subject(d.path(), "walker.subject");
    let reference = one_process(&subject, d.path());
    let work = d.path().join("walker.tiles");
    plan(&subject, &work);
    let block = guide_block("<!-- tiles_engines.rs runs this block: xargs -->");
    assert!(block.contains("xargs -P"), "the guide's block is the xargs route:\n{block}");
    let o = Command::new("bash")
        .args(["-euo", "pipefail", "-c", &block])
        .current_dir(d.path())
        .env("PATH", path_with(&[&binary_dir()]))
        .output()
        .unwrap();
    ok(&o, "the guide's xargs route");
    assert_same_products(&work, &reference, "xargs");
}

// ---------------------------------------------------------------------------------------------
// Ray

/// `tools/venv/bin/python`, with the ray package importable.
///
/// # Panics
/// When either is missing: scripts/setup installs them (tools/requirements.txt).
fn ray_python() -> PathBuf {
    let python = workspace_root().join("tools/venv/bin/python");
    assert!(
        python.is_file(),
        "{} is missing: run scripts/setup (it installs ray from tools/requirements.txt)",
        python.display()
    );
    let o = Command::new(&python).args(["-c", "import ray; print(ray.__version__)"]).output().expect("python runs");
    assert!(o.status.success(), "ray is not installed in tools/venv: run scripts/setup\n{}", stderr(&o));
    python
}

/// A TCP port nobody listens on now.
fn free_port() -> u16 {
    std::net::TcpListener::bind("127.0.0.1:0").unwrap().local_addr().unwrap().port()
}

/// A local Ray instance (`ray start --head --block`, 2 CPUs, no dashboard, its own temp dir and
/// ports) for as long as the guard lives. Drop stops it even when the test panics: SIGTERM to
/// `ray start`, which stops the processes it started, then SIGKILL to its process group (every
/// Ray process of this instance, started in a group of its own) for anything left. Not
/// `ray stop`: that kills every Ray instance of the machine, other users' too.
struct LocalRay {
    child: std::process::Child,
    address: String,
    _dir: tempfile::TempDir,
}

impl LocalRay {
    fn start(python: &Path) -> LocalRay {
        // Ray's sockets live under the temp dir; Unix socket paths are limited to 107 bytes.
        let dir = tempfile::Builder::new().prefix("ray").tempdir_in("/tmp").unwrap();
        let port = free_port();
        let log = dir.path().join("ray-start.log");
        let child = Command::new(python)
            .args(["-m", "ray.scripts.scripts", "start", "--head", "--block", "--num-cpus", "2"])
            .args(["--port", &port.to_string(), "--node-ip-address", "127.0.0.1", "--include-dashboard=false"])
            .args(["--dashboard-agent-listen-port", &free_port().to_string()])
            .args(["--object-store-memory", "100000000", "--disable-usage-stats", "--temp-dir"])
            .arg(dir.path().join("t"))
            .env("RAY_ACCEL_ENV_VAR_OVERRIDE_ON_ZERO", "0")
            .stdin(Stdio::null())
            .stdout(std::fs::File::create(&log).unwrap())
            .stderr(std::fs::File::create(dir.path().join("ray-start.err")).unwrap())
            .process_group(0)
            .spawn()
            .expect("ray start runs");
        let mut ray = LocalRay { child, address: format!("127.0.0.1:{port}"), _dir: dir };
        let t0 = Instant::now();
        loop {
            let text = std::fs::read_to_string(&log).unwrap_or_default();
            if text.contains("Ray runtime started") {
                return ray;
            }
            let err = || std::fs::read_to_string(ray._dir.path().join("ray-start.err")).unwrap_or_default();
            if let Some(status) = ray.child.try_wait().unwrap() {
                panic!("ray start exited ({status}) before the runtime started:\n{text}\n{}", err());
            }
            assert!(t0.elapsed() < Duration::from_secs(90), "Ray did not start in 90 s:\n{text}\n{}", err());
            std::thread::sleep(Duration::from_millis(200));
        }
    }
}

impl Drop for LocalRay {
    fn drop(&mut self) {
        let pid = self.child.id() as i32;
        unsafe { libc::kill(pid, libc::SIGTERM) };
        let t0 = Instant::now();
        while t0.elapsed() < Duration::from_secs(20) {
            if let Ok(Some(_)) = self.child.try_wait() {
                break;
            }
            std::thread::sleep(Duration::from_millis(100));
        }
        // The group is this instance's own (process_group(0) made `ray start` its leader).
        unsafe { libc::kill(-pid, libc::SIGKILL) };
        let _ = self.child.wait();
    }
}

/// A wrapper around the binary under test that makes job `index` of `stage` fail: the first
/// time it is asked for it (`once`, a marker folder made atomically), or every time. Every
/// attempt at that job is logged, one line each.
fn failing_wrapper(dir: &Path, stage: &str, index: usize, once: bool) -> (PathBuf, PathBuf) {
    let (script, attempts) =
        (dir.join(if once { "fails-once.sh" } else { "fails-always.sh" }), dir.join("attempts.log"));
    let marker = dir.join("failed-once");
    let fail = if once { format!("mkdir '{}' 2>/dev/null", p(&marker)) } else { "true".into() };
    write_script(
        &script,
        &format!(
            "#!/usr/bin/env bash\n\
             if [ \"$1 $2 $4 $5 $6 $7\" = \"tiles run --stage {stage} --index {index}\" ]; then\n\
             \x20 echo attempt >> '{log}'\n\
             \x20 if {fail}; then echo 'injected failure of {stage} {index}' >&2; exit 1; fi\n\
             fi\n\
             exec '{real}' \"$@\"\n",
            log = p(&attempts),
            real = SURFCAP,
        ),
    );
    (script, attempts)
}

fn driver(python: &Path, work: &Path, wrapper: &Path, ray: &LocalRay, retries: &str) -> Output {
    Command::new(python)
        .arg(workspace_root().join("tools/ray/surfcap_ray.py"))
        .arg(work)
        .args(["--surfcap", p(wrapper), "--address", &ray.address, "--retries", retries, "--cpus-per-job", "1"])
        .stdin(Stdio::null())
        .output()
        .expect("the driver runs")
}

#[test]
fn ray_driver_retries_a_job_failing_once_and_names_one_that_keeps_failing() {
    let python = ray_python();
    let d = tempfile::tempdir().unwrap();
    let subject = tiny_subject(d.path(), "worm.subject");
    let reference = one_process(&subject, d.path());
    let ray = LocalRay::start(&python);

    // A job that keeps failing: the driver stops after its retries, naming it; no merge.
    let work = d.path().join("always.tiles");
    plan(&subject, &work);
    let (table, table_jobs) = stages(&work).into_iter().nth(1).unwrap();
    let (wrapper, attempts) = failing_wrapper(d.path(), &table, table_jobs - 1, false);
    let o = driver(&python, &work, &wrapper, &ray, "1");
    assert!(!o.status.success(), "the driver succeeded with a job that always fails");
    let named = format!("{table} {}", table_jobs - 1);
    assert!(
        stderr(&o).contains(&format!("still failed after 1 retries: {named}")),
        "the job is named:\n{}",
        stderr(&o)
    );
    assert!(stderr(&o).contains(&format!("injected failure of {named}")), "its error is shown:\n{}", stderr(&o));
    assert_eq!(std::fs::read_to_string(&attempts).unwrap().lines().count(), 2, "one try and one retry");
    assert!(!work.join("merge.json").exists(), "nothing is merged after a failed job");

    // A job that fails once: retried, the run completes with the one-process bytes.
    let work = d.path().join("ray.tiles");
    plan(&subject, &work);
    let (distances, distance_jobs) = stages(&work)[0].clone();
    assert!(distance_jobs > 1, "the plan has several distance tiles");
    std::fs::remove_file(&attempts).unwrap();
    let (wrapper, attempts) = failing_wrapper(d.path(), &distances, 1, true);
    let t0 = Instant::now();
    let o = driver(&python, &work, &wrapper, &ray, "3");
    let seconds = t0.elapsed().as_secs_f64();
    let out = ok(&o, "the Ray driver");
    let summary: serde_json::Value =
        serde_json::from_str(&out).unwrap_or_else(|e| panic!("the summary is JSON ({e}):\n{out}"));
    assert_eq!(summary["retries"], 1, "{out}");
    assert_eq!(summary["retried_jobs"], serde_json::json!([format!("{distances} 1")]), "{out}");
    assert_eq!(summary["stages"][0]["failed_attempts"], 1, "{out}");
    let want: Vec<(String, usize)> = stages(&work);
    let got: Vec<(String, usize)> = summary["stages"]
        .as_array()
        .unwrap()
        .iter()
        .map(|s| (s["name"].as_str().unwrap().to_string(), s["jobs"].as_u64().unwrap() as usize))
        .collect();
    assert_eq!(got, want, "every stage ran, in the plan's order");
    assert_eq!(std::fs::read_to_string(&attempts).unwrap().lines().count(), 2, "the failed job ran twice");
    assert_same_products(&work, &reference, "Ray");
    eprintln!("Ray driver: {seconds:.1} s for {} jobs", want.iter().map(|s| s.1).sum::<usize>());
    drop(ray);
}

#[test]
fn ray_driver_refuses_a_missing_plan_or_binary() {
    let python = ray_python();
    let d = tempfile::tempdir().unwrap();
    let script = workspace_root().join("tools/ray/surfcap_ray.py");
    let run = |args: &[&str]| Command::new(&python).arg(&script).args(args).output().unwrap();
    let o = run(&[p(d.path()), "--surfcap", SURFCAP]);
    assert!(!o.status.success());
    assert!(stderr(&o).contains("plan.json is missing") && stderr(&o).contains("surfcap tiles plan"), "{}", stderr(&o));
    std::fs::write(d.path().join("plan.json"), r#"{"stages": [{"name": "distances", "jobs": 1}]}"#).unwrap();
    let missing = d.path().join("no-such-surfcap");
    let o = run(&[p(d.path()), "--surfcap", p(&missing)]);
    assert!(!o.status.success());
    assert!(stderr(&o).contains(&format!("--surfcap {}: no such program", p(&missing))), "{}", stderr(&o));
    std::fs::write(d.path().join("plan.json"), r#"{"stages": "all"}"#).unwrap();
    let o = run(&[p(d.path()), "--surfcap", SURFCAP]);
    assert!(!o.status.success());
    assert!(stderr(&o).contains("plan.json: expected a \"stages\" list"), "{}", stderr(&o));
}

// ---------------------------------------------------------------------------------------------
// Slurm

fn slurm_script(name: &str) -> PathBuf {
    workspace_root().join("tools/slurm").join(name)
}

#[test]
fn slurm_array_tasks_run_as_slurm_runs_them_give_the_one_process_bytes() {
    let d = tempfile::tempdir().unwrap();
    let subject = tiny_subject(d.path(), "worm.subject");
    let reference = one_process(&subject, d.path());
    let work = d.path().join("slurm.tiles");
    plan(&subject, &work);
    // What each task was started with: its arguments and RAYON_NUM_THREADS.
    let calls = d.path().join("calls.log");
    let logging = d.path().join("surfcap-logging.sh");
    write_script(
        &logging,
        &format!("#!/usr/bin/env bash\necho \"$RAYON_NUM_THREADS $*\" >> '{}'\nexec '{SURFCAP}' \"$@\"\n", p(&calls)),
    );
    let mut job_id = 4000;
    let mut expected = Vec::new();
    for (stage, jobs) in stages(&work) {
        let array_id = job_id;
        for task in 0..jobs {
            job_id += 1;
            // The variables Slurm sets in an array task (sbatch(1), "OUTPUT ENVIRONMENT VARIABLES").
            let o = Command::new("bash")
                .arg(slurm_script("surfcap-tiles.sbatch"))
                .current_dir(d.path())
                .env("SURFCAP", p(&logging))
                .env("WORK", p(&work))
                .env("STAGE", &stage)
                .env("SLURM_JOB_ID", job_id.to_string())
                .env("SLURM_ARRAY_JOB_ID", array_id.to_string())
                .env("SLURM_ARRAY_TASK_ID", task.to_string())
                .env("SLURM_ARRAY_TASK_COUNT", jobs.to_string())
                .env("SLURM_ARRAY_TASK_MIN", "0")
                .env("SLURM_ARRAY_TASK_MAX", (jobs - 1).to_string())
                .env("SLURM_ARRAY_TASK_STEP", "1")
                .env("SLURM_CPUS_PER_TASK", "2")
                .env("SLURM_JOB_NAME", format!("surfcap-{stage}"))
                .env("SLURM_SUBMIT_DIR", p(d.path()))
                .env_remove("OFFSET")
                .output()
                .unwrap();
            ok(&o, &format!("surfcap-tiles.sbatch, {stage} task {task}"));
            expected.push(format!("2 tiles run {} --stage {stage} --index {task}", p(&work)));
        }
        job_id += 1;
    }
    let o = Command::new("bash")
        .arg(slurm_script("surfcap-merge.sbatch"))
        .args([p(&work), p(&logging)])
        .env("SLURM_JOB_ID", job_id.to_string())
        .env("SLURM_CPUS_PER_TASK", "1")
        .output()
        .unwrap();
    ok(&o, "surfcap-merge.sbatch");
    expected.push(format!("1 tiles merge {}", p(&work)));
    let got: Vec<String> = std::fs::read_to_string(&calls).unwrap().lines().map(String::from).collect();
    assert_eq!(got, expected, "each task ran its job with SLURM_CPUS_PER_TASK threads");
    assert_same_products(&work, &reference, "Slurm array tasks");

    // Outside an array the template says so instead of running job 0.
    let o = Command::new("bash")
        .arg(slurm_script("surfcap-tiles.sbatch"))
        .args([p(&work), "distances", SURFCAP])
        .env_remove("SLURM_ARRAY_TASK_ID")
        .output()
        .unwrap();
    assert!(!o.status.success() && stderr(&o).contains("SLURM_ARRAY_TASK_ID is not set"), "{}", stderr(&o));
}

/// A fake `sbatch` that records its arguments (one call per line, arguments separated by
/// tabs) and prints a job id as `--parsable` does (with a cluster name, which submit.sh drops).
fn fake_sbatch(dir: &Path) -> PathBuf {
    let bin = dir.join("fake-bin");
    std::fs::create_dir(&bin).unwrap();
    let log = dir.join("sbatch.log");
    write_script(
        &bin.join("sbatch"),
        &format!(
            "#!/usr/bin/env bash\n\
             n=$(( $(cat '{log}' 2>/dev/null | wc -l) + 1 ))\n\
             (IFS=$'\\t'; echo \"$*\") >> '{log}'\n\
             echo \"$((7000 + n));testcluster\"\n",
            log = p(&log)
        ),
    );
    bin
}

fn sbatch_calls(dir: &Path) -> Vec<Vec<String>> {
    std::fs::read_to_string(dir.join("sbatch.log"))
        .unwrap()
        .lines()
        .map(|l| l.split('\t').map(String::from).collect())
        .collect()
}

#[test]
fn slurm_submit_chains_one_array_per_stage_and_the_merge() {
    let d = tempfile::tempdir().unwrap();
    let bin = fake_sbatch(d.path());
    // A fake surfcap whose stages have 3, 2, 1, 0 and 2,500 jobs: an empty stage is skipped,
    // a stage larger than MAX_ARRAY goes in several arrays, each told its offset.
    let counts = d.path().join("surfcap-counts.sh");
    write_script(
        &counts,
        "#!/usr/bin/env bash\n[ \"$1 $2 $4\" = 'tiles count --stage' ] || exit 9\n\
         case $5 in distances) echo 3;; table) echo 2;; scale) echo 1;; candidates) echo 0;; paths) echo 2500;; *) exit 9;; esac\n",
    );
    let work = d.path().join("fake.tiles");
    std::fs::create_dir(&work).unwrap();
    std::fs::write(work.join("plan.json"), "{}").unwrap();
    let o = Command::new("bash")
        .arg(slurm_script("submit.sh"))
        .args([p(&work), "--partition=cpu"])
        .env("PATH", path_with(&[&bin]))
        .env("SURFCAP", p(&counts))
        .env("MAX_ARRAY", "1000")
        .output()
        .unwrap();
    let out = ok(&o, "submit.sh");
    let calls = sbatch_calls(d.path());
    let tiles = p(&slurm_script("surfcap-tiles.sbatch")).to_string();
    let merge = p(&slurm_script("surfcap-merge.sbatch")).to_string();
    let logs = format!("--output={}/slurm-logs/", p(&work));
    // (array range, job name, offset, dependency, stage) per array, then the merge.
    let arrays = [
        ("0-2", "distances", 0, None),
        ("0-1", "table", 0, Some("afterok:7001")),
        ("0-0", "scale", 0, Some("afterok:7002")),
        ("0-999", "paths", 0, Some("afterok:7003")),
        ("0-999", "paths", 1000, Some("afterok:7003")),
        ("0-499", "paths", 2000, Some("afterok:7003")),
    ];
    assert_eq!(calls.len(), arrays.len() + 1, "{calls:?}");
    for (call, (range, stage, offset, dep)) in calls.iter().zip(arrays) {
        let has = |a: &str| call.iter().any(|c| c == a);
        assert!(has("--parsable") && has(&format!("--array={range}")), "{stage}: {call:?}");
        assert!(
            has(&format!("--job-name=surfcap-{stage}")) && has(&format!("--export=ALL,OFFSET={offset}")),
            "{call:?}"
        );
        assert!(call.iter().any(|c| c.starts_with(&logs)), "logs in the work folder: {call:?}");
        match dep {
            Some(dep) => assert!(has(&format!("--dependency={dep}")) && has("--kill-on-invalid-dep=yes"), "{call:?}"),
            None => assert!(!call.iter().any(|c| c.starts_with("--dependency")), "{call:?}"),
        }
        assert!(has("--partition=cpu"), "the caller's options reach every job: {call:?}");
        let tail = &call[call.len() - 4..];
        assert_eq!(tail, [tiles.as_str(), p(&work), stage, p(&counts)], "{call:?}");
    }
    let m = calls.last().unwrap();
    assert!(
        m.contains(&"--dependency=afterok:7004:7005:7006".to_string()),
        "the merge waits for every paths array: {m:?}"
    );
    assert!(!m.iter().any(|c| c.starts_with("--array")), "{m:?}");
    assert_eq!(&m[m.len() - 3..], [merge.as_str(), p(&work), p(&counts)], "{m:?}");
    assert!(out.contains("merge: job 7007"), "{out}");

    // A missing plan, binary or sbatch is named before anything is submitted.
    std::fs::remove_file(d.path().join("sbatch.log")).unwrap();
    let run = |work: &Path, surfcap: &str, path: String| {
        Command::new("bash")
            .arg(slurm_script("submit.sh"))
            .arg(work)
            .env("PATH", path)
            .env("SURFCAP", surfcap)
            .output()
            .unwrap()
    };
    let o = run(d.path(), p(&counts), path_with(&[&bin]));
    assert!(!o.status.success() && stderr(&o).contains("plan.json is missing"), "{}", stderr(&o));
    let o = run(&work, p(&d.path().join("nothing")), path_with(&[&bin]));
    assert!(!o.status.success() && stderr(&o).contains("no such executable"), "{}", stderr(&o));
    // A PATH with only what submit.sh needs besides sbatch (whatever this machine has installed).
    let bare = d.path().join("bare-bin");
    std::fs::create_dir(&bare).unwrap();
    for tool in ["bash", "dirname", "basename", "mkdir"] {
        let found =
            std::env::split_paths(&std::env::var_os("PATH").unwrap()).map(|d| d.join(tool)).find(|f| f.is_file());
        std::os::unix::fs::symlink(found.unwrap_or_else(|| panic!("{tool} is on PATH")), bare.join(tool)).unwrap();
    }
    let o = run(&work, p(&counts), p(&bare).to_string());
    assert!(!o.status.success() && stderr(&o).contains("sbatch is not on PATH"), "{}", stderr(&o));
    assert!(!d.path().join("sbatch.log").exists(), "nothing was submitted");
}

#[test]
fn slurm_submit_arrays_match_the_real_plan() {
    let d = tempfile::tempdir().unwrap();
    let bin = fake_sbatch(d.path());
    let subject = tiny_subject(d.path(), "worm.subject");
    let work = d.path().join("real.tiles");
    plan(&subject, &work);
    let o = Command::new("bash")
        .arg(slurm_script("submit.sh"))
        .arg(&work)
        .env("PATH", path_with(&[&bin, &binary_dir()]))
        .env_remove("SURFCAP")
        .env_remove("MAX_ARRAY")
        .env_remove("STAGES")
        .output()
        .unwrap();
    ok(&o, "submit.sh");
    let calls = sbatch_calls(d.path());
    let want: Vec<(String, usize)> = stages(&work).into_iter().filter(|s| s.1 > 0).collect();
    assert_eq!(calls.len(), want.len() + 1, "one array per stage with jobs and the merge: {calls:?}");
    for (k, (call, (stage, jobs))) in calls.iter().zip(&want).enumerate() {
        assert!(call.contains(&format!("--array=0-{}", jobs - 1)), "{stage}: {call:?}");
        assert_eq!(call[call.len() - 3..call.len() - 1], [p(&work), stage.as_str()], "{call:?}");
        let dep = (k > 0).then(|| format!("--dependency=afterok:{}", 7000 + k));
        assert_eq!(call.iter().find(|c| c.starts_with("--dependency")), dep.as_ref(), "{call:?}");
        // The binary found on PATH is passed by its absolute path.
        assert_eq!(call.last().unwrap(), SURFCAP, "{call:?}");
    }
    // Stages' jobs agree with `surfcap tiles count`.
    for (stage, jobs) in &want {
        let o = surfcap!(&["tiles", "count", p(&work), "--stage", stage]);
        assert_eq!(ok(&o, "tiles count").trim(), jobs.to_string(), "{stage}");
    }
}

/// A single-node Slurm cluster of Debian's packages (slurmctld, slurmd, slurm-client; installed
/// by scripts/setup) in a temporary folder: its own configuration (`SLURM_CONF`), ports, state,
/// spool and logs, no authentication daemon (`auth/none`, `cred/none`: one machine, one user),
/// processes tracked by process group. Drop cancels its jobs and stops both daemons (SIGTERM,
/// then SIGKILL to their process groups, each started in a group of its own).
struct LocalSlurm {
    dir: tempfile::TempDir,
    daemons: Vec<std::process::Child>,
}

impl LocalSlurm {
    fn conf(&self) -> PathBuf {
        self.dir.path().join("slurm.conf")
    }

    fn command(&self, program: &str) -> Command {
        let mut c = Command::new(program);
        c.env("SLURM_CONF", self.conf()).stdin(Stdio::null());
        c
    }

    fn start() -> LocalSlurm {
        for program in ["slurmctld", "slurmd", "sbatch", "squeue", "sinfo", "scontrol", "scancel"] {
            let found = std::env::split_paths(&std::env::var_os("PATH").unwrap_or_default())
                .chain(["/usr/sbin".into(), "/sbin".into()])
                .any(|d| d.join(program).is_file());
            assert!(
                found,
                "{program} is missing: run scripts/setup (it installs Debian's slurmctld, slurmd, slurm-client)"
            );
        }
        let dir = tempfile::Builder::new().prefix("slurm").tempdir_in("/tmp").unwrap();
        let d = dir.path();
        for sub in ["state", "spool"] {
            std::fs::create_dir(d.join(sub)).unwrap();
        }
        let mut name = [0u8; 256];
        assert_eq!(unsafe { libc::gethostname(name.as_mut_ptr().cast(), name.len()) }, 0);
        let host = String::from_utf8_lossy(&name[..name.iter().position(|&b| b == 0).unwrap()]).into_owned();
        let host = host.split('.').next().unwrap().to_string();
        let user =
            String::from_utf8(Command::new("id").arg("-un").output().unwrap().stdout).unwrap().trim().to_string();
        let meminfo = std::fs::read_to_string("/proc/meminfo").unwrap();
        let mem_mb = meminfo.split_whitespace().nth(1).unwrap().parse::<u64>().unwrap() / 1024;
        let dir_text = p(d);
        let conf = format!(
            "ClusterName=surfcaptest\nSlurmctldHost={host}(127.0.0.1)\nSlurmctldPort={ctld}\nSlurmdPort={slurmd}\n\
             AuthType=auth/none\nCredType=cred/none\nSlurmUser={user}\nSlurmdUser={user}\n\
             StateSaveLocation={dir_text}/state\nSlurmdSpoolDir={dir_text}/spool\n\
             SlurmctldPidFile={dir_text}/slurmctld.pid\nSlurmdPidFile={dir_text}/slurmd.pid\n\
             SlurmctldLogFile={dir_text}/slurmctld.log\nSlurmdLogFile={dir_text}/slurmd.log\n\
             ProctrackType=proctrack/pgid\nTaskPlugin=task/none\nSelectType=select/cons_tres\n\
             SelectTypeParameters=CR_Core\nSchedulerType=sched/builtin\n\
             SchedulerParameters=sched_interval=1,sched_min_interval=200000\nReturnToService=2\nMpiDefault=none\n\
             JobCompType=jobcomp/none\nAccountingStorageType=accounting_storage/none\n\
             JobAcctGatherType=jobacct_gather/none\nSwitchType=switch/none\nMinJobAge=600\n\
             NodeName={host} NodeAddr=127.0.0.1 CPUs=2 RealMemory={mem_mb} State=UNKNOWN\n\
             PartitionName=debug Nodes={host} Default=YES MaxTime=INFINITE State=UP\n",
            ctld = free_port(),
            slurmd = free_port(),
        );
        std::fs::write(d.join("slurm.conf"), conf).unwrap();
        let mut slurm = LocalSlurm { dir, daemons: Vec::new() };
        for daemon in ["slurmctld", "slurmd"] {
            let out = std::fs::File::create(slurm.dir.path().join(format!("{daemon}.out"))).unwrap();
            let child = slurm
                .command(daemon)
                .args(["-D", "-f", p(&slurm.conf())])
                .current_dir(slurm.dir.path())
                .stdout(out.try_clone().unwrap())
                .stderr(out)
                .process_group(0)
                .spawn()
                .unwrap_or_else(|e| panic!("{daemon} starts: {e}"));
            slurm.daemons.push(child);
        }
        let t0 = Instant::now();
        loop {
            let o = slurm.command("sinfo").args(["-h", "-o", "%T"]).output().unwrap();
            if String::from_utf8_lossy(&o.stdout).trim() == "idle" {
                return slurm;
            }
            for (daemon, child) in ["slurmctld", "slurmd"].iter().zip(&mut slurm.daemons) {
                if let Some(status) = child.try_wait().unwrap() {
                    panic!("{daemon} exited ({status}):\n{}", slurm.log(&format!("{daemon}.out")));
                }
            }
            assert!(
                t0.elapsed() < Duration::from_secs(60),
                "the Slurm node is not idle after 60 s:\n{}",
                slurm.log("slurmctld.log")
            );
            std::thread::sleep(Duration::from_millis(300));
        }
    }

    fn log(&self, name: &str) -> String {
        std::fs::read_to_string(self.dir.path().join(name)).unwrap_or_default()
    }

    /// Waits until no job is pending or running.
    fn wait_idle(&self, timeout: Duration) {
        let t0 = Instant::now();
        loop {
            let o = self.command("squeue").args(["-h", "-o", "%i %T %r"]).output().unwrap();
            let queue = String::from_utf8_lossy(&o.stdout).into_owned();
            if o.status.success() && queue.trim().is_empty() {
                return;
            }
            assert!(
                t0.elapsed() < timeout,
                "jobs still queued after {timeout:?}:\n{queue}\n{}",
                self.log("slurmctld.log")
            );
            std::thread::sleep(Duration::from_millis(300));
        }
    }

    /// The states of a job's tasks (every task of an array), from `scontrol show job`.
    fn job_states(&self, id: &str) -> Vec<String> {
        let o = self.command("scontrol").args(["show", "job", id]).output().unwrap();
        ok(&o, &format!("scontrol show job {id}"))
            .split_whitespace()
            .filter_map(|w| w.strip_prefix("JobState=").map(String::from))
            .collect()
    }
}

impl Drop for LocalSlurm {
    fn drop(&mut self) {
        // Only this cluster's jobs: the command reads this cluster's SLURM_CONF.
        let user =
            Command::new("id").arg("-un").output().map(|o| String::from_utf8_lossy(&o.stdout).trim().to_string());
        if let Ok(user) = user {
            let _ = self.command("scancel").args(["--quiet", "--user", &user]).output();
        }
        for child in self.daemons.iter_mut().rev() {
            let pid = child.id() as i32;
            unsafe { libc::kill(pid, libc::SIGTERM) };
            let t0 = Instant::now();
            while t0.elapsed() < Duration::from_secs(10) && !matches!(child.try_wait(), Ok(Some(_))) {
                std::thread::sleep(Duration::from_millis(100));
            }
            unsafe { libc::kill(-pid, libc::SIGKILL) };
            let _ = child.wait();
        }
    }
}

/// Submits WORK with `submit.sh` to the local cluster, waits for every job to leave the queue;
/// returns (stage, jobs, array id) per submitted stage and the merge job's id.
fn submit_and_wait(slurm: &LocalSlurm, work: &Path, surfcap: &Path) -> (Vec<(String, usize, String)>, String) {
    // --mem below the template's 2 GB so the test runs on small machines too.
    let o = slurm
        .command("bash")
        .arg(slurm_script("submit.sh"))
        .args([p(work), "--mem=500M"])
        .env("SURFCAP", surfcap)
        .env_remove("MAX_ARRAY")
        .env_remove("STAGES")
        .output()
        .unwrap();
    let out = ok(&o, "submit.sh");
    slurm.wait_idle(Duration::from_secs(180));
    let ids: Vec<String> = out.lines().map(|l| l.rsplit(' ').next().unwrap().to_string()).collect();
    let want: Vec<(String, usize)> = stages(work).into_iter().filter(|s| s.1 > 0).collect();
    assert_eq!(ids.len(), want.len() + 1, "one array per stage and the merge:\n{out}");
    let arrays = want.into_iter().zip(&ids).map(|((stage, jobs), id)| (stage, jobs, id.clone())).collect();
    (arrays, ids.last().unwrap().clone())
}

#[test]
fn slurm_for_real_on_a_single_node_cluster_stops_at_a_failed_job_then_resumes_to_the_one_process_bytes() {
    let d = tempfile::tempdir().unwrap();
    let subject = tiny_subject(d.path(), "worm.subject");
    let reference = one_process(&subject, d.path());
    let work = d.path().join("slurm.tiles");
    plan(&subject, &work);
    let slurm = LocalSlurm::start();

    // Job 0 of the second stage fails: its array fails, every later stage and the merge are
    // cancelled (afterok never satisfied), nothing is merged.
    let (table, _) = stages(&work)[1].clone();
    let (wrapper, attempts) = failing_wrapper(d.path(), &table, 0, false);
    let t0 = Instant::now();
    let (arrays, merge) = submit_and_wait(&slurm, &work, &wrapper);
    let failing = format!("{table} job 0 failed");
    assert_eq!(std::fs::read_to_string(&attempts).unwrap().lines().count(), 1, "{failing} once");
    for (k, (stage, jobs, id)) in arrays.iter().enumerate() {
        let states = slurm.job_states(id);
        match k {
            0 => assert_eq!(states, vec!["COMPLETED".to_string(); *jobs], "{stage} before the failure"),
            1 => assert!(states.contains(&"FAILED".to_string()), "{stage}: {states:?}"),
            _ => assert!(
                !states.is_empty() && states.iter().all(|s| s == "CANCELLED"),
                "{stage} after {failing}: {states:?}"
            ),
        }
    }
    assert_eq!(slurm.job_states(&merge), ["CANCELLED"], "the merge after {failing}");
    assert!(!work.join("merge.json").exists(), "nothing merged");
    let failed_run = t0.elapsed().as_secs_f64();

    // Submitted again with the real binary: the done jobs exit at once, the rest run, merged.
    let t0 = Instant::now();
    let (arrays, merge) = submit_and_wait(&slurm, &work, Path::new(SURFCAP));
    for (stage, jobs, id) in &arrays {
        assert_eq!(slurm.job_states(id), vec!["COMPLETED".to_string(); *jobs], "{stage} (array {id})");
    }
    assert_eq!(slurm.job_states(&merge), ["COMPLETED"], "the merge job");
    eprintln!("real Slurm: failed run {failed_run:.1} s, resumed run {:.1} s", t0.elapsed().as_secs_f64());
    assert_same_products(&work, &reference, "Slurm");
    drop(slurm);
}
