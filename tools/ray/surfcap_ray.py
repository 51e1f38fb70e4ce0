#!/usr/bin/env python3
"""Runs a tiled surfcap work folder on a Ray cluster.

    tools/venv/bin/python tools/ray/surfcap_ray.py WORK --surfcap PATH [--address ADDR]
        [--retries 3] [--cpus-per-job 1]

WORK is a folder made by `surfcap tiles plan SUBJECT -o WORK`. For each stage of its
`plan.json`, in order, every job of the stage is submitted as a Ray task that runs
`surfcap tiles run WORK --stage S --index I` (with RAYON_NUM_THREADS = --cpus-per-job); a
stage starts when every job of the previous one has succeeded. A failed job (non-zero exit)
raises with its stderr and Ray retries it up to --retries times. When every stage is done,
`surfcap tiles merge WORK` runs here, in the driver.

Every worker must see WORK and the binary at the same paths (a shared file system); jobs are
idempotent and write atomically, so a retried or re-run job is safe and an interrupted run
resumes where it stopped.

Prints a JSON summary on stdout: jobs and failed attempts per stage, retries, wall time.
Exit 0 when merged; 1 when a job still fails after its retries (the jobs named), when merge
fails, or on bad arguments (plan or binary missing).

Ray comes from PyPI (tools/requirements.txt, installed into tools/venv by scripts/setup);
surfcap itself never needs Python.
"""

import argparse
import json
import os
import shutil
import socket
import subprocess
import sys
import time


def fail(message):
    print(f"surfcap_ray: error: {message}", file=sys.stderr)
    sys.exit(1)


def read_plan(work):
    plan_path = os.path.join(work, "plan.json")
    if not os.path.isfile(plan_path):
        fail(f"{plan_path} is missing: make the work folder with `surfcap tiles plan SUBJECT -o {work}` first")
    try:
        with open(plan_path, encoding="utf-8") as f:
            plan = json.load(f)
    except (OSError, ValueError) as e:
        fail(f"{plan_path}: not a readable tiles plan ({e})")
    stages = plan.get("stages") if isinstance(plan, dict) else None
    if not isinstance(stages, list) or not stages:
        fail(f"{plan_path}: expected a \"stages\" list of {{\"name\", \"jobs\"}}")
    for s in stages:
        ok = isinstance(s, dict) and isinstance(s.get("name"), str) and isinstance(s.get("jobs"), int)
        if not ok or s["jobs"] < 0:
            fail(f"{plan_path}: stage {s!r}: expected {{\"name\": text, \"jobs\": count >= 0}}")
    return stages


def find_binary(path):
    found = path if os.sep in path else shutil.which(path)
    if not found or not os.path.isfile(found):
        fail(f"--surfcap {path}: no such program (give the path of the surfcap binary, e.g. target/release/surfcap)")
    if not os.access(found, os.X_OK):
        fail(f"--surfcap {found}: not executable")
    return os.path.abspath(found)


def parse_args(argv):
    a = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    a.add_argument("work", metavar="WORK", help="work folder made by `surfcap tiles plan`")
    a.add_argument("--surfcap", default="surfcap", help="the surfcap binary, same path on every worker (default: surfcap on PATH)")
    a.add_argument("--address", default=None, help="Ray cluster address, e.g. 10.0.0.1:6379 or auto (default: a local Ray started for this run)")
    a.add_argument("--retries", type=int, default=3, help="retries of a failed job (default: 3)")
    a.add_argument("--cpus-per-job", type=int, default=1, help="CPUs Ray reserves per job, also its RAYON_NUM_THREADS (default: 1)")
    args = a.parse_args(argv)
    if args.retries < 0:
        a.error(f"--retries {args.retries}: expected a count >= 0")
    if args.cpus_per_job < 1:
        a.error(f"--cpus-per-job {args.cpus_per_job}: expected a count >= 1")
    return args


