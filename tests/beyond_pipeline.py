#!/usr/bin/python3
"""The questions beyond the paper end to end (ctest; Debian's python3 + h5py + pandas):

- a small profile with active variants (sirl@vote, sirl@infogain) and noisy-teacher axes
  (β, mistake, attend) runs; its tables are bit-identical for --threads 1 and 2, and a run killed
  mid-way resumes to the same tables;
- /tables/robust_fpe and robust_tpa hold one row per (teacher, method, seed), with each teacher's
  measured answer error where the noise model puts it (β = 0: about 2/3 of triplets and 1/2 of
  labels wrong); VAE and Random have no FPE rows (their φ learns from no answers) but TPA rows;
- plot_figures draws fig_active and fig_robustness_<env> and what they drew (figures.json)
  equals the means recomputed here from the tables; the report has both sections;
- N* by hand: the interpolation, and "never reached" as > top N.
"""
import json
import os
import signal
import subprocess
import sys
import tempfile
import time

import h5py
import pandas as pd

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import sirl_testing  # noqa: E402

SIRL = sirl_testing.sirl_binary()
SRC = sirl_testing.source_dir()
sys.path.insert(0, os.path.join(SRC, "report"))
import plot_beyond  # noqa: E402

PROFILE = """
name = "beyond-test"
envs = ["grid"]
seeds = [0, 1, 2]
[queries]
similarity = 200
preference = 200
tpa_pairs = 100
fpe_trajectories = 400
[teacher]
beta = ["inf", 5, 0]
mistake = [0.25]
attend = [0.5]
[fpe]
methods = ["sirl", "sirl@vote", "sirl@infogain"]
N = [50, 100, 200]
[tpa]
methods = ["sirl", "sirl@vote"]
N = [200]
M = [40]
[robustness]
methods = ["sirl", "multipref10", "vae", "random"]
N = [200]
M = [40]
[active]
members = 3
pool = 300
batch = 25
round_epochs = 10
[hyper.grid]
"sirl.epochs" = 40
"vae.epochs" = 3
"pref.epochs" = 20
"tpa.epochs" = 20
"""


fail = sirl_testing.make_fail("beyond_pipeline")


def run(*args):
    p = sirl_testing.run_sirl(*args)
    if p.returncode != 0:
        fail(f"sirl {' '.join(args)} exited {p.returncode}\n{p.stdout}\n{p.stderr}")
    return p


def tables(path):
    with h5py.File(path, "r") as f:
        out = {}
        for k in ("fpe", "tpa", "robust_fpe", "robust_tpa"):
            df = pd.DataFrame(f["tables/" + k][:])
            for c in df.columns:
                if df[c].dtype == object:
                    df[c] = df[c].str.decode("utf-8")
            out[k] = df.sort_values(list(df.columns[:8])).reset_index(drop=True)
        return out


def same(a, b, what):
    for k in a:
        if not a[k].equals(b[k]):
            fail(f"{what}: /tables/{k} differs")


def n_star_by_hand():
    Ns = [100, 250, 500, 1000]
    # 0.04 at 250, 0.03 at 500: 0.035 is reached half-way, at 375.
    got = plot_beyond.n_star(Ns, [0.05, 0.04, 0.03, 0.02], 0.035)
    if abs(got - 375) > 1e-9:
        fail(f"N* interpolation: {got}, expected 375")
    if plot_beyond.n_star(Ns, [0.03, 0.02, 0.01, 0.0], 0.035) != 100:
        fail("N* when the first point already matches should be the first N")
    if plot_beyond.n_star(Ns, [0.05, 0.05, 0.05, 0.05], 0.035) != float("inf"):
        fail("N* never reached should be inf")


