#!/usr/bin/python3
"""`sirl submit` and `sirl status` without a cluster: the script and manifest it writes, that
`sirl plan --nodes N` and `sirl submit --nodes N` predict the same memory and (up to their two
calibrations) the same time, and one clear line with exit 2 for every wrong use."""
import json
import os
import re
import sys
import tempfile
from pathlib import Path

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import sirl_testing  # noqa: E402


def sirl(*args, expect=0):
    # No Slurm here: an empty slurm.conf makes every Slurm client fail at once (a missing one
    # makes sinfo retry for a minute, which `sirl status` cuts at 20 s).
    p = sirl_testing.run_sirl(*args, timeout=300, env=dict(os.environ, SLURM_CONF="/dev/null"))
    if p.returncode != expect:
        sys.exit(f"FAIL: sirl {' '.join(args)} exited {p.returncode}, expected {expect}\n"
                 f"{p.stdout}\n{p.stderr}")
    return p


def refused(why, *args):
    p = sirl(*args, expect=2)
    lines = [line for line in p.stderr.splitlines() if line.strip()]
    if len(lines) != 1 or why not in lines[0]:
        sys.exit(f"FAIL: sirl {' '.join(args)} should say '{why}' in one line:\n{p.stderr}")


def seconds(text):
    """'1h02m', '3m04s', '12s' → seconds."""
    total = 0
    for n, unit in re.findall(r"(\d+)([hms])", text):
        total += int(n) * {"h": 3600, "m": 60, "s": 1}[unit]
    return total


with tempfile.TemporaryDirectory() as tmp:
    tmp = Path(tmp)
    sub = tmp / "sub"
    p = sirl("submit", "smoke", "--shards", "3", "--cpus-per-task", "2", "--out", str(sub))
    script = (sub / "sirl-smoke.sbatch").read_text()
    assert "#SBATCH --array=0-2" in script and os.access(sub / "sirl-smoke.sbatch", os.X_OK)
    mem = int(re.search(r"--mem=(\d+)M", p.stdout).group(1))
    assert f"#SBATCH --mem={mem}M" in script, script
    assert (sub / "profile.toml").read_text() == sirl("plan", "smoke", "--resolved").stdout
    status = sirl("status", str(sub)).stdout
    assert status.count("not started") == 3 and "(no Slurm)" in status, status
    listed = sirl("status", str(sub), "--tasks").stdout
    counts = [int(n) for n in re.findall(r"^\d+\s+not started\s+0/(\d+)", status, re.M)]
    assert len(counts) == 3, status
    for i, n in enumerate(counts):
        assert f"shard {i}: {n} task(s) not committed" in listed, listed
    assert "grid/s0/sirl/N100/rep" in listed and "(checkpoint saved)" not in listed, listed
    # --json: the same shards, states and open tasks.
    js = json.loads(sirl("status", str(sub), "--json").stdout)
    assert [sh["state"] for sh in js["shards"]] == ["not started"] * 3, js["shards"]
    assert [sh["tasks"] for sh in js["shards"]] == counts, (js["shards"], counts)
    assert [len(sh["open_tasks"]) for sh in js["shards"]] == counts
    assert js["profile"] == "smoke" and js["queue_known"] is False, js
    print(f"ok: an array of 3 shards written (--mem={mem}M); status: 3 not started (text and --json)")

    plan = sirl("plan", "smoke", "--nodes", "2", "--cores-per-node", "4").stdout
    mpi = sirl("submit", "smoke", "--nodes", "2", "--cores-per-node", "4", "--out",
               str(tmp / "mpi")).stdout
    plan_mem = re.search(r"memory per node: (\d+) MiB", plan).group(1)
    sub_mem = re.search(r"memory per node (\d+) MiB", mpi).group(1)
    plan_t = seconds(re.search(r"predicted makespan: (\S+)", plan).group(1))
    sub_t = seconds(re.search(r"predicted: (\S+) on 2 node", mpi).group(1))
    if plan_mem != sub_mem or abs(plan_t - sub_t) > 0.25 * max(plan_t, sub_t) + 1:
        sys.exit(f"FAIL: plan and submit disagree: memory {plan_mem} vs {sub_mem} MiB, time "
                 f"{plan_t} vs {sub_t} s\n{plan}\n{mpi}")
    print(f"ok: plan and submit --nodes 2 agree: {plan_mem} MiB per node, {plan_t} s vs {sub_t} s")

    refused("give no PROFILE", "submit", "smoke", "--rerun-failed", "--out", str(sub))
    refused("and no --set", "submit", "--rerun-failed", "--set", "seeds=[0]", "--out", str(sub))
    refused("--rerun-failed needs --out", "submit", "--rerun-failed")
    refused("no Slurm answers here", "submit", "--rerun-failed", "--out", str(sub))
    refused("name a profile", "submit")
    refused("give one of them", "submit", "smoke", "--nodes", "2", "--shards", "3")
    refused("give one of them", "submit", "smoke", "--mpi", "--shards", "4")
    refused("holds no submission", "status", str(tmp))
    refused("another profile", "submit", "quick", "--out", str(sub))
    hostile = tmp / "hostile.toml"  # a name that would add a line to the script and leave DIR
    hostile.write_text('extends = "smoke"\nname = "x\\ntouch /tmp/pwned/y"\n')
    refused("cannot name a Slurm job", "submit", str(hostile), "--out", str(tmp / "hostile"))
    (sub / "submission.toml").write_text("profile = 'smoke'\nshards = [")
    refused("is not a submission manifest", "status", str(sub))
    print("ok: wrong uses refused in one line (exit 2)")
