#!/usr/bin/python3
"""The plotting tool on the output of the smoke profile's plan with narrow networks
(tests/data/engine-test.toml) (ctest): every figure and the report exist;
Fig. 7 draws the cells the file holds even when an environment overrides the ablation's M;
Fig. 3 is drawn on the simplified GridRobot; a partial file (one shard of two) still plots, with
the missing cells reported as gaps. The top-down view (fig_paths_<env>) is drawn for 2-D points
only, never for GridRobot or JacoRobot.

TPA protocols and references (issue 56), first on synthetic tables, then on the smoke file: Fig. 5
is drawn per protocol (fig5_tpa from the paper's rows only, fig5_tpa_linear from the linear
ones), Figs. 4 and 5 draw the references (truth φ*, raw input) as reference lines, never as
methods; adding linear and reference rows changes no paper figure; a file with one protocol
draws it and notes the other as not run; the report's table of every claim has one row per
claim × environment × protocol, a claim's linear row right after its paper twin.

The report's first screen: the title, a sentence on the run, then the main claims' table (one
column per environment × protocol of the file, each cell's verdict claims.json's), the legend of
⚠ and the metrics spelled out; report.html colours the verdict cells and has a table of contents
whose links land; the user study's H3/H4 are in the table of every claim, their verdicts those of
plot_study.py's study report."""
import json
import os
import re
import shutil
import subprocess
import sys
import tempfile

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import sirl_testing  # noqa: E402
from results_frame import reframe  # noqa: E402

import h5py
import numpy as np
import pandas as pd
from scipy import stats

SIRL = os.environ.get("SIRL", "sirl")  # ctest sets it; `figures.py FILE.h5` needs no binary
SRC = os.environ["SIRL_SOURCE_DIR"]
SMOKE = os.path.join(SRC, "tests", "data", "engine-test.toml")  # smoke's plan, narrow nets
PLOT = os.path.join(SRC, "report", "plot_figures.py")
FILES = [f"{n}.{e}" for n in ("fig3_grid_similar", "fig4_fpe", "fig5_tpa", "fig7_ablation",
                               "fig_learning_curves")
         for e in ("png", "pdf")] + ["report.md", "report.html", "figures.json", "claims.csv", "ledger.csv"]


def sh(*cmd):
    p = subprocess.run(cmd, capture_output=True, text=True, stdin=subprocess.DEVNULL)
    if p.returncode != 0:
        sys.exit(f"FAIL: {' '.join(cmd)} exited {p.returncode}\n{p.stdout}\n{p.stderr}")
    return p


def synthetic_tables():
    """FPE and TPA rows as the reader types them: the paper's main grid and ablation, the linear
    protocol's cells of every method, and the references (truth: paper and linear TPA, FPE; raw:
    linear TPA, FPE), N <NA> for the N-free ones."""
    rng = np.random.default_rng(7)
    base = {"sirl": 0.8, "vae": 0.6, "multipref10": 0.7, "singlepref": 0.65, "random": 0.68}
    F, T = [], []

    def row(**k):
        k.setdefault("method", k["variant"])
        k.setdefault("vae", k["variant"] == "vae")
        k.update(selection="uniform", teacher="")
        return k

    for env in ("grid", "jaco"):
        for s in range(3):
            for v, b in base.items():
                for N in ([None] if v in ("vae", "random") else [50, 100]):
                    F.append(row(env=env, variant=v, N=N, seed=s, fpe=1 - b + 0.01 * s, reference=False))
                    for M in (10, 40):
                        x = b + 0.01 * rng.standard_normal()
                        T.append(row(env=env, variant=v, N=N, M=M, seed=s, tpa=x, frozen=v == "sirl",
                                     in_main=True, in_ablation=False, best_mode=True,
                                     protocol="paper", reference=False))
                        if v not in ("vae", "random"):
                            T.append(row(env=env, variant=v, N=N, M=M, seed=s, tpa=x - 0.03,
                                         frozen=v != "sirl", in_main=False, in_ablation=True,
                                         best_mode=False, protocol="paper", reference=False))
                        T.append(row(env=env, variant=v, N=N, M=M, seed=s, tpa=0.2 + 0.01 * s,
                                     frozen=True, in_main=True, in_ablation=False, best_mode=True,
                                     protocol="linear", reference=False))
            for ref, f in (("truth", 0.0), ("raw", 0.9)):
                F.append(row(env=env, variant=ref, N=None, seed=s, fpe=f + 0.001 * s, reference=True))
                for M in (10, 40):
                    for protocol in (("paper", "linear") if ref == "truth" else ("linear",)):
                        T.append(row(env=env, variant=ref, N=None, M=M, seed=s,
                                     tpa=0.97 - 0.01 * s - (0.3 if ref == "raw" else 0), frozen=True,
                                     in_main=True, in_ablation=False, best_mode=True,
                                     protocol=protocol, reference=True))
    out = []
    for rows in (F, T):
        d = pd.DataFrame(rows)
        for c in ("N", "M"):
            if c in d:
                d[c] = d[c].astype("Int64")
        for c in ("vae", "frozen", "in_main", "in_ablation", "best_mode", "reference"):
            if c in d:
                d[c] = d[c].astype("boolean")
        out.append(d)
    return out