def main():
    n_star_by_hand()
    with tempfile.TemporaryDirectory() as tmp:
        prof = os.path.join(tmp, "beyond-test.toml")
        with open(prof, "w") as fh:
            fh.write(PROFILE)
        one, two = os.path.join(tmp, "one.h5"), os.path.join(tmp, "two.h5")
        run("run", prof, "--out", one, "--threads", "1", "--quiet")
        run("run", prof, "--out", two, "--threads", "2", "--quiet")
        T = tables(one)
        same(T, tables(two), "--threads 1 vs 2")

        # Killed mid-way, then resumed: the same tables.
        killed = os.path.join(tmp, "killed.h5")
        p = subprocess.Popen([SIRL, "run", prof, "--out", killed, "--threads", "2", "--quiet",
                              "--checkpoint-minutes", "0"], stdin=subprocess.DEVNULL)
        tasks = killed + ".tasks"
        deadline = time.time() + 120
        while time.time() < deadline and p.poll() is None:
            if os.path.isdir(tasks) and len([n for n in os.listdir(tasks) if n.endswith(".h5")]) >= 25:
                break
            time.sleep(0.05)
        if p.poll() is not None:
            fail("the run ended before it could be killed mid-way (nothing resumed)")
        p.send_signal(signal.SIGKILL)
        p.wait()
        run("run", prof, "--out", killed, "--quiet")
        same(T, tables(killed), "killed + resumed vs fresh")

        rf, rt = T["robust_fpe"], T["robust_tpa"]
        teachers = {"beta=5", "beta=0", "mistake=0.25", "attend=0.5"}
        if set(rf.teacher) != teachers or set(rt.teacher) != teachers:
            fail(f"robustness teachers: {set(rf.teacher)}, {set(rt.teacher)}")
        if len(rf) != 4 * 2 * 3:  # teachers × query methods × seeds
            fail(f"robust_fpe has {len(rf)} rows, expected 24")
        if set(rf.variant) != {"sirl", "multipref10"}:
            fail(f"robust_fpe variants {set(rf.variant)}: VAE/Random FPE cannot depend on a teacher")
        if len(rt) != 4 * 4 * 3:
            fail(f"robust_tpa has {len(rt)} rows, expected 48")
        coin = rf[rf.teacher == "beta=0"]
        if not (0.55 < coin.similarity_error.mean() < 0.8 and 0.4 < coin.preference_error.mean() < 0.6):
            fail(f"β = 0 answer errors {coin.similarity_error.mean()}, {coin.preference_error.mean()}")
        slips = rf[rf.teacher == "mistake=0.25"]
        if not 0.15 < slips.preference_error.mean() < 0.35:
            fail(f"mistake 0.25: preference error {slips.preference_error.mean()}")
        if not (rf[rf.teacher == "beta=5"].level == 5).all() or \
                set(rf[rf.teacher == "attend=0.5"].axis) != {"attend"}:
            fail("axis / level columns do not describe the teacher")
        # One seed's answer errors are one bundle's: equal across every method of that seed.
        if rt.groupby(["teacher", "seed"]).similarity_error.nunique().max() != 1:
            fail("a teacher's answer error differs between cells of one seed")

        figs = os.path.join(tmp, "figs")
        p = subprocess.run(["/usr/bin/python3", os.path.join(SRC, "report", "plot_figures.py"),
                            one, "--out", figs], capture_output=True, text=True)
        if p.returncode != 0:
            fail(f"plot_figures exited {p.returncode}\n{p.stderr}")
        for name in ("fig_active.png", "fig_robustness_grid.png"):
            if not os.path.getsize(os.path.join(figs, name)):
                fail(f"{name} missing")
        drawn = json.load(open(os.path.join(figs, "figures.json")))
        fpe = T["fpe"]
        for v in ("sirl", "sirl@vote", "sirl@infogain"):
            for n in (50, 100, 200):
                want = fpe[(fpe.variant == v) & (fpe.N == n)].fpe.mean()
                got = drawn["fig_active"]["grid"][v][str(n)]
                if abs(got - want) > 1e-12:
                    fail(f"fig_active {v} N={n}: drew {got}, the table says {want}")
        fr = drawn["fig_robustness"]["grid"]
        # The paper's TPA protocol only (a file without the column holds nothing else).
        paper = lambda d: d[d.protocol == "paper"] if "protocol" in d else d  # noqa: E731
        for teacher, axis, tick in (("beta=0", "beta", "0"), ("mistake=0.25", "mistake", "0.25")):
            rp = paper(rt)
            want = rp[(rp.teacher == teacher) & (rp.variant == "random")].tpa.mean()
            if abs(fr["tpa"][axis]["random"][tick] - want) > 1e-12:
                fail(f"fig_robustness TPA {teacher}: drew {fr['tpa'][axis]['random'][tick]}, want {want}")
            ref = paper(T["tpa"])
            want0 = ref[(ref.variant == "random") & (ref.M == 40) & (ref.frozen == 0)].tpa.mean()
            if abs(fr["tpa"][axis]["random"]["perfect"] - want0) > 1e-12:
                fail("fig_robustness: the perfect teacher's point is not the main grid's cell")
        report = open(os.path.join(figs, "report.md")).read()
        for h in ("## Beyond the paper: active similarity queries",
                  "## Beyond the paper: robustness to noisy teachers", "| grid | vote |"):
            if h not in report:
                fail(f"report.md lacks {h!r}")
        # The dead-units table: one row per (env, method variant), whatever teachers the φ
        # learned from (a noisy teacher's name is no method), and every variant the run trained.
        sec = report.split("## Dead units", 1)[1].split("\n## ", 1)[0]
        rows = [ln.split("|")[1:3] for ln in sec.splitlines() if ln.startswith("| grid |")]
        got = [v.strip() for _, v in rows]
        # Methods only: the references (truth φ*, raw input) train no φ, so have no dead units.
        meths = lambda d: set(d[d.reference == 0].variant if "reference" in d else d.variant)  # noqa: E731
        want = sorted(meths(T["tpa"]) | meths(T["fpe"]))
        if sorted(got) != want:
            fail(f"dead units: variants {sorted(got)}, expected one row each of {want}")
    print("beyond_pipeline: OK")


if __name__ == "__main__":
    main()
