#!/usr/bin/python3
"""bench/stop_equivalence.py --rule pref end to end on tests/data/stop-equivalence-pref-tiny.toml
(GridRobot's three preference methods at toy scale, 3 seeds, both sides for real): exit 0 (either
verdict exits 0; a failed check exits 1), a report with one FPE and one TPA row per preference
method, every φ checked against the rule applied to its fixed-run curve and at least one stopped
before pref.epochs. Then that the check can fail: the script's rule_stop on hand-made curves
with answers worked out by hand, and check_pref_stops refusing runs the rule does not explain.
SIRL_STOP_EQUIVALENCE overrides the script (to run this test against another version)."""
import importlib.util
import json
import math
import os
import subprocess
import sys
import tempfile
import time

SRC = os.environ["SIRL_SOURCE_DIR"]
SIRL = os.environ["SIRL"]
SCRIPT = os.environ.get("SIRL_STOP_EQUIVALENCE",
                        os.path.join(SRC, "bench", "stop_equivalence.py"))
PROFILE = os.path.join(SRC, "tests", "data", "stop-equivalence-pref-tiny.toml")
PY = "/usr/bin/python3"
METHODS = {"singlepref", "multipref10", "multipref50"}
SEEDS, PREF_EPOCHS = 3, 60  # as the profile says

sys.path.insert(0, os.path.join(SRC, "python"))
import sirl_bench  # noqa: E402

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import sirl_testing  # noqa: E402


fail = sirl_testing.make_fail("stop_equivalence_pref_tiny")


def load_script():
    spec = importlib.util.spec_from_file_location("stop_equivalence", SCRIPT)
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


def table(text, header):
    """The rows (lists of cells) of the Markdown table right below the line `header`."""
    lines = text.splitlines()
    if header not in lines:
        return None
    i = lines.index(header) + 2  # past the blank line to the table's header
    rows = []
    for ln in lines[i + 2:]:  # past the header and the |---| line
        if not ln.startswith("|"):
            break
        rows.append([c.strip() for c in ln.strip().strip("|").split("|")])
    return rows


def check_rule_stop(se):
    """rule_stop on curves whose answers are worked out by hand (the engine's check_convergence:
    w = e // 10 epochs a window, a = mean of curve[e-2w, e-w), b = mean of curve[e-w, e),
    converged when |a - b| <= rel_tol * max(|a|, |b|) + 1e-4)."""
    # 100 - i for i < 30 (it falls by 1 an epoch), 50 from epoch 30 on; 60 epochs.
    # min_epochs 20, rel_tol 0.01. Up to e = 29 both windows lie on the slope: a - b = w >= 2,
    # more than 0.01 * (<= 100) + 1e-4. From e = 30, w = 3:
    #   e = 30: a = mean(76, 75, 74)  = 75,    b = mean(73, 72, 71) = 72    -> no
    #   e = 31: a = mean(75, 74, 73)  = 74,    b = mean(72, 71, 50) = 64.33 -> no
    #   e = 32: a = 73,                        b = mean(71, 50, 50) = 57    -> no
    #   e = 33: a = mean(73, 72, 71)  = 72,    b = 50                       -> no
    #   e = 34: a = mean(72, 71, 50)  = 64.33, b = 50                       -> no
    #   e = 35: a = mean(71, 50, 50)  = 57,    b = 50                       -> no
    #   e = 36: a = mean(50, 50, 50)  = 50,    b = 50                       -> stops: 36.
    # (Windows of ceil(e / 10) epochs would say 38; a prefix one epoch too long, 35.)
    step = [100.0 - i for i in range(30)] + [50.0] * 30
    cases = [
        ("step, min 20", step, 20, 0.01, 36),
        # The minimum holds: from e = 37 (w = 3) both windows are 50 -> 37.
        ("step, min 37", step, 37, 0.01, 37),
        # A tolerance of 10 % holds on the slope already: e = 20, w = 2, a = mean(84, 83) = 83.5,
        # b = mean(82, 81) = 81.5, |a - b| = 2 <= 0.1 * 83.5 + 1e-4 -> 20.
        ("step, tol 10 %", step, 20, 0.1, 20),
        # Never converges (w = 2 to 5: |a - b| = w >= 2 > 0.01 * 100 + 1e-4): the cap, its length.
        ("slope", [100.0 - i for i in range(60)], 20, 0.01, 60),
        # inf for 25 epochs, then 1; min 20, w = 2. Up to e = 26 both windows' means are inf
        # (|inf - inf| = nan: no). e = 27: a = mean(inf, inf), b = mean(1, 1):
        # |inf - 1| <= 0.01 * inf holds, but a window whose mean is not finite never converges
        # (engine: std::isfinite(a) && std::isfinite(b)); e = 28: a = mean(inf, 1) = inf, no;
        # e = 29: a = mean(1, 1) = b -> 29 (without the finiteness test: 27).
        ("inf", [math.inf] * 25 + [1.0] * 5, 20, 0.01, 29),
    ]
    for name, curve, min_epochs, rel_tol, want in cases:
        got = se.rule_stop(curve, min_epochs, rel_tol)
        if got != want:
            fail(f"rule_stop on the hand-made curve '{name}' (min {min_epochs}, tol {rel_tol}) "
                 f"says {got}; worked out by hand: {want}")