def check_synthetic(tmp):
    """Figs. 4, 5 and 7 on synthetic tables: what they drew (figures.DRAWN), per protocol, with
    the references apart from the methods."""
    sys.path.insert(0, os.path.join(SRC, "report"))
    import declared_methods
    import figures
    import run_tables
    run_tables.ENV.update({"grid": {"title": "GridRobot"}, "jaco": {"title": "JacoRobot"}})
    figures.load_styles(declared_methods.Declared)
    fpe, tpa = synthetic_tables()
    envs = ["grid", "jaco"]

    def draw(f, t, name):
        figures.DRAWN.clear()
        out, notes = os.path.join(tmp, name), []
        os.makedirs(out)
        figures.plot_fig4(f, envs, out, notes)
        for protocol in run_tables.PROTOCOLS:
            figures.plot_fig5(t, envs, out, notes, protocol)
        figures.plot_fig7(t, envs, out, notes)
        return json.loads(json.dumps(figures.DRAWN)), notes, out

    drawn, notes, out = draw(fpe, tpa, "syn")
    for f in ("fig4_fpe.png", "fig5_tpa.png", "fig5_tpa_linear.png", "fig7_ablation.png"):
        assert os.path.getsize(os.path.join(out, f)) > 200, f
    refs = {"truth", "raw"}
    for key in ("fig4", "fig5", "fig5_linear"):
        for env, panels in drawn[key].items():
            for panel in (panels.values() if key != "fig4" else [panels]):
                assert not refs & set(panel), (key, env, panel.keys())
    assert set(drawn["fig4_references"]["grid"]) == refs, drawn["fig4_references"]
    want = fpe[(fpe.env == "grid") & (fpe.variant == "raw")].fpe.mean()
    assert abs(drawn["fig4_references"]["grid"]["raw"]["0"] - want) < 1e-12
    # Fig. 5: each protocol's figure from its own rows; every panel of an environment carries its
    # references (the paper's protocol has no raw-input cells: truth only).
    for protocol, key in (("paper", "fig5"), ("linear", "fig5_linear")):
        d = tpa[(tpa.protocol == protocol) & tpa.in_main & tpa.best_mode]
        n = 0
        for (env, v, N, M), g in d[~d.reference].groupby(["env", "variant", "N", "M"], dropna=False):
            panels = [str(N)] if not pd.isna(N) else list(drawn[key][env])
            for panel in panels:
                assert abs(drawn[key][env][panel][v][str(M)] - g.tpa.mean()) < 1e-12, (key, env, v, N, M)
                n += 1
        for (env, v, M), g in d[d.reference].groupby(["env", "variant", "M"]):
            for panel in drawn[key][env]:
                assert abs(drawn[key + "_references"][env][panel][v][str(M)] - g.tpa.mean()) < 1e-12
                n += 1
        assert n > 40, (protocol, n)
    assert set(drawn["fig5_references"]["grid"]["50"]) == {"truth"}, drawn["fig5_references"]
    assert set(drawn["fig5_linear_references"]["jaco"]["100"]) == refs
    assert drawn["fig5_protocols"] == {"paper": "fig5_tpa", "linear": "fig5_tpa_linear"}
    # The paper's figures are those of the tables without the new rows.
    plain, _, _ = draw(fpe[~fpe.reference], tpa[(tpa.protocol == "paper") & ~tpa.reference], "plain")
    for key in ("fig4", "fig5", "fig7"):
        assert plain[key] == drawn[key], key
    assert plain["fig5_protocols"]["linear"] == "not run" and "fig5_linear" not in plain
    # One protocol run (a profile's [tpa] protocols = ["linear"]): the paper's Fig. 5 and Fig. 7
    # are noted, not drawn, and nothing crashes.
    lin, notes, out = draw(fpe, tpa[tpa.protocol == "linear"], "linear-only")
    assert lin["fig5_protocols"] == {"paper": "not run", "linear": "fig5_tpa_linear"}, lin
    assert "fig5" not in lin and "fig7" not in lin and lin["fig5_linear"] == drawn["fig5_linear"]
    assert any("Fig. 5: not run" in n for n in notes), notes
    assert not os.path.exists(os.path.join(out, "fig5_tpa.png"))
    none, notes, _ = draw(fpe[~fpe.reference], tpa[~tpa.reference], "no-references")
    assert "fig4_references" not in none and "fig5_references" not in none
    assert any("Fig. 4: the references" in n and "not run" in n for n in notes), notes
    print("ok: synthetic tables: Fig. 5 per protocol from its own rows, truth and raw drawn as "
          "reference lines only; the paper's figures unchanged by the new rows; one protocol "
          "or no references: noted as not run")


