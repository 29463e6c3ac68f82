#!/usr/bin/python3
"""The plotting tool on the output of the smoke profile's plan with narrow networks
(tests/data/engine-test.toml) (ctest): every figure and the report exist;
Fig. 7 draws the cells the file holds even when an environment overrides the ablation's M;
Fig. 3 is drawn on the simplified GridRobot; a partial file (one shard of two) still plots, with
the missing cells reported as gaps."""
import json
import os
import subprocess
import sys
import tempfile

import h5py
import pandas as pd
from scipy import stats

SIRL = os.environ["SIRL"]
SRC = os.environ["SIRL_SOURCE_DIR"]
SMOKE = os.path.join(SRC, "tests", "data", "engine-test.toml")  # smoke's plan, narrow nets
PLOT = os.path.join(SRC, "report", "plot_figures.py")
FILES = [f"{n}.{e}" for n in ("fig3_grid_similar", "fig4_fpe", "fig5_tpa", "fig7_ablation",
                               "fig_learning_curves")
         for e in ("png", "pdf")] + ["report.md", "report.html", "figures.json"]


def sh(*cmd):
    p = subprocess.run(cmd, capture_output=True, text=True, stdin=subprocess.DEVNULL)
    if p.returncode != 0:
        sys.exit(f"FAIL: {' '.join(cmd)} exited {p.returncode}\n{p.stdout}\n{p.stderr}")
    return p


def check_outputs(d):
    for f in FILES:
        p = os.path.join(d, f)
        if not os.path.exists(p) or os.path.getsize(p) < 200:
            sys.exit(f"FAIL: {p} missing or empty")
    return open(os.path.join(d, "report.md")).read()


