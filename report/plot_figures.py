#!/usr/bin/python3
"""Draws the paper's figures and a report from a sirl-bench results file (HDF5 only).

    /usr/bin/python3 report/plot_figures.py RESULTS.h5 --out FIGURE_DIR

Writes fig3_grid_similar.{png,pdf}, fig4_fpe.{png,pdf}, fig5_tpa.{png,pdf} (the paper's TPA
protocol), fig5_tpa_linear.{png,pdf} (the linear protocol, when the file has it),
fig7_ablation.{png,pdf}, fig_learning_curves.{png,pdf}, fig_paths_<env>.{png,pdf} (the
trajectories seen from above, for an environment whose file stores 2-D points) and report.md
(+ report.html). Reads only the file: /tables/*, /runs/... and /datasets/... . Every figure plots
what the file holds (which cells belong to Fig. 5 or Fig. 7, which protocol fit them and which
rows are references are columns of /tables/tpa), never a re-reading of the profile. A partial
file (an interrupted run) plots with gaps and notes, never zeros; a protocol or reference the file
lacks is noted as not run.

The work is in four modules beside it: run_tables.py (the file's tables and environments),
figures.py (the figures), hypotheses.py (the claims decided) and report.py (the report).
"""

import argparse
import json
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import figures  # noqa: E402
import plot_beyond  # noqa: E402
import plot_hyper  # noqa: E402
import plot_paths  # noqa: E402
import report  # noqa: E402
import run_tables  # noqa: E402
from safe_output import write_text  # noqa: E402
import sirl_bench  # noqa: E402  (run_tables puts it on the path)


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("results", help="HDF5 results file written by `sirl run`")
    ap.add_argument("--out", required=True, help="directory for the figures and the report")
    a = ap.parse_args()
    if not os.path.exists(a.results):
        sys.exit(f"plot_figures: {a.results}: no such file")
    os.makedirs(a.out, exist_ok=True)
    try:
        res, t = run_tables.load(a.results)
    except sirl_bench.ResultsError as e:
        sys.exit(f"plot_figures: {e}")
    run_tables.load_envs(res)
    try:
        figures.load_styles(res)
    except sirl_bench.ResultsError as e:
        sys.exit(f"plot_figures: {e}")
    envs = [e for e in run_tables.ENV if any(not t[k].empty and (t[k].env == e).any()
                                  for k in ("fpe", "tpa", "training"))] or list(run_tables.ENV)[:1]
    notes = []
    if not t["tpa"].empty and "best_mode" not in t["tpa"]:
        # Which cells are a method's best mode is a column the engine writes (from 0.8.0 on);
        # this file predates it, and the rule is not restated here.
        msg = ("this file was written by an engine before 0.8.0: its tables carry no best_mode "
               "column, so Fig. 5 and H2 are not drawn; `sirl merge NEW.h5 THIS.h5` rewrites its "
               "tables with the current engine")
        notes.append(msg)
        print(f"plot_figures: {msg}", file=sys.stderr)
    prov = res.provenance
    if not prov.get("complete", 1):
        notes.append(f"partial run: {prov.get('tasks_done')} of {prov.get('tasks_total')} "
                     "tasks; missing cells are gaps, not zeros")
    shard = prov.get("shard", "")
    if shard:
        notes.append(f"this file is shard {shard} of a run: missing cells are in the other shards "
                     "(combine them with `sirl merge`)")
    fig3_key = figures.plot_fig3(res, a.out, notes)
    figures.plot_fig4(t["fpe"], envs, a.out, notes)
    for protocol in run_tables.PROTOCOLS:  # fig5_tpa (the paper's), fig5_tpa_linear
        figures.plot_fig5(t["tpa"], envs, a.out, notes, protocol)
    figures.plot_fig7(t["tpa"], envs, a.out, notes)
    figures.plot_learning_curves(res, t, envs, a.out, notes)
    beyond = {"active": plot_beyond.plot_active(t["fpe"], t["tpa"], a.out, notes, figures.DRAWN),
              "robustness": plot_beyond.plot_robustness(t["fpe"], t["tpa"], t["robust_fpe"],
                                                        t["robust_tpa"], a.out, notes, figures.DRAWN)}
    beyond["hyper"] = plot_hyper.plot_hyper(t["all_points"]["fpe"], t["all_points"]["tpa"],
                                            res.hyper_points, figures.STYLE, figures.ORDER,
                                            figures.mean_ci, figures.save, a.out,
                                            notes, figures.DRAWN)
    beyond["paths"] = plot_paths.plot_paths(res.datasets, a.out, figures.DRAWN)
    report.report(res, t, envs, a.out, notes, fig3_key, beyond)
    write_text(os.path.join(a.out, "figures.json"), json.dumps(figures.DRAWN, indent=1))
    print(f"plot_figures: wrote figures and report.md to {a.out}/")


def run():
    """main(), with whatever a file the engine did not write can still make go wrong (a table
    whose columns are not the engine's, values no figure expects) as one line and exit 1, never
    a traceback. SIRL_DEBUG=1 shows the traceback (for a file the engine did write: a bug)."""
    try:
        main()
    except sirl_bench.ResultsError as e:
        sys.exit(f"plot_figures: {e}")
    except Exception as e:  # noqa: BLE001 (any failure on untrusted input is one line)
        if os.environ.get("SIRL_DEBUG"):
            raise
        what = " ".join(str(e).split())[:300]
        sys.exit(f"plot_figures: {' '.join(sys.argv[1:2])}: cannot draw its figures "
                 f"({type(e).__name__}: {what}); if the engine wrote this file, this is a bug: "
                 "SIRL_DEBUG=1 shows the traceback")


if __name__ == "__main__":
    run()
