"""The results file as the figure and report scripts read it: its cell tables (through
sirl_bench), its environments' registrations, and the cells of the paper's Fig. 5.

/tables/tpa holds every TPA protocol's cells (column `protocol`: "paper", "linear") and
/tables/fpe and tpa the references' rows (column `reference`: truth φ*, raw input). Every
consumer selects with of_protocol (the paper's where the paper's figures and claims were drawn
before the protocols), and with methods / references: a reference is never a method."""
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
                     "vae_weak_claim": int(a.get("vae_weak_claim", 0)),
                     "beyond_paper": bool(a.get("beyond_paper", False))}


def env_title(env):
    return ENV.get(env, {}).get("title", env)


def beyond_paper(env):
    """Not one of the paper's environments (read from a file, or from other work): the paper
    made no statement about it, so the claims decided on it are this benchmark's findings."""
    return ENV.get(env, {}).get("beyond_paper", False)


def claim_env_title(env):
    """The environment's title where a claim's verdict is shown, marked when beyond the paper."""
    return env_title(env) + (" (beyond the paper)" if beyond_paper(env) else "")


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
    t["linear_fits"] = linear_fits(res, t["timings"])
    return res, t


def linear_fits(res, timings):
    """The linear protocol's fits as rows like /tables/training's (which holds the trainings by
    gradient only): kind "tpa", protocol "linear", converged = every head's Newton converged
    (the record's newton_converged), newton_iterations (the most of its heads). The base point
    of any hyper-parameter axis only (a task's point: /tables/timings). Empty for a file without
    the linear protocol."""
    recs = res.records
    if recs.empty or "protocol" not in recs or "newton_converged" not in recs:
        return pd.DataFrame()
    f = recs[recs["protocol"] == "linear"]
    if not timings.empty and "hyper_point" in timings:
        f = f[f.key.isin(set(timings.key[timings.hyper_point == ""]))]
    cols = ["key", "env", "variant", "method", "N", "M", "frozen", "seed", "teacher", "best_mode",
            "newton_iterations"]
    out = f[[c for c in cols if c in f]].copy()
    out.insert(0, "kind", "tpa")
    out["converged"] = f["newton_converged"]
    out["protocol"] = "linear"
    out["reference"] = (f["reference"] if "reference" in f else pd.Series(False, index=f.index)) \
        .astype("boolean").fillna(False)
    return out.reset_index(drop=True)


def claim_trainings(t):
    """What the claims' "trainings converged" count: /tables/training's rows (the paper's
    protocol's TPA cells among them) and the linear protocol's fits."""
    tr, fits = t.get("training", pd.DataFrame()), t.get("linear_fits", pd.DataFrame())
    if fits is None or fits.empty:
        return tr
    return pd.concat([tr, fits], ignore_index=True) if not tr.empty else fits


# The TPA protocols (/tables/tpa's `protocol`), the paper's first: the report's order.
PAPER = "paper"
PROTOCOLS = tuple(sirl_bench.PROTOCOLS)
PROTOCOL_TEXT = {
    "paper": "the paper's reward head (two hidden layers, 128 wide on GridRobot, 1024 on "
             "JacoRobot) trained by Adam",
    "linear": "an L2-regularised logistic (Bradley–Terry) linear head on the standardised frozen "
              "φ, its penalty chosen by 5-fold cross-validation on the M training pairs",
}


def of_protocol(tpa, protocol):
    """The rows of TPA table `tpa` fit by `protocol` (a table without the column, or an empty
    one, holds the paper's only)."""
    if "protocol" not in tpa:
        return tpa if protocol == PAPER else tpa.iloc[0:0]
    return tpa[tpa["protocol"] == protocol]


def _is_reference(d):
    return d["reference"].fillna(False).astype(bool).to_numpy()


def methods(d):
    """The rows of the methods (a table's rows that are not references: the file marks them,
    column `reference`; a table without it has none)."""
    if "reference" not in d or d.empty:
        return d
    return d[~_is_reference(d)]


def references(d):
    """The rows of the reference representations (truth φ*, raw input): never a method."""
    if "reference" not in d or d.empty:
        return d.iloc[0:0]
    return d[_is_reference(d)]


def main_tpa(tpa, protocol=PAPER):
    """Fig. 5's cells of `protocol` (the file marks them: in_main), each method in its best mode
    (the paper's protocol: SIRL frozen, the others unfrozen; the linear protocol: every φ
    frozen). Methods only: the references' rows are reference_tpa's."""
    if tpa.empty:
        return tpa
    t = methods(of_protocol(tpa, protocol))
    t = t[t["in_main"]] if "in_main" in t else t
    # best_mode: the file's (engines ≥ 0.8.0); older files have no such column
    return t[t["best_mode"]] if "best_mode" in t else t.iloc[0:0]


def reference_tpa(tpa, protocol=PAPER):
    """The references' TPA rows of `protocol` (their heads on a frozen φ*, or on the raw input;
    N <NA>): Fig. 5's reference lines."""
    if tpa.empty:
        return tpa
    return references(of_protocol(tpa, protocol))


def protocols_run(tpa):
    """The protocols whose rows `tpa` holds, in PROTOCOLS order (any other after them)."""
    if tpa.empty:
        return []
    have = set(tpa["protocol"]) if "protocol" in tpa else {PAPER}
    return [p for p in PROTOCOLS if p in have] + sorted(have - set(PROTOCOLS))