with tempfile.TemporaryDirectory() as tmp:
    full = os.path.join(tmp, "smoke.h5")
    sh(SIRL, "run", SMOKE, "--out", full, "--quiet")
    sh("/usr/bin/python3", PLOT, full, "--out", os.path.join(tmp, "full"))
    rep = check_outputs(os.path.join(tmp, "full"))
    for claim in ("H1", "H2", "SIRL is better frozen", "Random beats preference"):
        assert claim in rep, f"report lacks {claim}"
    assert "paired t-test" in rep and "p = " in rep and "Holm p" in rep
    # The summary table opens the report, before the figures; the profile's text closes it.
    assert rep.index("| claim | environment | verdict") < rep.index("## Figures") < rep.index(
        "## Configuration"), "report order: summary, figures, …, profile"
    # The page a reader opens, in chromium: summary table first, real tables, every image loaded.
    p = subprocess.run(["node", os.path.join(SRC, "tests", "report_browser.mjs"),
                        os.path.join(tmp, "full", "report.html")], cwd=os.path.join(SRC, "app", "study_web"),
                       capture_output=True, text=True, timeout=300, stdin=subprocess.DEVNULL)
    if p.returncode != 0:
        sys.exit(f"FAIL: report_browser\n{p.stdout}\n{p.stderr}")
    print(p.stdout.strip())
    for section in ("Did every training converge?", "The VAE's posterior", "Dead units"):
        assert section in rep, f"report lacks {section}"
    drawn = json.load(open(os.path.join(tmp, "full", "figures.json")))
    assert drawn["fig3"]["env"] == "grid2", drawn["fig3"]
    print("ok: every figure and the report from the smoke run; Fig. 3 on grid2")

    # What Figs. 4 and 5 drew equals the seed means computed here from the tables (a plot of the
    # wrong column, of train_mse, of the ablation's cells or of the other frozen mode differs).
    with h5py.File(full, "r") as f:
        fpe = pd.DataFrame(f["tables/fpe"][:])
        tpa = pd.DataFrame(f["tables/tpa"][:])
    for t in (fpe, tpa):
        for c in ("env", "variant"):
            t[c] = t[c].str.decode("utf-8")
    checked = 0
    for (env, v, n), g in fpe.groupby(["env", "variant", "N"]):
        want = g.fpe.mean()
        got = drawn["fig4"][env][v][str(n)]
        assert abs(got - want) < 1e-12, (env, v, n, got, want)
        checked += 1
    main = tpa[(tpa.in_main == 1) & (tpa.best_mode == 1)]  # the engine marks the best mode
    for (env, v, n, m), g in main.groupby(["env", "variant", "N", "M"]):
        panels = [str(n)] if n > 0 else list(drawn["fig5"][env])  # N = 0 cells in every panel
        for panel in panels:
            got = drawn["fig5"][env][panel][v][str(m)]
            assert abs(got - g.tpa.mean()) < 1e-12, (env, v, n, m, got, g.tpa.mean())
            checked += 1
    assert checked > 50, checked
    print(f"ok: Figs. 4 and 5 drew the seed means of the tables ({checked} points checked)")

    # H1 per environment recomputed here from /tables/fpe with scipy's paired t-test and Holm by
    # hand: the verdict and the adjusted p of every comparison equal claims.json's (a report that
    # compared the wrong N, the wrong column or skipped the correction differs).
    reported = {(h["env"], h["claim"][:2]): h for h in
                json.load(open(os.path.join(tmp, "full", "claims.json")))}
    for env in sorted(fpe.env.unique()):
        if env == "grid2":
            continue
        d = fpe[fpe.env == env]
        nmax = d.N.max()
        at = lambda v: d[(d.variant == v) & ((d.N == nmax) | (d.N == 0))].set_index("seed").fpe.sort_index()
        ps, diffs = [], []
        for v in ["vae", "multipref10", "multipref50", "singlepref", "random"]:
            s, o = at("sirl"), at(v)
            ps.append(stats.ttest_rel(s, o).pvalue)
            diffs.append((s - o).mean())
        order = sorted(range(5), key=lambda i: ps[i])
        adj, run = [0.0] * 5, 0.0
        for r, i in enumerate(order):
            run = max(run, min(1.0, (5 - r) * ps[i]))
            adj[i] = run
        want = ("held" if all(q < 0.05 and x < 0 for q, x in zip(adj, diffs)) else
                "not held" if any(q < 0.05 and x > 0 for q, x in zip(adj, diffs)) else "inconclusive")
        h = reported[(env, "H1")]
        assert h["verdict"] == want, (env, h["verdict"], want)
        for c, q in zip(h["comparisons"], adj):
            assert abs(c["p_holm"] - q) < 1e-9, (env, c, q)
    print("ok: H1's verdicts and Holm p's equal a recomputation from /tables/fpe")

    # H1's "trainings converged" counts, recomputed from /tables/training by task key: the φ of
    # SIRL and of each preference baseline at the largest N, and every VAE of the environment.
    with h5py.File(full, "r") as f:
        tr = pd.DataFrame(f["tables/training"][:])
    conv = dict(zip(tr.key.str.decode("utf-8"), tr.converged))
    for env in sorted(fpe.env.unique()):
        if env == "grid2":
            continue
        nmax = fpe[fpe.env == env].N.max()
        keys = [k for k in conv if k.startswith(env + "/") and (
            k.endswith("/vae") or any(k.endswith(f"/{v}/N{nmax}/rep") and "/" + v + "/" in k
                                      for v in ("sirl", "multipref10", "multipref50", "singlepref")))]
        want = [int(sum(conv[k] for k in keys)), len(keys)]
        got = reported[(env, "H1")]["converged"]
        assert list(got) == want and want[1] > 0, (env, got, want, keys)
    print("ok: H1's trainings-converged counts equal a recount from /tables/training")

    # JacoRobot runs its ablation at another M than the top-level [ablation]: Fig. 7 must draw
    # the cells the file holds (16 + 4 bars: four methods × 4 configurations, VAE and Random × 2).
    over = os.path.join(tmp, "override.toml")
    with open(over, "w") as f:
        f.write(f'extends = "{SMOKE}"\n[jaco]\nablation_M = [80]\n')
    ov = os.path.join(tmp, "override.h5")
    sh(SIRL, "run", over, "--out", ov, "--quiet")
    sh("/usr/bin/python3", PLOT, ov, "--out", os.path.join(tmp, "ov"))
    fig7 = json.load(open(os.path.join(tmp, "ov", "figures.json")))["fig7"]
    assert fig7["jaco"]["M"] == [80] and fig7["grid"]["M"] == [40], fig7
    for env in ("grid", "jaco"):
        assert fig7[env]["bars"] == 20 and fig7[env]["missing"] == 0, (env, fig7[env])
    print("ok: Fig. 7 draws every ablation cell of the file, per environment:", fig7)

    part = os.path.join(tmp, "shard.h5")
    sh(SIRL, "run", SMOKE, "--out", part, "--shard", "0/2", "--quiet")
    sh("/usr/bin/python3", PLOT, part, "--out", os.path.join(tmp, "part"))
    rep = check_outputs(os.path.join(tmp, "part"))
    assert "missing" in rep or "not evaluated" in rep or "n/a" in rep, rep
    print("ok: a partial (one-shard) file plots, gaps noted")
print("PASS")
