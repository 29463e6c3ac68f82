#!/usr/bin/python3
"""Does the converged stopping rule change TPA? An equivalence test (TOST) of tpa.stop =
"converged" against "fixed" (every head the schedule's epochs, the paper's protocol).

Runs one profile (its [hyper.<env>] sections say "tpa.stop" = "fixed") as it is and with
"converged" in their place, over the same seeds, cells, queries and initial weights, then asks per
environment and method whether the two give the same TPA:

  per seed, the method's mean TPA over its cells (M values, frozen modes);
  d = converged − fixed per seed (paired);
  two one-sided t-tests at α = 0.05 against ±0.02 (bench/bf16_equivalence.py's test and margin):
  *equivalent* when the 90 % confidence interval of the mean d lies inside the margin.

Also reports every cell's difference, each head's stopping epoch (spread per cell), and the
compute each side took (FLOPs executed and task-seconds, from /tables/timings).

Both runs resume and share one task cache, so the converged run reuses every representation the
fixed run trained (`sirl run --cache`). The converged side is the same profile with
`--set hyper.<env>."tpa.stop"="converged"`. Writes both results files and
OUT/stop-equivalence.{md,json}.

  /usr/bin/python3 bench/stop_equivalence.py --profile bench/stop-equivalence-jaco.toml
                                             [--threads 2] [--out out/stop-equivalence-jaco]

--rule pref tests the preference φ's rule instead (pref.stop = "converged" against "fixed",
docs/stopping-rule.md, "Preference φ that stop when they have learned"): the profile's
[hyper.<env>] sections say "pref.stop" = "fixed", the converged side sets "converged" there; every
preference φ (SinglePref, MultiPref-10, MultiPref-50, with or without VAE) of the converged run
must have stopped where the rule, applied to the same φ's fixed-run loss curve, says (its curve
holds the epochs it ran, the fixed curve's first epochs bit for bit); then per environment and
preference method, TPA (per seed the mean over the method's best-mode cells, ±0.02) and FPE (per
seed the mean over its N, ±0.005) by the same TOST. Equivalent only if both metrics are. The
compute is the preference φ's (rep tasks). Either verdict exits 0; a failed check exits 1.

  /usr/bin/python3 bench/stop_equivalence.py --rule pref
                                             --profile bench/stop-equivalence-jaco-pref.toml

--rule shadow needs one run, not two: the profile sets "tpa.shadow_rel_tol" (engine/tpa.h), so every
head of a cell whose heads run every epoch is also scored where "converged" at that tolerance
(minimum tpa.stop_min_epochs) would have stopped it: bit for bit the stopped run's head. Each
head's shadow epoch is checked against the rule applied to its curve, then per environment and
method (references too) the same TOST on TPA (±0.02), "converged" being the shadow's TPA. The
compute of the rule's side is counted from the shadow epochs (no task-seconds: it did not run).

  /usr/bin/python3 bench/stop_equivalence.py --rule shadow
                                             --profile bench/stop-equivalence-jaco-frozen-groups.toml
"""
import argparse
import json
import math
import os
import subprocess
import sys
import tomllib

import pandas as pd

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from bf16_equivalence import ALPHA, run, tost  # noqa: E402  (the same test, the same runner)

# The reader package: installed by scripts/setup.sh, or beside this folder in a checkout.
sys.path.insert(1, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "python"))
import sirl_bench  # noqa: E402

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
MARGIN = 0.02
# --rule pref: the preference methods (a +VAE variant is its method's, with "vae" set), and the
# margins of docs/bf16-equivalence.md per metric.
PREF_METHODS = ("singlepref", "multipref10", "multipref50")
PREF_MARGINS = {"fpe": 0.005, "tpa": 0.02}


