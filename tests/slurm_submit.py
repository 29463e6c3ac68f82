#!/usr/bin/python3
"""`sirl submit` on a real one-node Slurm (tests/one_node_slurm.py), three ways:
1. a job array of 3 shards, one of which fails (its output path is a folder): `sirl status` names
   it, `sirl merge` refuses the gap and `--partial` writes it with the missing tasks listed,
   `sirl submit --rerun-failed` resubmits exactly that shard, and the merged file equals a
   single run's (tables and weights);
2. one training interrupted twice mid-training: by the time-limit warning (SIGUSR1 to the batch
   shell: sirl saves and the script requeues the job) and by `scontrol requeue` (SIGTERM, as a
   pre-emption): each requeued job continues from the epoch the last one saved, and the result
   equals an uninterrupted run's bits;
3. the MPI variant (one allocation, `mpirun` inside): a worker rank's training saves on the
   warning, the job requeues itself and continues it to the same bits.
Needs root and Debian's slurmctld, slurmd and munge (scripts/setup.sh --tests); skipped (77)
without them, except under CI."""
import os
import re
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import h5py
import numpy as np
import pandas as pd

sys.path.insert(0, str(Path(__file__).resolve().parent))
import sirl_testing  # noqa: E402
from one_node_slurm import OneNodeSlurm, missing_programs  # noqa: E402

SIRL = os.environ["SIRL"]
SRC = Path(os.environ["SIRL_SOURCE_DIR"])
DATA = SRC / "tests" / "data"
ENGINE_TEST, SLOW = str(DATA / "engine-test.toml"), str(DATA / "slow-training.toml")


fail = sirl_testing.make_fail("slurm_submit")


def skip_or_fail(why):
    if os.environ.get("CI"):
        fail(why + " (CI must run this test: scripts/setup.sh --tests installs Slurm)")
    print("SKIP: " + why)
    sys.exit(77)


def load(path):
    with h5py.File(path, "r") as f:
        t = {k: pd.DataFrame(f["tables/" + k][:]) for k in ("fpe", "tpa", "training")}
        keys = [k.decode() for k in f["runs_index"][:]]
        w = {k: f[f"runs/{k}/params"][:] for k in keys if f"runs/{k}/params" in f}
        return t, w, dict(f.attrs)


def same_results(a, b, what):
    (ta, wa, _), (tb, wb, _) = load(a), load(b)
    for k in ta:
        if not ta[k].equals(tb[k]):
            fail(f"{what}: table {k} differs\n{ta[k].compare(tb[k]) if ta[k].shape == tb[k].shape else ''}")
    if wa.keys() != wb.keys() or not all(np.array_equal(wa[k], wb[k]) for k in wa):
        fail(f"{what}: weights differ")
    return len(ta["tpa"]), len(wa)


# Open MPI as root, on loopback (the job inherits this environment from sbatch).
MPI_ENV = dict(OMPI_ALLOW_RUN_AS_ROOT="1", OMPI_ALLOW_RUN_AS_ROOT_CONFIRM="1", OMPI_MCA_btl="self,tcp",
               OMPI_MCA_btl_tcp_if_include="lo", OMPI_MCA_oob_tcp_if_include="lo")


def sirl(s, *args, expect=0):
    s.env.update(MPI_ENV)
    p = s.run(SIRL, *args, check=False, timeout=600)
    if p.returncode != expect:
        fail(f"sirl {' '.join(args)} exited {p.returncode}, expected {expect}\n{p.stdout}\n{p.stderr}")
    return p


def job_id(submit_output):
    m = re.search(r"(?:submitted: job|as job) (\d+)", submit_output)
    if not m:
        fail("no job id in:\n" + submit_output)
    return m.group(1)


def wait_for(what, predicate, s, timeout=300):
    deadline = time.time() + timeout
    while time.time() < deadline:
        if predicate():
            return
        time.sleep(0.3)
    fail(f"timed out waiting for {what}\nqueue: {s.queue()}\n{s.logs()}")