def check_paths(tmp):
    """The top-down view (plot_paths.py) on synthetic /datasets groups: one figure per
    environment with 2-D points, one panel per true feature (four at most), the first 40
    trajectories, the unit on the colour bar; 3-D points and no points draw nothing; the report
    embeds each figure drawn."""
    sys.path.insert(0, os.path.join(SRC, "report"))
    import plot_paths
    import report
    rng = np.random.default_rng(3)
    flat = rng.random((50, 51, 2)).astype(np.float32)
    attrs = {"title": "Flat", "features_raw.feature_names": list("abcde"),
             "features_raw.units": ["", "m", "", "", ""]}
    ds = {"flat": {"attrs": attrs, "points": flat, "features_raw": rng.random((50, 5))},
          "solid": {"attrs": {}, "points": rng.random((50, 9, 3)), "features_raw": rng.random((50, 2))},
          "none": {"attrs": {}, "features_raw": rng.random((50, 2))}}
    out, drawn = os.path.join(tmp, "paths"), {}
    os.makedirs(out)
    assert plot_paths.plot_paths(ds, out, drawn) == ["flat"], drawn
    assert drawn["fig_paths"] == {"flat": {"file": "fig_paths_flat", "trajectories": 40,
                                           "features": ["a", "b [m]", "c", "d"]}}, drawn
    assert sorted(f for f in os.listdir(out)) == ["fig_paths_flat.pdf", "fig_paths_flat.png"]
    assert report.paths_lines(["flat"], out)[0].endswith("(fig_paths_flat.png)")
    print("ok: top-down view drawn for 2-D points only (4 panels, 40 trajectories), in the report")


def check_outputs(d):
    for f in FILES:
        p = os.path.join(d, f)
        if not os.path.exists(p) or os.path.getsize(p) < 200:
            sys.exit(f"FAIL: {p} missing or empty")
    # claims.csv: one row per (claim, comparison) of claims.json, the same verdicts and p's.
    claims = json.load(open(os.path.join(d, "claims.json")))
    rows = pd.read_csv(os.path.join(d, "claims.csv"))
    want = [(h["claim"], h["verdict"], c.get("p")) for h in claims for c in (h["comparisons"] or [{}])]
    got = list(zip(rows["claim"], rows["verdict"], rows["p"]))
    assert len(got) == len(want) and all(
        a[:2] == b[:2] and (b[2] is None and pd.isna(a[2]) or abs(a[2] - b[2]) <= 1e-12 * abs(b[2]))
        for a, b in zip(got, want)), (got[:3], want[:3])
    return open(os.path.join(d, "report.md")).read()


def decoded(f, name):
    """A table as stored (strings decoded; flags 0/1, N and M 0 where a cell has none)."""
    t = pd.DataFrame(f["tables/" + name][:])
    for c in t.columns:
        if t[c].dtype == object:
            t[c] = t[c].str.decode("utf-8")
    return t


def holm_verdict(ps, diffs, better):
    """Holm's adjusted p's by hand and the verdict they give."""
    m = len(ps)
    order = sorted(range(m), key=lambda i: ps[i])
    adj, run = [0.0] * m, 0.0
    for r, i in enumerate(order):
        run = max(run, min(1.0, (m - r) * ps[i]))
        adj[i] = run
    way = (lambda x: x < 0) if better == "<" else (lambda x: x > 0)
    want = ("held" if all(q < 0.05 and way(x) for q, x in zip(adj, diffs)) else
            "not held" if any(q < 0.05 and not way(x) and x != 0 for q, x in zip(adj, diffs))
            else "inconclusive")
    return adj, want


def without_new_rows(src, dst):
    """A copy of results file src as an engine before issue 56 wrote it: /tables/fpe and tpa
    without the linear protocol's rows, the references' rows and the two columns."""
    shutil.copy(src, dst)
    with h5py.File(dst, "r+") as f:
        for name in ("fpe", "tpa"):
            a = f["tables/" + name][:]
            keep = np.ones(len(a), bool)
            if "reference" in a.dtype.names:
                keep &= a["reference"] == 0
            if "protocol" in a.dtype.names:
                keep &= a["protocol"] == b"paper"
            cols = [c for c in a.dtype.names if c not in ("reference", "protocol")]
            b = np.empty(int(keep.sum()), dtype=[(c, a.dtype[c]) for c in cols])
            for c in cols:
                b[c] = a[c][keep]
            del f["tables/" + name]
            f.create_dataset("tables/" + name, data=b)
    reframe(dst)  # that engine framed what it wrote


def report_section(rep, title):
    """The text of the report's section whose heading starts with `title`, to the next one."""
    return rep.split("\n## " + title, 1)[1].split("\n## ", 1)[0]


def md_table(text, header):
    """The Markdown table of `text` whose header line starts with `header`: its header cells
    and its rows' cells."""
    lines = text.splitlines()
    i = next(k for k, ln in enumerate(lines) if ln.startswith(header))
    split = lambda ln: [c.strip() for c in ln.strip()[1:-1].split(" | ")]  # noqa: E731
    body = []
    for ln in lines[i + 2:]:
        if not ln.startswith("| "):
            break
        body.append(split(ln))
    return split(lines[i]), body


VERDICT_CLASS = {"held": "v-held", "not held": "v-not-held", "inconclusive": "v-inconclusive",
                 "not run": "v-none", "not evaluated": "v-none"}