def converged_settings(resolved, rule="tpa"):
    """--set values that turn every environment's "tpa.stop" (--rule pref: "pref.stop") = "fixed"
    into "converged"."""
    key = f"{rule}.stop"
    envs = [env for env, hy in resolved.get("hyper", {}).items() if hy.get(key) == "fixed"]
    if not envs:
        sys.exit(f'stop_equivalence: the profile sets no [hyper.<env>] "{key}" = "fixed" to vary')
    return [f'hyper.{env}."{key}"="converged"' for env in envs] + \
        [f'name="{resolved["name"]}-converged"']


def tables(path):
    """The run's tables, /tables/tpa cut to the paper's protocol and the methods (the stopping
    rule is about the paper's heads; linear evaluation and the references have no epochs)."""
    res = sirl_bench.open(path)
    t = {k: res.tables[k] for k in ("tpa", "timings", "tpa_heads")}
    tpa = t["tpa"]
    t["tpa"] = tpa[(tpa.protocol == "paper") & ~tpa.reference.astype(bool)]
    return t


CELL = ["env", "variant", "N", "M", "frozen", "seed"]


def rule_stop(curve, min_epochs, rel_tol, abs_tol=1e-4):
    """The epochs a head trains under the converged rule, from its fixed-run curve: an independent
    reimplementation of engine/convergence.h (sums in order, in double, as the engine's; a
    window whose mean is not finite never converges). The same rule ends a preference φ
    (pref.stop): pass its curve, pref.stop_min_epochs and pref.stop_rel_tol."""
    cap = len(curve)
    for e in range(max(2, min_epochs), cap):
        w = max(1, e // 10)
        a = b = 0.0
        for x in curve[e - 2 * w:e - w]:
            a += float(x)
        for x in curve[e - w:e]:
            b += float(x)
        a, b = a / w, b / w
        if math.isfinite(a) and math.isfinite(b) and \
                abs(a - b) <= rel_tol * max(abs(a), abs(b)) + abs_tol:
            return e
    return cap


def check_stops(fixed_path, conv_path):
    """Every head of the converged run must have stopped where the rule, applied to the same
    head's curve in the fixed run, says (the two trainings are identical up to the stop).
    Returns the number of heads checked."""
    checked = 0
    fixed, conv = sirl_bench.open(fixed_path), sirl_bench.open(conv_path)
    prof = tomllib.loads(conv.provenance["profile_text"])  # the profile the run resolved
    recs = conv.records
    for r in recs[recs.arrays.str.split(",").map(lambda a: "head_epochs" in a)].itertuples():
        hy = prof.get("hyper", {}).get(r.env, {})
        min_epochs = int(hy.get("tpa.stop_min_epochs", 100))
        # each mode has its own tolerance
        rel_tol = float(hy.get("tpa.stop_frozen_rel_tol" if r.frozen else "tpa.stop_rel_tol", 0.01))
        curves = fixed.array(r.key, "loss_curves")
        got = conv.array(r.key, "head_epochs")
        for h, c in enumerate(curves):
            want = rule_stop(c, min_epochs, rel_tol)
            if int(got[h]) != want:
                sys.exit(f"stop_equivalence: {r.key} head {h} stopped after {int(got[h])} "
                         f"epochs; the rule on its fixed-run curve says {want}")
            checked += 1
    return checked


def method_rows(cells, margin, **extra):
    """Per (env, method): the seed-paired TOST of converged − fixed on the method's mean over its
    cells (one dict each, `extra` fields first)."""
    rows = []
    per_seed = cells.groupby(["env", "variant", "seed"])[["fixed", "converged"]].mean()
    for (env, variant), g in per_seed.groupby(level=[0, 1]):
        diffs = list((g.converged - g.fixed).astype(float))
        mean, ci, p = tost(diffs, margin)
        rows.append({**extra, "env": env, "method": variant, "seeds": len(diffs),
                     "fixed": float(g.fixed.mean()), "converged": float(g.converged.mean()),
                     "diff": mean, "ci90": ci, "margin": margin, "p_tost": p,
                     "equivalent": bool(p < ALPHA)})
    return rows


def compare(fixed_path, conv_path):
    a, b = tables(fixed_path), tables(conv_path)
    ta, tb = a["tpa"].set_index(CELL).tpa, b["tpa"].set_index(CELL).tpa
    if set(ta.index) != set(tb.index):
        sys.exit("stop_equivalence: the two runs' TPA cells differ")
    cells = pd.DataFrame({"fixed": ta, "converged": tb.reindex(ta.index)})
    cells["d"] = cells.converged - cells.fixed
    heads = b["tpa_heads"].groupby(CELL, dropna=False).agg(
        epochs_min=("epochs", "min"), epochs_median=("epochs", "median"),
        epochs_max=("epochs", "max"), stopped=("stopped", "mean"))
    cells = cells.join(heads).reset_index()
    rows = method_rows(cells, MARGIN)
    cost = {}
    for side, t in (("fixed", a["timings"]), ("converged", b["timings"])):
        tp = t[t.kind == "tpa"]
        cost[side] = {"tpa_flops": float(tp.flops.sum()),
                      "tpa_protocol_flops": float(tp.protocol_flops.sum()),
                      "tpa_task_seconds": float(tp.seconds.sum()),
                      "all_task_seconds": float(t.seconds.sum())}
    return rows, cells, cost


def report(rows, cells, cost, profile, title='tpa.stop = "converged" against "fixed"'):
    ok = all(r["equivalent"] for r in rows)
    lines = [f"# {title}: equivalence (TOST, α = {ALPHA}) on {profile}", "",
             "Per seed: the method's mean TPA over its cells; d = converged − fixed, paired by "
             f"seed. Equivalent when the 90 % CI of the mean d lies inside ±{MARGIN}.", "",
             "| env | method | seeds | fixed | converged | mean d | 90 % CI | TOST p | verdict |",
             "|---|---|---:|---:|---:|---:|---|---:|---|"]
    for r in rows:
        lo, hi = r["ci90"]
        lines.append(f"| {r['env']} | {r['method']} | {r['seeds']} | {r['fixed']:.4f} | "
                     f"{r['converged']:.4f} | {r['diff']:+.4f} | [{lo:+.4f}, {hi:+.4f}] | "
                     f"{r['p_tost']:.2g} | "
                     f"{'equivalent' if r['equivalent'] else 'not shown equivalent'} |")
    failed = [f"{r['env']} {r['method']}" for r in rows if not r["equivalent"]]
    lines += ["", "**Verdict: equivalent on every method.**" if ok else
              "**Verdict: equivalence not shown** for " + ", ".join(failed) + "."]
    f, c = cost["fixed"], cost["converged"]
    lines += ["", "## Compute", "",
              "| | fixed | converged | ratio |", "|---|---:|---:|---:|",
              f"| TPA FLOPs executed | {f['tpa_flops']:.4g} | {c['tpa_flops']:.4g} | "
              f"{f['tpa_flops'] / max(c['tpa_flops'], 1):.2f}× |",
              ]
    if c.get("tpa_task_seconds") is not None:  # a shadow rule did not run: no seconds of its own
        lines += [f"| TPA task-seconds | {f['tpa_task_seconds']:.0f} | "
                  f"{c['tpa_task_seconds']:.0f} | "
                  f"{f['tpa_task_seconds'] / max(c['tpa_task_seconds'], 1e-9):.2f}× |",
                  f"| all task-seconds | {f['all_task_seconds']:.0f} | "
                  f"{c['all_task_seconds']:.0f} | |"]
    lines += ["", "## Every cell", "",
              "| env | method | N | M | frozen | seed | fixed | converged | d | head epochs "
              "min / median / max | stopped |",
              "|---|---|---:|---:|---:|---:|---:|---:|---:|---|---:|"]
    for _, r in cells.sort_values(CELL).iterrows():
        n = "—" if pd.isna(r.N) else int(r.N)  # a method that uses no queries has no N
        lines.append(f"| {r.env} | {r.variant} | {n} | {r.M} | {int(r.frozen)} | {r.seed} | "
                     f"{r.fixed:.4f} | {r.converged:.4f} | {r.d:+.4f} | {r.epochs_min:.0f} / "
                     f"{r.epochs_median:.0f} / {r.epochs_max:.0f} | {100 * r.stopped:.0f} % |")
    return "\n".join(lines) + "\n", ok


# ---- --rule shadow: a head rule watched in one run (tpa.shadow_rel_tol) ----

def check_shadow_stops(path):
    """Every head with a shadow score must have run every epoch, and its shadow epoch must be where
    the rule, applied to its own curve, says. Returns the number of heads checked."""
    res = sirl_bench.open(path)
    prof = tomllib.loads(res.provenance["profile_text"])
    recs = res.records
    checked = 0
    for r in recs[recs.arrays.str.split(",").map(lambda a: "shadow_epochs" in a)].itertuples():
        hy = prof.get("hyper", {}).get(r.env, {})
        min_epochs = int(hy.get("tpa.stop_min_epochs", 100))
        rel_tol = float(hy.get("tpa.shadow_rel_tol", 0))
        curves = res.array(r.key, "loss_curves")
        ran = res.array(r.key, "head_epochs")
        got = res.array(r.key, "shadow_epochs")
        for h, c in enumerate(curves):
            if int(ran[h]) != len(c):
                sys.exit(f"stop_equivalence: {r.key} head {h} ran {int(ran[h])} of {len(c)} "
                         "epochs: a shadow rule is only scored where heads run every epoch")
            want = rule_stop(c, min_epochs, rel_tol)
            if int(got[h]) != want:
                sys.exit(f"stop_equivalence: {r.key} head {h}'s shadow epoch is {int(got[h])}; "
                         f"the rule on its curve says {want}")
            checked += 1
    if checked == 0:
        sys.exit('stop_equivalence: no TPA cell has a shadow rule (set [hyper.<env>] '
                 '"tpa.shadow_rel_tol" and run heads every epoch)')
    return checked


def compare_shadow(path):
    """The fixed run's TPA against the shadow's, per cell and per method (references too)."""
    res = sirl_bench.open(path)
    recs = res.records
    recs = recs[(recs.kind == "tpa") & recs.arrays.str.split(",").map(
        lambda a: "shadow_epochs" in a)]
    cells, flops = [], {"fixed": 0.0, "converged": 0.0, "protocol": 0.0}
    for r in recs.itertuples():
        e = res.array(r.key, "shadow_epochs")
        cap = res.array(r.key, "loss_curves").shape[1]
        cells.append({"env": r.env, "variant": r.variant, "N": r.N, "M": r.M,
                      "frozen": r.frozen, "seed": r.seed, "fixed": float(r.tpa),
                      "converged": float(r.tpa_shadow), "epochs_min": float(e.min()),
                      "epochs_median": float(pd.Series(e).median()),
                      "epochs_max": float(e.max()), "stopped": float((e < cap).mean())})
        flops["fixed"] += float(r.flops)
        flops["protocol"] += float(r.protocol_flops)
        flops["converged"] += float(r.protocol_flops) * float(e.mean()) / cap
    cells = pd.DataFrame(cells)
    cells["d"] = cells.converged - cells.fixed
    rows = method_rows(cells, MARGIN)
    cost = {"fixed": {"tpa_flops": flops["fixed"], "tpa_protocol_flops": flops["protocol"]},
            "converged": {"tpa_flops": flops["converged"],
                          "tpa_protocol_flops": flops["protocol"], "tpa_task_seconds": None}}
    return rows, cells, cost


def main_shadow(a, path, out):
    checked = check_shadow_stops(path)
    print(f"stop_equivalence: {checked} heads' shadow epochs are where the rule on their curves "
          "says", flush=True)
    rows, cells, cost = compare_shadow(path)
    text, ok = report(rows, cells, cost, os.path.relpath(a.profile, ROOT),
                      title='the rule watched (tpa.shadow_rel_tol) against every epoch')
    text += (f"\n{checked} heads checked: each head's shadow epoch is where the rule, applied to "
             "its curve, says; its shadow score is that stopped head's (engine/tpa.h).\n")
    with open(os.path.join(out, "stop-equivalence.md"), "w", encoding="utf-8") as f:
        f.write(text)
    with open(os.path.join(out, "stop-equivalence.json"), "w", encoding="utf-8") as f:
        json.dump({"profile": a.profile, "rule": "tpa.shadow_rel_tol", "equivalent": ok,
                   "rows": rows, "cost": cost, "heads_checked": checked}, f, indent=1)
    print(text)


# ---- --rule pref: the preference φ's rule (pref.stop), FPE and TPA ----

def is_pref(frame):
    """Rows of a table or the records that belong to a preference method (any VAE variant)."""
    return frame.method.isin(PREF_METHODS)


def check_pref_stops(fixed_path, conv_path):
    """Every preference φ of the converged run must have stopped where the rule, applied to the
    same φ's curve in the fixed run, says: its curve holds exactly the epochs it ran, and they are
    the fixed curve's first epochs bit for bit (the two trainings are identical up to the stop).
    Returns one dict per φ checked (exits naming the first φ that breaks this)."""
    fixed, conv = sirl_bench.open(fixed_path), sirl_bench.open(conv_path)
    prof = tomllib.loads(conv.provenance["profile_text"])  # the profile the run resolved
    fixed_keys = set(fixed.keys())
    recs = conv.records
    phis = []
    for r in recs[(recs.kind == "rep") & is_pref(recs)].itertuples():
        hy = prof.get("hyper", {}).get(r.env, {})
        if hy.get("pref.stop") != "converged":
            sys.exit(f'stop_equivalence: the converged run has no "pref.stop" = "converged" for '
                     f"{r.env} ({r.key})")
        min_epochs = int(hy.get("pref.stop_min_epochs", 500))
        rel_tol = float(hy.get("pref.stop_rel_tol", 0.01))
        if r.key not in fixed_keys:
            sys.exit(f"stop_equivalence: {r.key} is not in the fixed run")
        curve = fixed.array(r.key, "loss_curve")
        got = conv.array(r.key, "loss_curve")
        cap = int(hy.get("pref.epochs", len(curve)))
        if len(curve) != cap:
            sys.exit(f"stop_equivalence: {r.key}'s fixed-run curve has {len(curve)} epochs, not "
                     f"pref.epochs = {cap}: the fixed run did not run the full schedule")
        want = rule_stop(curve, min_epochs, rel_tol)
        if len(got) != want:
            sys.exit(f"stop_equivalence: φ {r.key} stopped after {len(got)} epochs; the rule on "
                     f"its fixed-run curve says {want}")
        if got.tobytes() != curve[:want].tobytes():
            sys.exit(f"stop_equivalence: φ {r.key}'s curve differs from its fixed-run curve's "
                     f"first {want} epochs")
        phis.append({"key": r.key, "env": r.env, "method": r.variant, "N": int(r.N),
                     "seed": int(r.seed), "cap": cap, "epochs": want,
                     "min_epochs": min_epochs, "rel_tol": rel_tol})
    if not phis:
        sys.exit("stop_equivalence: the converged run has no preference φ to check")
    return phis


PHI = ["env", "variant", "N", "seed"]


def pref_tables(path):
    """The preference methods' rows: /tables/tpa cut to the paper's protocol and the methods'
    best modes, /tables/fpe, /tables/timings."""
    res = sirl_bench.open(path)
    tpa, fpe = res.tables["tpa"], res.tables["fpe"]
    keep = (tpa.protocol == "paper") & ~tpa.reference.astype(bool) & tpa.best_mode.astype(bool)
    return {"tpa": tpa[keep & is_pref(tpa)],
            "fpe": fpe[~fpe.reference.astype(bool) & is_pref(fpe)],
            "timings": res.tables["timings"]}


def compare_pref(fixed_path, conv_path, phis):
    a, b = pref_tables(fixed_path), pref_tables(conv_path)
    rows, cells = [], {}
    for metric, index in (("fpe", PHI), ("tpa", CELL)):
        ta, tb = a[metric].set_index(index)[metric], b[metric].set_index(index)[metric]
        if set(ta.index) != set(tb.index):
            sys.exit(f"stop_equivalence: the two runs' {metric.upper()} cells differ")
        if ta.empty:
            sys.exit(f"stop_equivalence: the runs have no {metric.upper()} cell of a preference "
                     "method")
        c = pd.DataFrame({"fixed": ta, "converged": tb.reindex(ta.index)})
        c["d"] = c.converged - c.fixed
        cells[metric] = c.reset_index()
        rows += method_rows(cells[metric], PREF_MARGINS[metric], metric=metric)
    # Every φ: its stopping epoch beside its FPE cells (an FPE-less φ keeps NaN there).
    epochs = pd.DataFrame(phis).rename(columns={"method": "variant"})
    fpe = cells["fpe"].astype({"N": int, "seed": int})
    cells["phi"] = epochs.merge(fpe, on=PHI, how="left")
    cost = {}
    for side, t in (("fixed", a["timings"]), ("converged", b["timings"])):
        rep = t[(t.kind == "rep") & is_pref(t)]
        cost[side] = {"rep_flops": float(rep.flops.sum()),
                      "rep_protocol_flops": float(rep.protocol_flops.sum()),
                      "rep_task_seconds": float(rep.seconds.sum()),
                      "all_task_seconds": float(t.seconds.sum())}
    return rows, cells, cost


def method_verdicts(rows):
    """Per (env, method): equivalent when every metric is (the rule may then be used there)."""
    out = {}
    for r in rows:
        k = f"{r['env']} {r['method']}"
        out[k] = out.get(k, True) and r["equivalent"]
    return out


def report_pref(rows, cells, cost, phis, profile):
    ok = all(r["equivalent"] for r in rows)
    methods = method_verdicts(rows)
    lines = [f"# pref.stop = \"converged\" against \"fixed\": equivalence (TOST, α = {ALPHA}) on "
             f"{profile}", "",
             "The rule: pref.stop (a preference φ ends at the first epoch e ≥ "
             "pref.stop_min_epochs at which its training loss has converged at pref.stop_rel_tol; "
             "docs/stopping-rule.md). Per seed: the method's mean over its cells (FPE: its N; TPA: "
             "its best-mode cells); d = converged − fixed, paired by seed. Equivalent when the "
             "90 % CI of the mean d lies inside the metric's margin; a method is equivalent when "
             "both metrics are."]
    for metric in ("fpe", "tpa"):
        margin = PREF_MARGINS[metric]
        lines += ["", f"## {metric.upper()} (margin ±{margin})", "",
                  "| env | method | seeds | fixed | converged | mean d | 90 % CI | TOST p | "
                  "verdict |",
                  "|---|---|---:|---:|---:|---:|---|---:|---|"]
        for r in rows:
            if r["metric"] != metric:
                continue
            lo, hi = r["ci90"]
            lines.append(f"| {r['env']} | {r['method']} | {r['seeds']} | {r['fixed']:.4f} | "
                         f"{r['converged']:.4f} | {r['diff']:+.5f} | [{lo:+.5f}, {hi:+.5f}] | "
                         f"{r['p_tost']:.2g} | "
                         f"{'equivalent' if r['equivalent'] else 'not shown equivalent'} |")
    failed = [f"{r['metric'].upper()} {r['env']} {r['method']}" for r in rows
              if not r["equivalent"]]
    may = [k for k, v in methods.items() if v]
    keep = [k for k, v in methods.items() if not v]
    lines += ["", "**Verdict: equivalent on every method and metric.**" if ok else
              "**Verdict: equivalence not shown** for " + ", ".join(failed) + ".", "",
              "May stop by the rule (both metrics equivalent): " + (", ".join(may) or "none") +
              ". Keep the schedule's epochs: " + (", ".join(keep) or "none") + "."]
    f, c = cost["fixed"], cost["converged"]
    lines += ["", "## Compute (the preference φ: rep tasks)", "",
              "| | fixed | converged | ratio |", "|---|---:|---:|---:|",
              f"| φ FLOPs executed | {f['rep_flops']:.4g} | {c['rep_flops']:.4g} | "
              f"{f['rep_flops'] / max(c['rep_flops'], 1):.2f}× |",
              f"| φ protocol FLOPs | {f['rep_protocol_flops']:.4g} | "
              f"{c['rep_protocol_flops']:.4g} | |",
              f"| φ task-seconds | {f['rep_task_seconds']:.1f} | {c['rep_task_seconds']:.1f} | "
              f"{f['rep_task_seconds'] / max(c['rep_task_seconds'], 1e-9):.2f}× |",
              f"| all task-seconds | {f['all_task_seconds']:.1f} | {c['all_task_seconds']:.1f} | |",
              "", "## Every φ", "",
              "| env | method | N | seed | epochs run / pref.epochs | FPE fixed | FPE converged "
              "| d |",
              "|---|---|---:|---:|---|---:|---:|---:|"]
    for _, r in cells["phi"].sort_values(PHI).iterrows():
        fpe = ("— | — | —" if pd.isna(r.fixed) else
               f"{r.fixed:.5f} | {r.converged:.5f} | {r.d:+.5f}")
        lines.append(f"| {r.env} | {r.variant} | {r.N} | {r.seed} | {r.epochs} / {r.cap} | "
                     f"{fpe} |")
    lines += ["", "## Every TPA cell", "",
              "| env | method | N | M | frozen | seed | fixed | converged | d |",
              "|---|---|---:|---:|---:|---:|---:|---:|---:|"]
    for _, r in cells["tpa"].sort_values(CELL).iterrows():
        lines.append(f"| {r.env} | {r.variant} | {int(r.N)} | {r.M} | {int(r.frozen)} | "
                     f"{r.seed} | {r.fixed:.4f} | {r.converged:.4f} | {r.d:+.4f} |")
    stopped = sum(p["epochs"] < p["cap"] for p in phis)
    lines += ["", f"{len(phis)} preference φ checked: each stopped where the rule, applied to the "
              f"same φ's curve in the fixed run, says ({stopped} before pref.epochs), its curve "
              "the fixed curve's first epochs bit for bit."]
    return "\n".join(lines) + "\n", ok, methods


def main_pref(a, paths, out):
    phis = check_pref_stops(paths["fixed"], paths["converged"])
    stopped = sum(p["epochs"] < p["cap"] for p in phis)
    print(f"stop_equivalence: {len(phis)} preference φ stopped where the rule on their fixed-run "
          f"curves says ({stopped} before pref.epochs)", flush=True)
    rows, cells, cost = compare_pref(paths["fixed"], paths["converged"], phis)
    text, ok, methods = report_pref(rows, cells, cost, phis, os.path.relpath(a.profile, ROOT))
    with open(os.path.join(out, "stop-equivalence.md"), "w", encoding="utf-8") as f:
        f.write(text)
    with open(os.path.join(out, "stop-equivalence.json"), "w", encoding="utf-8") as f:
        json.dump({"profile": a.profile, "rule": "pref.stop", "equivalent": ok,
                   "methods": methods, "rows": rows, "cost": cost,
                   "stops": {"checked": len(phis), "stopped": stopped, "phis": phis}}, f,
                  indent=1)
    print(text)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--rule", choices=("tpa", "pref", "shadow"), default="tpa",
                    help='the rule to test: tpa.stop (the reward heads, default), pref.stop (the '
                    'preference φ; FPE and TPA) or the profile\'s tpa.shadow_rel_tol (one run)')
    ap.add_argument("--profile", default=None,
                    help="default bench/stop-equivalence-jaco.toml (--rule pref: "
                    "bench/stop-equivalence-jaco-pref.toml)")
    ap.add_argument("--threads", type=int, default=2)
    ap.add_argument("--out", default=None, help="default out/<profile name>")
    ap.add_argument("--cache", default=None,
                    help="the task cache (default OUT/tasks): two tests given the same folder "
                    "train the tasks they share once")
    ap.add_argument("--sirl", default=os.path.join(ROOT, "build", "release", "app", "sirl"))
    ap.add_argument("--analyse-only", action="store_true", help="compare existing results files")
    a = ap.parse_args()
    if a.profile is None:
        a.profile = os.path.join(ROOT, "bench", "stop-equivalence-jaco-pref.toml"
                                 if a.rule == "pref" else "stop-equivalence-jaco.toml")
    stem = os.path.splitext(os.path.basename(a.profile))[0]
    out = a.out or os.path.join(ROOT, "out", stem)
    if not a.analyse_only and not os.access(a.sirl, os.X_OK):
        sys.exit(f"stop_equivalence: no sirl binary at {a.sirl} (./scripts/build.sh release)")
    os.makedirs(out, exist_ok=True)
    cache = a.cache or os.path.join(out, "tasks")
    if a.rule == "shadow":  # one run: the profile as it is
        path = os.path.join(out, "fixed.h5")
        if not a.analyse_only:
            run(a.sirl, a.profile, [], path, a.threads, ["--cache", cache])
        if not os.path.isfile(path):
            sys.exit(f"stop_equivalence: {path}: no results file (run without --analyse-only)")
        return main_shadow(a, path, out)
    paths = {stop: os.path.join(out, stop + ".h5") for stop in ("fixed", "converged")}
    if not a.analyse_only:
        p = subprocess.run([a.sirl, "plan", a.profile, "--resolved"], capture_output=True,
                           text=True)
        if p.returncode != 0:
            sys.exit(f"stop_equivalence: {p.stderr.strip()}")
        sets = {"fixed": [], "converged": converged_settings(tomllib.loads(p.stdout), a.rule)}
        for stop in ("fixed", "converged"):
            run(a.sirl, a.profile, sets[stop], paths[stop], a.threads, ["--cache", cache])
    for path in paths.values():
        if not os.path.isfile(path):
            sys.exit(f"stop_equivalence: {path}: no results file (run without --analyse-only)")
    if a.rule == "pref":
        return main_pref(a, paths, out)
    checked = check_stops(paths["fixed"], paths["converged"])
    print(f"stop_equivalence: {checked} heads stopped where the rule on their fixed-run curves "
          "says", flush=True)
    rows, cells, cost = compare(paths["fixed"], paths["converged"])
    text, ok = report(rows, cells, cost, os.path.relpath(a.profile, ROOT))
    text += (f"\n{checked} heads checked: each stopped where the rule, applied to the same head's "
             "curve in the fixed run, says.\n")
    with open(os.path.join(out, "stop-equivalence.md"), "w", encoding="utf-8") as f:
        f.write(text)
    with open(os.path.join(out, "stop-equivalence.json"), "w", encoding="utf-8") as f:
        json.dump({"profile": a.profile, "equivalent": ok, "rows": rows, "cost": cost}, f,
                  indent=1)
    print(text)


if __name__ == "__main__":
    main()