def check_refusals(se, fixed, conv):
    """check_pref_stops exits, naming the φ, when the converged run did not stop where the rule
    says: here a rule one epoch later than the real one, then the runs' roles swapped (a
    "fixed" run whose curves are the stopped ones)."""
    real = se.rule_stop
    try:
        se.rule_stop = lambda c, m, t: real(c, m, t) + 1
        try:
            se.check_pref_stops(fixed, conv)
        except SystemExit as e:
            if "stopped after" not in str(e):
                fail(f"check_pref_stops, rule shifted by one epoch: exited with '{e}'")
        else:
            fail("check_pref_stops accepted φ that stopped an epoch before the rule says")
    finally:
        se.rule_stop = real
    try:
        se.check_pref_stops(conv, conv)
    except SystemExit as e:
        if "fixed-run curve has" not in str(e):
            fail(f"check_pref_stops, stopped curves as the fixed run: exited with '{e}'")
    else:
        fail("check_pref_stops accepted stopped curves as the fixed run's")
    n = len(se.check_pref_stops(fixed, conv))  # and the real pair passes
    if n != len(METHODS) * SEEDS:
        fail(f"check_pref_stops checked {n} φ, not {len(METHODS) * SEEDS}")


def main():
    se = load_script()
    check_rule_stop(se)
    with tempfile.TemporaryDirectory(prefix="stop-equivalence-pref-") as out:
        t0 = time.monotonic()
        try:
            p = subprocess.run([PY, SCRIPT, "--rule", "pref", "--profile", PROFILE, "--out", out,
                                "--threads", "2", "--sirl", SIRL], capture_output=True, text=True,
                               stdin=subprocess.DEVNULL, timeout=240)
        except subprocess.TimeoutExpired as e:
            fail(f"{SCRIPT} --rule pref still running after 240 s; stdout so far:\n{e.stdout}")
        took = time.monotonic() - t0
        if p.returncode != 0:  # 0 whatever the verdict; 1 only when a check failed
            fail("stop_equivalence.py --rule pref did not exit 0", p)
        md_path = os.path.join(out, "stop-equivalence.md")
        json_path = os.path.join(out, "stop-equivalence.json")
        for path in (md_path, json_path, os.path.join(out, "fixed.h5"),
                     os.path.join(out, "converged.h5")):
            if not os.path.isfile(path):
                fail(f"no {os.path.basename(path)} in --out", p)
        with open(md_path, encoding="utf-8") as f:
            md = f.read()
        with open(json_path, encoding="utf-8") as f:
            rep = json.load(f)

        # The report names the rule and has one table per metric, a row per preference method.
        if rep.get("rule") != "pref.stop" or not md.startswith('# pref.stop = "converged"'):
            fail(f"the report does not name the rule pref.stop:\n{md[:300]}")
        for metric, margin in (("FPE", 0.005), ("TPA", 0.02)):
            rows = table(md, f"## {metric} (margin ±{margin})")
            if rows is None or {r[1] for r in rows} != METHODS or len(rows) != len(METHODS):
                fail(f"the markdown's {metric} table has not one row per preference method: "
                     f"{rows}\n{md}")
            jrows = [r for r in rep["rows"] if r["metric"] == metric.lower()]
            if {r["method"] for r in jrows} != METHODS or len(jrows) != len(METHODS):
                fail(f"the JSON's {metric} rows are not one per preference method: {jrows}")
            for r in jrows:
                if r["seeds"] != SEEDS or r["margin"] != margin:
                    fail(f"{metric} {r['method']}: {r['seeds']} seeds, margin {r['margin']}")
        if rep["equivalent"] != all(r["equivalent"] for r in rep["rows"]):
            fail("the verdict is not 'equivalent only if every method and metric is'")
        for m in METHODS:
            both = all(r["equivalent"] for r in rep["rows"] if r["method"] == m)
            if rep["methods"].get(f"grid {m}") != both:
                fail(f"grid {m}'s verdict is not its two metrics': {rep['methods']}")
        cost = rep["cost"]
        for side in ("fixed", "converged"):
            if not cost[side]["rep_flops"] > 0 or not cost[side]["rep_protocol_flops"] > 0:
                fail(f"no φ FLOPs in the {side} side's cost: {cost}")
        if cost["fixed"]["rep_flops"] != cost["fixed"]["rep_protocol_flops"] or \
                not cost["converged"]["rep_flops"] < cost["converged"]["rep_protocol_flops"]:
            fail(f"the φ FLOPs executed against the protocol's are off: {cost}")

        # Every φ checked; at least one stopped before pref.epochs; the epochs the report gives
        # are the converged run's curve lengths, each the rule's on the fixed run's curve.
        stops = rep["stops"]
        if stops["checked"] != len(METHODS) * SEEDS or len(stops["phis"]) != stops["checked"]:
            fail(f"{stops['checked']} φ checked, not {len(METHODS) * SEEDS}")
        if not 1 <= stops["stopped"] == sum(ph["epochs"] < PREF_EPOCHS for ph in stops["phis"]):
            fail(f"no φ stopped before pref.epochs = {PREF_EPOCHS}: {stops}")
        fixed_path, conv_path = os.path.join(out, "fixed.h5"), os.path.join(out, "converged.h5")
        fixed, conv = sirl_bench.open(fixed_path), sirl_bench.open(conv_path)
        for ph in stops["phis"]:
            n = len(conv.array(ph["key"], "loss_curve"))
            want = se.rule_stop(fixed.array(ph["key"], "loss_curve"), 10, 0.005)
            if not ph["epochs"] == n == want or ph["cap"] != PREF_EPOCHS:
                fail(f"{ph['key']}: the report says {ph['epochs']} epochs of {ph['cap']}, the "
                     f"converged curve has {n}, the rule on the fixed curve says {want}")
        if "9 preference φ stopped where the rule" not in p.stdout:
            fail("the script did not print how many φ it checked", p)

        check_refusals(se, fixed_path, conv_path)
    print(f"stop_equivalence.py --rule pref: {took:.1f} s; {stops['checked']} φ checked, "
          f"{stops['stopped']} stopped before {PREF_EPOCHS} epochs; verdict "
          f"{'equivalent' if rep['equivalent'] else 'not shown equivalent'}")


if __name__ == "__main__":
    main()