def check_first_screen(rep, page, claims, titles):
    """The report opens with the title, the run's sentence and the main claims' table: one column
    per environment × protocol of the file (the paper's first; H1 in its columns, FPE having one
    protocol), each cell's verdict (and ⚠) claims.json's; then the legend of the verdicts and of
    ⚠, and FPE, TPA, N and M spelled out. In report.html every verdict cell carries its verdict's
    class and a table of contents after the main claims links every section."""
    lines = rep.splitlines()
    assert lines[0].startswith("# sirl-bench report: profile") and lines[1] == "", lines[:2]
    assert lines[2].startswith("This run: profile `") and "tasks done" in lines[2], lines[2]
    assert lines[3] == "" and lines[4].startswith("| main claim |"), lines[3:5]
    mains = [h for h in claims if h["main"]]
    envs = list(dict.fromkeys(h["env"] for h in mains))
    protocols = ["paper"] + [p for p in ("linear",) if any(
        h["protocol"] == p and h["verdict"] != "not run" for h in mains)]
    cols = [(e, p) for p in protocols for e in envs]
    head, rows = md_table(rep, "| main claim |")
    assert head == ["main claim"] + [f"{titles[e]}, paper protocol" if p == "paper" else
                                     f"{titles[e]}, {p} (secondary)" for e, p in cols] + \
        ["the paper"], head
    assert [re.match(r"\*\*(H[12])\*\* — ", r[0]).group(1) for r in rows] == ["H1", "H2"], rows
    verdicts = []
    for r in rows:
        family = r[0][2:4]
        assert r[-1].startswith("held in both environments at N = 1000: “"), r[-1]
        for (env, p), cell in zip(cols, r[1:-1]):
            if family == "H1" and p != "paper":
                assert cell == "(FPE has one protocol)", cell
                continue
            h = next(h for h in mains if h["env"] == env and h["claim"][:2] == family
                     and h["protocol"] == (None if family == "H1" else p))
            m = re.match(r"\*\*([^*]+)\*\*( ⚠)?: \S", cell)
            assert m and m.group(1) == h["verdict"], (env, p, family, cell, h["verdict"])
            conv = h.get("converged")
            assert bool(m.group(2)) == bool(conv and conv[0] < conv[1]), (cell, conv)
            verdicts.append(h["verdict"])
    opening = rep[:rep.index("\n## ")]
    for text in ("*held*: SIRL beat every baseline", "*inconclusive*: neither",
                 "**⚠**: some of the trainings the verdict rests on had not converged",
                 "the verdict is provisional", "**FPE** (feature prediction error):",
                 "lower is better", "**TPA** (test preference accuracy):", "higher is better",
                 "**N**: the queries φ is trained on", "**M**: the preference pairs"):
        assert text in opening, f"the first screen lacks {text!r}"
    assert rep.index("| main claim |") < rep.index("## Every claim") < rep.index(
        "| claim | environment | protocol | verdict") < rep.index("## Paper says, we find") < \
        rep.index("## Figures") < rep.index("## Configuration"), \
        "report order: main claims, every claim, ledger, figures, …, profile"

    # report.html: the page opens with the title, the sentence and #main-claims; its verdict
    # cells carry their verdict's class; the contents sit between it and the first section.
    body = page[page.index("<body>") + 6:]
    assert re.match(r"<h1>[^<]*</h1>\s*<p>This run: profile .*?</p>\s*<table id=\"main-claims\">",
                    body, re.S), body[:500]
    table = body[body.index('<table id="main-claims">'):body.index("</table>")]
    got = re.findall(r'<td class="([^"]*)"><strong>([^<]*)</strong>', table)
    assert [v for _, v in got] == verdicts and all(VERDICT_CLASS[v] == c for c, v in got), \
        (got, verdicts)
    summary = body[body.index('<table id="summary">'):]
    summary = summary[:summary.index("</table>")]
    assert len(re.findall(r'<td class="v-[a-z-]+"><strong>', summary)) >= len(claims), summary[:400]
    nav = body[body.index('<nav id="contents">'):body.index("</nav>")]
    links = re.findall(r'<a href="#([^"]+)">', nav)
    h2 = re.findall(r'<h2 id="([^"]+)">', body)
    ids = set(re.findall(r' id="([^"]+)"', body))
    assert links == h2 and set(links) <= ids and len(links) >= 8, (links, h2)
    assert body.index('<table id="main-claims">') < body.index('<nav id="contents">') < \
        body.index("<h2"), "the contents are not between the main claims and the first section"
    figs = re.findall(r'<p class="figure"><a href="([^"]+)"><img [^>]*src="([^"]+)"', body)
    assert figs and all(a == b for a, b in figs), figs
    print(f"ok: the first screen: the main claims ({len(rows)} × {len(cols)} cells, verdicts and ⚠ "
          f"those of claims.json, coloured by verdict), the legend, FPE, TPA, N and M spelled "
          f"out; report.html's contents link its {len(links)} sections; figures open full size")


STUDY_ROWS = {"U01": "H3:", "U02": "own answers", "U03": "Held-out", "U04": "Simulated"}
LEDGER_TO_CLAIM = {"confirmed": "held", "contradicted": "not held", "undecided": "inconclusive",
                   "not run": "not run"}


