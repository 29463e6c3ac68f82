#!/usr/bin/python3
"""bench/stop_equivalence.py --rule shadow end to end on tests/data/stop-equivalence-shadow-tiny.toml
(GridRobot frozen cells of SIRL and Random, and truth's, at toy scale; one run, every head every
epoch, the converged rule watched by tpa.shadow_rel_tol): exit 0 with one verdict row per method
and every head checked. Then against an independent run: the same profile with the rule applied
(tpa.stop = "converged" at the shadow's tolerance) must give, cell by cell, the TPA and each
head's held-out accuracy and stopping epoch that the watched run recorded as its shadow. Last,
that the script's check can fail: a rule that says otherwise is refused."""
import importlib.util
import json
import os
import subprocess
import sys
import tempfile

SRC = os.environ["SIRL_SOURCE_DIR"]
SIRL = os.environ["SIRL"]
SCRIPT = os.path.join(SRC, "bench", "stop_equivalence.py")
PROFILE = os.path.join(SRC, "tests", "data", "stop-equivalence-shadow-tiny.toml")
PY = "/usr/bin/python3"
SEEDS, CELLS_PER_SEED, HEADS = 3, 3 * 2, 20  # sirl, random, truth at M = 10 and 30

sys.path.insert(0, os.path.join(SRC, "python"))
import sirl_bench  # noqa: E402

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import sirl_testing  # noqa: E402


fail = sirl_testing.make_fail("stop_equivalence_shadow_tiny")


def main():
    with tempfile.TemporaryDirectory(prefix="stop-equivalence-shadow-") as out:
        p = subprocess.run([PY, SCRIPT, "--rule", "shadow", "--profile", PROFILE, "--out", out,
                            "--sirl", SIRL], capture_output=True, text=True, timeout=240)
        if p.returncode != 0:
            fail("the script failed", p)
        with open(os.path.join(out, "stop-equivalence.json"), encoding="utf-8") as f:
            j = json.load(f)
        want = SEEDS * CELLS_PER_SEED * HEADS
        if j["heads_checked"] != want:
            fail(f"{j['heads_checked']} heads checked, not {want}", p)
        methods = sorted(r["method"] for r in j["rows"])
        if methods != ["random", "sirl", "truth"]:
            fail(f"verdict rows for {methods}, not random, sirl and truth", p)
        if not all(r["seeds"] == SEEDS for r in j["rows"]):
            fail("a verdict row is not over the three seeds", p)
        c = j["cost"]
        if not c["converged"]["tpa_flops"] < c["fixed"]["tpa_flops"] == \
                c["fixed"]["tpa_protocol_flops"]:
            fail(f"the rule's FLOPs are not below the fixed run's full schedule: {c}", p)

        # The rule applied for real, in an independent run from the same task cache.
        conv = os.path.join(out, "converged.h5")
        q = subprocess.run([SIRL, "run", PROFILE, "--out", conv, "--threads", "2",
                            "--cache", os.path.join(out, "tasks"),
                            "--set", 'hyper.grid."tpa.stop"="converged"',
                            "--set", 'hyper.grid."tpa.stop_frozen_rel_tol"=0.01',
                            "--set", 'hyper.grid."tpa.shadow_rel_tol"=0'],
                           capture_output=True, text=True, timeout=240)
        if q.returncode != 0:
            fail("the converged run failed", q)
        watched, applied = sirl_bench.open(os.path.join(out, "fixed.h5")), sirl_bench.open(conv)
        wr = watched.records
        cells = wr[wr.kind == "tpa"]
        if len(cells) != SEEDS * CELLS_PER_SEED:
            fail(f"{len(cells)} TPA cells in the watched run, not {SEEDS * CELLS_PER_SEED}")
        ar = applied.records.set_index(["env", "variant", "M", "seed"])
        stopped_early = 0
        for r in cells.itertuples():
            a = ar.loc[(r.env, r.variant, r.M, r.seed)]
            if float(a.tpa) != float(r.tpa_shadow):
                fail(f"{r.key}: the rule's TPA {a.tpa!r} is not the shadow's {r.tpa_shadow!r}")
            se = watched.array(r.key, "shadow_epochs")
            he = applied.array(a.key, "head_epochs")
            if list(se) != list(he):
                fail(f"{r.key}: shadow epochs {list(se)} but the rule stopped at {list(he)}")
            if list(watched.array(r.key, "shadow_accuracy")) != list(applied.array(a.key,
                                                                                  "accuracy")):
                fail(f"{r.key}: a head's shadow accuracy is not the stopped head's")
            stopped_early += int((se < 80).sum())
        if stopped_early == 0:
            fail("no head stopped before the cap: a weak test")

        # The check refuses a rule that does not explain the shadow epochs.
        spec = importlib.util.spec_from_file_location("stop_equivalence", SCRIPT)
        se_mod = importlib.util.module_from_spec(spec)
        spec.loader.exec_module(se_mod)
        se_mod.rule_stop = lambda curve, min_epochs, rel_tol: len(curve)  # "never stops"
        try:
            se_mod.check_shadow_stops(os.path.join(out, "fixed.h5"))
        except SystemExit as e:
            if "shadow epoch" not in str(e):
                fail(f"the check refused for another reason: {e}")
        else:
            fail("check_shadow_stops accepted shadow epochs the rule does not give")
    print(f"ok: {want} heads checked; the applied rule's {len(cells)} cells equal their shadows "
          f"({stopped_early} heads stopped before the cap)")


if __name__ == "__main__":
    main()