def array_with_a_failed_shard(s, tmp):
    single = tmp / "single.h5"  # the reference: the engine-test fixture's file, or computed
    if not sirl_testing.copy_fixture("engine-test", str(single), with_cache=False):
        sirl(s, "run", ENGINE_TEST, "--out", str(single), "--threads", "2", "--quiet")
    sub = tmp / "array"
    (sub / "shard-1.h5").mkdir(parents=True)  # shard 1's output is a folder: `sirl run` refuses it
    p = sirl(s, "submit", ENGINE_TEST, "--shards", "3", "--cpus-per-task", "1", "--out", str(sub),
             "--now")
    first = job_id(p.stdout)
    script = (sub / "sirl-engine-test.sbatch").read_text()
    for line in ("#SBATCH --array=0-2", "#SBATCH --cpus-per-task=1", "#SBATCH --requeue",
                 "#SBATCH --open-mode=append", "#SBATCH --signal=B:USR1@300"):
        if line not in script:
            fail(f"the script lacks '{line}':\n{script}")
    if not re.search(r"#SBATCH --mem=\d+M", script) or f"--output={sub}/logs/" not in script:
        fail("the script lacks --mem or logs under the submission folder:\n" + script)
    s.wait_idle()
    status = sirl(s, "status", str(sub)).stdout
    rows = {int(line.split()[0]): line for line in status.splitlines() if line[:1].isdigit()}
    if "complete" not in rows[0] or "complete" not in rows[2] or "failed (2)" not in rows[1]:
        fail("status should show shards 0, 2 complete and 1 failed (2):\n" + status)
    if "not complete and not queued: 1 " not in status:
        fail("status should name shard 1 to rerun:\n" + status)
    shards = [str(sub / f"shard-{i}.h5") for i in (0, 2)]
    p = sirl(s, "merge", str(tmp / "gap.h5"), *shards, expect=2)
    if "are in none of the inputs" not in p.stderr:
        fail("merge without --partial should refuse the gap:\n" + p.stderr)
    sirl(s, "merge", "--partial", str(tmp / "partial.h5"), *shards)
    with h5py.File(tmp / "partial.h5", "r") as f:
        missing = f.attrs["missing_tasks"].split()
        present = {k.decode() for k in f["runs_index"][:]}
        if f.attrs["complete"] != 0 or not missing or present & set(missing):
            fail("the partial merge should list its missing tasks, none of them present")
    # The report of the partial merge marks the verdicts that rest on missing cells.
    figs = tmp / "partial-figures"
    r = subprocess.run(["/usr/bin/python3", str(SRC / "report" / "plot_figures.py"),
                        str(tmp / "partial.h5"), "--out", str(figs)], capture_output=True,
                       text=True, timeout=600)
    if r.returncode != 0:
        fail(f"plot_figures on the partial merge exited {r.returncode}\n{r.stderr}")
    report = (figs / "report.md").read_text()
    if "⧗ **Partial merge**" not in report or "** ⧗ |" not in report:
        fail("the partial merge's report should mark its verdicts ⧗:\n" + report[:3000])
    print(f"ok: shard 1 failed, status named it; merge refused the gap; --partial lists "
          f"{len(missing)} missing tasks and its report marks the verdicts resting on them")

    (sub / "shard-1.h5").rmdir()
    p = sirl(s, "submit", "--rerun-failed", "--out", str(sub))
    if "resubmitted shards 1 as job" not in p.stdout:
        fail("--rerun-failed should resubmit shard 1 alone:\n" + p.stdout)
    again = job_id(p.stdout)
    elements = [j for j in s.queue() if j.startswith(again + "_") or j == again]
    if elements and elements != [f"{again}_1"]:
        fail(f"the rerun should be array index 1 only, Slurm has {elements}")
    s.wait_idle()
    starts = {i: (sub / "state" / f"shard-{i}.log").read_text().count("start ") for i in range(3)}
    if starts != {0: 1, 1: 2, 2: 1}:
        fail(f"only shard 1 should have run twice: {starts}")
    status = sirl(s, "status", str(sub)).stdout
    if "3 of 3 complete" not in status:
        fail("every shard should be complete now:\n" + status)
    merged = tmp / "merged.h5"
    sirl(s, "merge", str(merged), *[str(sub / f"shard-{i}.h5") for i in range(3)])
    rows, weights = same_results(single, merged, "array of 3 shards vs single run")
    print(f"ok: job {first} (3 shards) + rerun {again} (shard 1) merged == single run: {rows} TPA "
          f"rows, {weights} weight arrays")