def check_study_claims(rep, full, tmp):
    """The user study's H3 and H4 are rows of the table of every claim, their verdicts the
    ledger's U01–U04 in the claims' words and those of plot_study.py's study report (all
    participants) drawn from the same file."""
    book = json.load(open(os.path.join(tmp, "full", "ledger.json")))["statements"]
    study = {r["id"]: r for r in book if r["env"] == "study"}
    _, rows = md_table(report_section(rep, "Every claim"), "| claim | environment | protocol | verdict")
    rows = [r for r in rows if r[1] == "user study (simulated cohort)"]
    if not study:
        assert not rows and "this profile ran no study" in rep, rows
        return
    sh("/usr/bin/python3", os.path.join(SRC, "report", "plot_study.py"), full, "--out",
       os.path.join(tmp, "study"))
    theirs = open(os.path.join(tmp, "study", "study_report.md")).read()
    # Its H3 line, then its H4 lines over all participants: Real (own answers), Held-out,
    # Simulated, in that order.
    h3 = re.findall(r"\*\*H3 — [^*]*: ([a-z ]+)\*\*", theirs)
    h4 = re.findall(r"\*\*H4 — [^*]*, all participants: ([a-z ]+)\*\*", theirs)
    assert len(h3) == 1 and len(h4) == 3, (h3, h4)
    want = dict(zip(("U01", "U02", "U03", "U04"), h3 + h4))
    assert len(rows) == len(study) == 4, (rows, sorted(study))
    for sid, r in study.items():
        row = next(x for x in rows if STUDY_ROWS[sid] in x[0])
        verdict = row[3].strip("*")
        assert verdict == LEDGER_TO_CLAIM[r["verdict"]], (sid, row, r["verdict"])
        assert r["verdict"] == "not run" or verdict == want[sid], (sid, verdict, want[sid])
    print("ok: the user study's H3 and H4 are in the claims table, their verdicts the ledger's and "
          "plot_study.py's")