def main(argv):
    args = parse_args(argv)
    work = os.path.abspath(args.work)
    if not os.path.isdir(work):
        fail(f"{work}: no such work folder (make it with `surfcap tiles plan SUBJECT -o {work}`)")
    stages = read_plan(work)
    surfcap = find_binary(args.surfcap)
    try:
        import ray
    except ImportError:
        fail("the ray package is missing: run scripts/setup (it installs tools/requirements.txt into tools/venv) and use tools/venv/bin/python")

    # stdout carries only the summary: Ray prints its own messages (e.g. "Task run_job failed ...
    # will be retried") to the driver's stdout, so everything else goes to stderr.
    summary_out = os.fdopen(os.dup(sys.stdout.fileno()), "w")
    sys.stdout.flush()
    os.dup2(sys.stderr.fileno(), sys.stdout.fileno())
    sys.stdout = sys.stderr

    # Silences a FutureWarning of Ray 2.52 about GPU variables; surfcap uses no GPU.
    os.environ.setdefault("RAY_ACCEL_ENV_VAR_OVERRIDE_ON_ZERO", "0")
    started = time.monotonic()
    init = {"logging_level": "warning", "log_to_driver": False}
    if args.address:
        ray.init(address=args.address, **init)
    else:
        ray.init(include_dashboard=False, **init)

    # Failed attempts, as the tasks report them before raising: Ray retries a task that raised
    # without telling the driver, so the tasks tell this actor (num_cpus=0: it holds no CPU).
    @ray.remote(num_cpus=0)
    class Attempts:
        def __init__(self):
            self.failures = []

        def failed(self, stage, index, message):
            self.failures.append({"stage": stage, "index": index, "message": message})

        def all(self):
            return self.failures

    @ray.remote
    def run_job(binary, work_dir, stage, index, threads, attempts):
        env = dict(os.environ, RAYON_NUM_THREADS=str(threads))
        t0 = time.monotonic()
        p = subprocess.run(
            [binary, "tiles", "run", work_dir, "--stage", stage, "--index", str(index)],
            env=env,
            stdin=subprocess.DEVNULL,
            capture_output=True,
            text=True,
        )
        if p.returncode != 0:
            message = f"job {stage} {index} failed on {socket.gethostname()} (exit {p.returncode}): {p.stderr.strip()}"
            ray.get(attempts.failed.remote(stage, index, message))
            raise RuntimeError(message)
        return time.monotonic() - t0

    attempts = Attempts.remote()
    task = run_job.options(num_cpus=args.cpus_per_job, max_retries=args.retries, retry_exceptions=True)
    summary = {"work": work, "address": args.address, "retries_allowed": args.retries, "cpus_per_job": args.cpus_per_job, "stages": []}
    failed_jobs = []
    for s in stages:
        name, jobs = s["name"], s["jobs"]
        t0 = time.monotonic()
        refs = {task.remote(surfcap, work, name, i, args.cpus_per_job, attempts): i for i in range(jobs)}
        job_seconds = []
        pending = list(refs)
        while pending:
            done, pending = ray.wait(pending, num_returns=1)
            try:
                job_seconds.append(ray.get(done[0]))
            except Exception as e:  # the task's RuntimeError after its last retry
                cause = getattr(e, "cause", None) or e
                failed_jobs.append({"stage": name, "index": refs[done[0]], "error": str(cause).strip()})
        summary["stages"].append({
            "name": name,
            "jobs": jobs,
            "seconds": round(time.monotonic() - t0, 3),
            "max_job_seconds": round(max(job_seconds, default=0.0), 3),
        })
        if failed_jobs:
            break

    failures = ray.get(attempts.all.remote())
    for st in summary["stages"]:
        st["failed_attempts"] = sum(1 for f in failures if f["stage"] == st["name"])
    # A retry is a failed attempt that Ray ran again: every failure except each abandoned job's last.
    summary["retries"] = len(failures) - len(failed_jobs)
    summary["retried_jobs"] = sorted({f"{f['stage']} {f['index']}" for f in failures})
    ray.shutdown()

    if failed_jobs:
        summary["failed_jobs"] = failed_jobs
        summary["wall_seconds"] = round(time.monotonic() - started, 3)
        print(json.dumps(summary, indent=2), file=summary_out, flush=True)
        names = ", ".join(f"{j['stage']} {j['index']}" for j in failed_jobs)
        fail(f"{len(failed_jobs)} job(s) still failed after {args.retries} retries: {names}; "
             f"not merged. Last error: {failed_jobs[-1]['error']}")

    t0 = time.monotonic()
    m = subprocess.run([surfcap, "tiles", "merge", work], stdin=subprocess.DEVNULL, capture_output=True, text=True)
    if m.returncode != 0:
        fail(f"`{surfcap} tiles merge {work}` failed (exit {m.returncode}): {m.stderr.strip()}")
    summary["merge_seconds"] = round(time.monotonic() - t0, 3)
    summary["wall_seconds"] = round(time.monotonic() - started, 3)
    print(json.dumps(summary, indent=2), file=summary_out, flush=True)


if __name__ == "__main__":
    main(sys.argv[1:])