def training_requeued_twice(s, tmp):
    ref = tmp / "uninterrupted.h5"
    sirl(s, "run", SLOW, "--out", str(ref), "--threads", "1", "--quiet", "--checkpoint-minutes", "-1")
    sub = tmp / "requeue"
    p = sirl(s, "submit", SLOW, "--shards", "1", "--cpus-per-task", "1", "--checkpoint-minutes",
             "0", "--out", str(sub), "--now")
    job = job_id(p.stdout) + "_0"
    checkpoints = sub / "tasks" / "checkpoints"
    log = sub / "state" / "shard-0.log"
    saved = lambda: checkpoints.is_dir() and any(checkpoints.glob("*.h5"))  # noqa: E731
    wait_for("the training's first checkpoint", lambda: s.queue().get(job) == "RUNNING" and saved(), s)
    # The warning Slurm sends to the batch shell before the time limit (--signal=B:USR1@N).
    s.run("scancel", "--batch", "--signal=USR1", job)
    wait_for("the job to requeue itself and continue",
             lambda: log.exists() and log.read_text().count("start ") == 2, s)
    time.sleep(3)  # a few seconds into the continued training
    wait_for("the continued training's next checkpoint", saved, s)
    s.run("scontrol", "requeue", job)  # a pre-emption: SIGTERM to every process of the job
    s.wait_idle()
    out = "".join(f.read_text() for f in (sub / "logs").glob("*.out"))
    stops = [int(e) for e in re.findall(r"saved at epoch (\d+); stopping", out)]
    resumes = [int(e) for e in re.findall(r"continues from its checkpoint at epoch (\d+)", out)]
    if len(stops) != 2 or resumes != stops or not 0 < stops[0] < stops[1]:
        fail(f"each requeued job should continue from the epoch the last one saved: saved at "
             f"{stops}, continued from {resumes}\n{out}")
    exits = re.findall(r"^exit (\d+)", log.read_text(), re.M)
    if exits != ["75", "75", "0"]:
        fail(f"the job should stop twice (exit 75) and then finish: {exits}")
    merged = tmp / "requeued.h5"
    sirl(s, "merge", str(merged), str(sub / "shard-0.h5"))
    same_results(ref, merged, "a training requeued twice vs uninterrupted")
    print(f"ok: stopped at epochs {stops[0]} (SIGUSR1, self-requeue) and {stops[1]} (scontrol "
          f"requeue), continued from each; the result equals an uninterrupted run")


def mpi_run_requeued(s, tmp):
    """The MPI variant: one allocation, rank 0 dispatching to a worker rank; the worker's training
    saves into the submission's cache on the warning and the requeued job continues it."""
    ref = tmp / "uninterrupted.h5"  # written by training_requeued_twice
    sub = tmp / "mpi"
    p = sirl(s, "submit", SLOW, "--mpi", "--cores-per-node", "2", "--checkpoint-minutes", "0",
             "--out", str(sub), "--now")
    job = job_id(p.stdout)
    script = (sub / "sirl-slow-training.sbatch").read_text()
    for line in ("#SBATCH --nodes=1", "#SBATCH --ntasks-per-node=2", "mpirun --bind-to none"):
        if line not in script:
            fail(f"the MPI script lacks '{line}':\n{script}")
    checkpoints = sub / "tasks" / "checkpoints"
    wait_for("the worker's first checkpoint", lambda: s.queue().get(job) == "RUNNING" and
             checkpoints.is_dir() and any(checkpoints.glob("*.h5")), s)
    s.run("scancel", "--batch", "--signal=USR1", job)
    s.wait_idle()
    out = "".join(f.read_text() for f in (sub / "logs").glob("*.out"))
    stops = re.findall(r"saved at epoch (\d+); stopping", out)
    resumes = re.findall(r"continues from its checkpoint at epoch (\d+)", out)
    if len(stops) != 1 or resumes != stops:
        fail(f"the worker should save once and the requeued job continue from there: saved at "
             f"{stops}, continued from {resumes}\n{out}")
    sirl(s, "merge", str(tmp / "mpi.h5"), str(sub / "slow-training.h5"))
    same_results(ref, tmp / "mpi.h5", "MPI run requeued vs uninterrupted")
    print(f"ok: MPI job stopped at epoch {stops[0]} (SIGUSR1 through mpirun), requeued itself, "
          f"continued to the uninterrupted run's bits")


def main():
    if os.geteuid() != 0:
        skip_or_fail("a one-node Slurm is started as root")
    if missing_programs():
        skip_or_fail("not installed: " + ", ".join(missing_programs()))
    t0 = time.time()
    with tempfile.TemporaryDirectory(prefix="sirl-submit-") as tmp, OneNodeSlurm() as s:
        array_with_a_failed_shard(s, Path(tmp))
        training_requeued_twice(s, Path(tmp))
        mpi_run_requeued(s, Path(tmp))
    print(f"ok: Slurm tests in {time.time() - t0:.0f} s")


main()