def check_smoke(full, tmp):
    """The figures and the report of a smoke results file."""
    sh("/usr/bin/python3", PLOT, full, "--out", os.path.join(tmp, "full"))
    rep = check_outputs(os.path.join(tmp, "full"))
    for claim in ("H1", "H2", "SIRL is better frozen", "Random beats preference"):
        assert claim in rep, f"report lacks {claim}"
    assert "paired t-test" in rep and "p = " in rep and "Holm p" in rep
    # The main claims open the report; the table of every claim, the ledger and the figures
    # follow; the profile's text closes it.
    sys.path.insert(0, os.path.join(SRC, "python"))
    import sirl_bench
    with sirl_bench.open(full) as r:
        titles = {e: g["attrs"].get("title", e) for e, g in r.datasets.items()}
    check_first_screen(rep, open(os.path.join(tmp, "full", "report.html")).read(),
                       json.load(open(os.path.join(tmp, "full", "claims.json"))), titles)
    check_study_claims(rep, full, tmp)
    # The page a reader opens, in chromium: the main claims first, coloured, the contents' links
    # land, real tables, every image loaded.
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
    # GridRobot and JacoRobot store no points: no top-down view.
    assert "fig_paths" not in drawn and "fig_paths_" not in rep
    assert not [f for f in os.listdir(os.path.join(tmp, "full")) if f.startswith("fig_paths_")]
    print("ok: every figure and the report from the smoke run; Fig. 3 on grid2")

    # What Figs. 4 and 5 drew equals the seed means computed here from the tables (a plot of the
    # wrong column, of train_mse, of the ablation's cells or of the other frozen mode differs):
    # the methods' rows as methods, the references' (truth φ*, raw input) as reference lines
    # only, and Fig. 5 once per TPA protocol from that protocol's rows.
    with h5py.File(full, "r") as f:
        fpe, tpa = decoded(f, "fpe"), decoded(f, "tpa")
    for t in (fpe, tpa):
        if "reference" not in t:  # a file of an engine before the references
            t["reference"] = 0
    if "protocol" not in tpa:
        tpa["protocol"] = "paper"
    checked = 0
    for (env, v, n, ref), g in fpe.groupby(["env", "variant", "N", "reference"]):
        want = g.fpe.mean()
        got = (drawn["fig4_references"][env][v]["0"] if ref else drawn["fig4"][env][v][str(n)])
        assert abs(got - want) < 1e-12, (env, v, n, got, want)
        assert not ref or (n == 0 and v not in drawn["fig4"][env]), (env, v, n)
        checked += 1
    protocols = [p for p in ("paper", "linear") if (tpa.protocol == p).any()]
    for protocol in protocols:
        key = "fig5" if protocol == "paper" else f"fig5_{protocol}"
        d = tpa[tpa.protocol == protocol]
        main = d[(d.in_main == 1) & (d.best_mode == 1) & (d.reference == 0)]  # the engine marks them
        if protocol != "paper":
            assert (main.frozen == 1).all() and not (d.in_ablation == 1).any(), protocol
        for (env, v, n, m), g in main.groupby(["env", "variant", "N", "M"]):
            panels = [str(n)] if n > 0 else list(drawn[key][env])  # N = 0 cells in every panel
            for panel in panels:
                got = drawn[key][env][panel][v][str(m)]
                assert abs(got - g.tpa.mean()) < 1e-12, (key, env, v, n, m, got, g.tpa.mean())
                checked += 1
        for (env, v, m), g in d[d.reference == 1].groupby(["env", "variant", "M"]):
            assert (g.N == 0).all() and v not in {x for pn in drawn[key][env].values() for x in pn}
            for panel in drawn[key][env]:
                got = drawn[key + "_references"][env][panel][v][str(m)]
                assert abs(got - g.tpa.mean()) < 1e-12, (key, env, v, m, got, g.tpa.mean())
                checked += 1
    assert checked > 50, checked
    assert {p for p, f in drawn["fig5_protocols"].items() if f != "not run"} == set(protocols), \
        drawn["fig5_protocols"]
    print(f"ok: Figs. 4 and 5 drew the seed means of the tables, Fig. 5 for protocol(s) "
          f"{', '.join(protocols)}, the references {sorted(set(fpe[fpe.reference == 1].variant))} "
          f"as lines ({checked} points checked)")

    # H1 per environment recomputed here from /tables/fpe with scipy's paired t-test and Holm by
    # hand: the verdict and the adjusted p of every comparison equal claims.json's (a report that
    # compared the wrong N, the wrong column or skipped the correction differs). H2 likewise per
    # TPA protocol from that protocol's main cells.
    claims = json.load(open(os.path.join(tmp, "full", "claims.json")))
    reported = {(h["env"], h["claim"][:2], h["protocol"]): h for h in claims}
    baselines = ["vae", "multipref10", "multipref50", "singlepref", "random"]
    for env in sorted(fpe.env.unique()):
        if env == "grid2":
            continue
        d = fpe[(fpe.env == env) & (fpe.reference == 0)]
        nmax = d.N.max()
        at = lambda v: d[(d.variant == v) & ((d.N == nmax) | (d.N == 0))].set_index("seed").fpe.sort_index()
        ps = [stats.ttest_rel(at("sirl"), at(v)).pvalue for v in baselines]
        adj, want = holm_verdict(ps, [(at("sirl") - at(v)).mean() for v in baselines], "<")
        h = reported[(env, "H1", None)]
        assert h["verdict"] == want, (env, h["verdict"], want)
        for c, q in zip(h["comparisons"], adj):
            assert abs(c["p_holm"] - q) < 1e-9, (env, c, q)
        # H2 is one claim decided under every protocol: Holm runs over all their comparisons.
        per = {}
        for protocol in protocols:
            d = tpa[(tpa.env == env) & (tpa.protocol == protocol) & (tpa.in_main == 1)
                    & (tpa.best_mode == 1) & (tpa.reference == 0)]
            nmax = d.N.max()
            at = lambda v: d[(d.variant == v) & ((d.N == nmax) | (d.N == 0))].groupby("seed").tpa.mean()
            have = [v for v in baselines if (d.variant == v).any()]
            per[protocol] = (have, [stats.ttest_rel(at("sirl"), at(v)).pvalue for v in have],
                             [(at("sirl") - at(v)).mean() for v in have])
        all_ps = [p for protocol in protocols for p in per[protocol][1]]
        all_adj, _ = holm_verdict(all_ps, [0.0] * len(all_ps), ">")
        start = 0
        for protocol in protocols:
            have, ps, diffs = per[protocol]
            adj = all_adj[start:start + len(ps)]
            start += len(ps)
            way = [q < 0.05 and x > 0 for q, x in zip(adj, diffs)]
            want = ("held" if all(way) else
                    "not held" if any(q < 0.05 and x < 0 for q, x in zip(adj, diffs))
                    else "inconclusive")
            h = reported[(env, "H2", protocol)]
            assert [c["name"] for c in h["comparisons"]] == have, (env, protocol, h["comparisons"])
            if all(np.isfinite(all_ps)):  # else the report's exact sign test decides
                assert h["verdict"] == want, (env, protocol, h["verdict"], want)
                for c, q in zip(h["comparisons"], adj):
                    assert abs(c["p_holm"] - q) < 1e-9, (env, protocol, c, q)
    names = {c["name"] for h in claims for c in h["comparisons"]}
    assert not names & {"truth", "raw"}, names
    _, rows = md_table(report_section(rep, "Every claim"), "| claim | environment | protocol | verdict")
    # The protocol column: "paper (primary; its head as run against the paper's)", "linear
    # (secondary)", "—" for FPE claims.
    cells = [r[2].split(" (")[0] for r in rows]
    assert {"—", "paper"} <= set(cells) <= {"—", "paper", "linear"}, cells
    full_cells = [r[2] for r in rows]
    assert all(("primary;" in c and "epochs" in c) for c in full_cells if c.startswith("paper")), full_cells
    assert all(c == "linear (secondary)" for c in full_cells if c.startswith("linear")), full_cells
    # The main claims first; a claim's linear row right after its paper twin (same claim, same
    # environment), so the two protocols of a claim are read together.
    main = [r[0].startswith("**") for r in rows]
    assert main == sorted(main, reverse=True) and sum(main) == sum(h["main"] for h in claims), main
    for i, c in enumerate(cells):
        if c == "linear":
            prev = rows[i - 1]
            assert cells[i - 1] == "paper" and prev[1] == rows[i][1] and (
                prev[0] == rows[i][0] or prev[0][:4] == rows[i][0][:4] == "**H2"), (prev, rows[i])
    print(f"ok: H1's and H2's verdicts and Holm p's ({', '.join(protocols)} protocol) equal a "
          "recomputation from the tables; the claims table lists the main claims first, each "
          "claim's linear row after its paper twin")

    # H1's "trainings converged" counts, recomputed from /tables/training's columns: the φ of
    # SIRL and of each preference baseline at the largest N, and every VAE of the environment.
    with h5py.File(full, "r") as f:
        tr = decoded(f, "training")
    sys.path.insert(0, os.path.join(SRC, "python"))
    import sirl_bench
    with sirl_bench.open(full) as r:
        recs = r.records
    for env in sorted(fpe.env.unique()):
        if env == "grid2":
            continue
        nmax = fpe[(fpe.env == env) & (fpe.reference == 0)].N.max()
        t = tr[(tr.env == env) & (tr.teacher == "")]
        use = t[(t.kind == "vae") | ((t.kind == "rep") & (t.N == nmax) & t.variant.isin(
            ["sirl", "multipref10", "multipref50", "singlepref"]))]
        want = [int(use.converged.sum()), len(use)]
        got = reported[(env, "H1", None)]["converged"]
        assert list(got) == want and want[1] > 0, (env, got, want)
        if "linear" in protocols:  # H2 (linear): those and the Newton fits of its cells
            d = tpa[(tpa.env == env) & (tpa.protocol == "linear") & (tpa.reference == 0)]
            nmax = d.N.max()
            compared = ["sirl"] + baselines
            fits = recs[(recs.protocol == "linear") & (recs.env == env) & (recs.teacher == "")
                        & recs.variant.isin(compared) & ((recs.N == nmax) | recs.N.isna())]
            use = t[(t.kind == "vae") | ((t.kind == "rep") & (t.N == nmax) & t.variant.isin(compared))]
            want = [int(use.converged.sum() + fits.newton_converged.sum()), len(use) + len(fits)]
            got = reported[(env, "H2", "linear")]["converged"]
            assert list(got) == want and len(fits) > 0, (env, got, want)
    print("ok: H1's (and the linear H2's, with its Newton fits) trainings-converged counts equal "
          "a recount from /tables/training (and the records)")

    # The same file as an engine before the protocols and references wrote it: every FPE and
    # paper-protocol claim, and Figs. 4, 5 (paper) and 7, are the same numbers.
    old = os.path.join(tmp, "old.h5")
    without_new_rows(full, old)
    sh("/usr/bin/python3", PLOT, old, "--out", os.path.join(tmp, "old"))
    was = json.load(open(os.path.join(tmp, "old", "claims.json")))
    was_drawn = json.load(open(os.path.join(tmp, "old", "figures.json")))
    paper = [h for h in claims if h["protocol"] != "linear"]

    def unadjusted(h, across):
        """A claim without what Holm across protocols changes (its adjusted p's and what they
        decide), for the claims whose linear twin exists in one file and not in the other."""
        if not across:
            return h
        h = {k: v for k, v in h.items() if k not in ("verdict", "power", "seeds80", "holm_across")}
        h["comparisons"] = [{k: v for k, v in c.items() if k != "p_holm"} for c in h["comparisons"]]
        return h
    across = [bool(h.get("holm_across")) for h in paper]
    assert [unadjusted(h, x) for h, x in zip(paper, across)] == \
        [unadjusted(h, x) for h, x in zip([h for h in was if h["protocol"] != "linear"], across)], \
        "paper claims changed"
    for key in ("fig4", "fig5", "fig7"):
        assert drawn.get(key) == was_drawn.get(key), key
    assert "fig4_references" not in was_drawn and was_drawn["fig5_protocols"]["linear"] == "not run"
    assert all(h["verdict"] == "not run" for h in was if h["protocol"] == "linear")
    # Its main claims' table: the paper protocol's columns only (no protocol ran the others).
    was_head, _ = md_table(open(os.path.join(tmp, "old", "report.md")).read(), "| main claim |")
    assert was_head[1:-1] == [c for c in md_table(rep, "| main claim |")[0][1:-1]
                              if c.endswith("paper protocol")], was_head
    print(f"ok: the {len(paper)} FPE and paper-protocol claims and Figs. 4, 5, 7 equal those of "
          "the file without the linear and reference rows (an older engine's)")


