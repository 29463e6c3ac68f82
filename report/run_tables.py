"""The results file as the figure and report scripts read it: its cell tables (through
sirl_bench), its environments' registrations, and the cells of the paper's Fig. 5."""
import os
import sys

import pandas as pd

# The reader package: installed by scripts/setup.sh, or beside this folder in a checkout.
sys.path.insert(1, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "python"))
import sirl_bench  # noqa: E402

# Each environment's registration as the run stored it (attributes of /datasets/<env>: title,
# in_claims, fig3_rank, vae_weak_claim, view), so no environment name is spelled out here.
ENV = {}


def load_envs(res):
    for name, g in res.datasets.items():
        a = g["attrs"]
        ENV[name] = {"title": a.get("title", name), "in_claims": int(a.get("in_claims", 1)),
                     "fig3_rank": int(a.get("fig3_rank", 0)),
                     "vae_weak_claim": int(a.get("vae_weak_claim", 0))}


def env_title(env):
    return ENV.get(env, {}).get("title", env)


TABLES = ("fpe", "tpa", "timings", "training", "vae_latents", "robust_fpe", "robust_tpa")


def load(path):
    """The file through sirl_bench (typed tables; N and M are <NA> where a cell has none). The
    cell tables hold the base point of any hyper-parameter axis only (the paper's figures and
    claims); every point's rows are in t["all_points"]."""
    res = sirl_bench.open(path)
    t = {k: res.tables[k] if k in res.tables else pd.DataFrame() for k in TABLES}
    t["all_points"] = {k: t[k] for k in ("fpe", "tpa")}
    for k in ("fpe", "tpa", "training", "robust_fpe", "robust_tpa"):
        if "hyper_point" in t[k]:
            t[k] = t[k][t[k].hyper_point == ""]
    return res, t


def main_tpa(tpa):
    """Fig. 5's cells (the file marks them: in_main), each method in the paper's best mode (SIRL
    frozen, the others unfrozen)."""
    if tpa.empty:
        return tpa
    t = tpa[tpa["in_main"]] if "in_main" in tpa else tpa
    # best_mode: the file's (engines ≥ 0.8.0); older files have no such column
    return t[t["best_mode"]] if "best_mode" in t else t.iloc[0:0]