if __name__ == "__main__" and len(sys.argv) > 1:  # a results file given: its checks only
    with tempfile.TemporaryDirectory() as tmp:
        check_synthetic(tmp)
        check_paths(tmp)
        check_smoke(sys.argv[1], tmp)
    print("PASS")
    sys.exit(0)

with tempfile.TemporaryDirectory() as tmp:
    check_synthetic(tmp)
    check_paths(tmp)
    full = os.path.join(tmp, "smoke.h5")
    # The engine-test fixture's file and a copy of its cache (the runs below reuse what they
    # share with it); without the fixture, computed here.
    if sirl_testing.copy_fixture("engine-test", full, with_file=True, with_cache=False):
        cache = os.path.join(tmp, "engine-test.tasks")
        sirl_testing.copy_fixture("engine-test", with_file=False, cache_dest=cache)
        reuse = ["--cache", cache]
    else:
        sh(SIRL, "run", SMOKE, "--out", full, "--quiet")
        reuse = []
    check_smoke(full, tmp)

    # `sirl show`: the file summarised, its verdicts those of the report beside it.
    os.symlink(os.path.join(tmp, "full"), os.path.join(tmp, "smoke-figures"))
    shown = json.loads(subprocess.run([SIRL, "show", full, "--json"], capture_output=True,
                                      text=True, check=True).stdout)
    import sirl_bench
    with sirl_bench.open(full) as res:  # the reader's records: an independent count
        kinds = {k: int(n) for k, n in res.records["kind"].value_counts().items()}
    # The run's profile is SMOKE's (engine-test: smoke's plan with narrow networks).
    assert shown["profile"] == "engine-test" and shown["verified"], shown
    assert shown["tasks"] == {"done": sum(kinds.values()), "total": sum(kinds.values()),
                              "complete": True}, (shown["tasks"], kinds)
    assert shown["task_kinds"] == kinds, (shown["task_kinds"], kinds)
    assert shown["environments"] == ["grid", "grid2", "jaco"], shown["environments"]
    claims = json.load(open(os.path.join(tmp, "full", "claims.json")))
    assert [(v["env"], v["verdict"]) for v in shown["verdicts"]] == [
        (h["env"], h["verdict"]) for h in claims if h["main"]], shown["verdicts"]
    text = subprocess.run([SIRL, "show", full], capture_output=True, text=True, check=True).stdout
    assert "main claims" in text and f"{sum(kinds.values())} of {sum(kinds.values())} done" in text
    # Verdicts are stored by `sirl reproduce` only (reproduce_prediction checks them): the file
    # of `sirl run` has none, and the reader says so in one line rather than returning nothing.
    try:
        sirl_bench.claims(full)
        raise AssertionError("claims() of a file without stored verdicts returned")
    except sirl_bench.ResultsError as e:
        assert "no verdicts stored" in str(e) and "\n" not in str(e), e
    assert len(sirl_bench.claims(os.path.join(tmp, "full"))) == len(claims)
    print(f"ok: sirl show summarises the file ({sum(kinds.values())} tasks, "
          f"{len(shown['verdicts'])} main verdicts from the report beside it)")

    # JacoRobot runs its ablation at another M than the top-level [ablation]: Fig. 7 must draw
    # the cells the file holds (16 + 4 bars: four methods × 4 configurations, VAE and Random × 2).
    over = os.path.join(tmp, "override.toml")
    with open(over, "w") as f:
        f.write(f'extends = "{SMOKE}"\n[jaco]\nablation_M = [80]\n')
    ov = os.path.join(tmp, "override.h5")
    sh(SIRL, "run", over, "--out", ov, "--quiet", *reuse)
    # Links planted at the names the figures take (issue 65: savefig and open() wrote through
    # them): each is replaced by the figure, its target left as it was.
    os.makedirs(os.path.join(tmp, "ov"))
    planted = ("report.md", "report.html", "figures.json", "claims.json", "fig4_fpe.png",
               "fig7_ablation.pdf")
    for name in planted:
        with open(os.path.join(tmp, "victim-" + name), "w") as f:
            f.write("the user's " + name)
        os.symlink(os.path.join(tmp, "victim-" + name), os.path.join(tmp, "ov", name))
    sh("/usr/bin/python3", PLOT, ov, "--out", os.path.join(tmp, "ov"))
    for name in planted:
        assert open(os.path.join(tmp, "victim-" + name)).read() == "the user's " + name, name
        assert not os.path.islink(os.path.join(tmp, "ov", name)), name
        assert os.path.getsize(os.path.join(tmp, "ov", name)) > 100, name
    assert not [n for n in os.listdir(os.path.join(tmp, "ov")) if n.endswith(".tmp")]
    print("ok: links planted at six figure and report names are replaced, never written through")
    fig7 = json.load(open(os.path.join(tmp, "ov", "figures.json")))["fig7"]
    assert fig7["jaco"]["M"] == [80] and fig7["grid"]["M"] == [40], fig7
    for env in ("grid", "jaco"):
        assert fig7[env]["bars"] == 20 and fig7[env]["missing"] == 0, (env, fig7[env])
    print("ok: Fig. 7 draws every ablation cell of the file, per environment:", fig7)

    part = os.path.join(tmp, "shard.h5")
    sh(SIRL, "run", SMOKE, "--out", part, "--shard", "0/2", "--quiet", *reuse)
    sh("/usr/bin/python3", PLOT, part, "--out", os.path.join(tmp, "part"))
    rep = check_outputs(os.path.join(tmp, "part"))
    assert "missing" in rep or "not evaluated" in rep or "n/a" in rep, rep
    print("ok: a partial (one-shard) file plots, gaps noted")
print("PASS")
