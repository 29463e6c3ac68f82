"""Paper says, we find: every statement of the paper that a results file's tables can check,
decided from the file (docs/ledger.md is the same list for readers; a test keeps the two equal).

Each statement is one or more comparisons over seeds, paired by seed (claims.paired):
  direction   a is better than b ("<": lower FPE, ">": higher TPA). Holm's correction runs over
              every directional comparison of the statement's family (all its statements in one
              environment). confirmed = every comparison goes the paper's way with adjusted
              p < α; contradicted = at least one goes the other way with adjusted p < α;
              undecided otherwise (with the seeds that would give 80 % power).
  equivalent  a is within ±margin of b (the paper's "similarly", "comparably", "like", "close
              to"); two one-sided tests (TOST), Holm over the family's equivalence comparisons.
              confirmed = every comparison inside the margin (adjusted TOST p < α);
              contradicted = some comparison outside it (one-sided p of |Δ| > margin, adjusted,
              < α); undecided otherwise.
Margins were fixed before any run was decided (docs/ledger.md): TPA ±0.02, FPE ±0.005.
The user study's statements use the study analysis's own tests (H3: two-sided Welch t over
training seeds; H4: one-way ANOVA over participants or rewards), beside the paper's F and p.
Pure pandas/scipy; no file access."""
import math
from dataclasses import dataclass, field

import numpy as np
import pandas as pd
from scipy import stats

import claims as claims_stats
from run_tables import PAPER, env_title, main_tpa, methods, of_protocol, references

ALPHA = claims_stats.ALPHA
MARGIN = {"fpe": 0.005, "tpa": 0.02}
BASELINES = ["vae", "multipref10", "multipref50", "singlepref", "random"]
PREF = ["multipref10", "multipref50", "singlepref"]
QUERY_METHODS = ["sirl", "sirl+vae"] + PREF
VERDICT = {"held": "confirmed", "not held": "contradicted", "inconclusive": "undecided"}

# The paper's scale, for "paper architecture, 15 of 1000 epochs" (its §4.3 and App. B).
# They are also the engine's defaults where a profile sets none (datasets/environments.cpp).
PAPER_SCALE = {
    "grid": {"head": "φ→128→128→1", "hidden": [128, 128], "tpa_epochs": 500, "sirl_epochs": 3000,
             "N": "100–1000", "M": "10–190"},
    "jaco": {"head": "φ→1024→1024→1", "hidden": [1024, 1024], "tpa_epochs": 1000,
             "sirl_epochs": 3000, "N": "100–1000", "M": "10–190"},
}


@dataclass
class Statement:
    id: str
    section: str
    paper: str              # the paper's words (short)
    envs: tuple             # environments it is about
    kind: str               # "direction", "equivalent", "study"
    metric: str = "tpa"     # "fpe", "tpa" (Fig. 5's cells, paper protocol), "ablation" (Fig. 7's)
    a: str = "sirl"         # variant (or "method@key=value" selectors for the ablation)
    b: list = field(default_factory=list)
    better: str = ">"
    N: object = "max"       # "max", "min" or a number (ignored for the ablation)
    b_N: object = None      # b's N when it differs from a's (a trend in N)
    M: object = "mean"      # "mean" over M, "max", "min"
    b_M: object = None
    family: str = ""
    paper_number: str = ""
    note: str = ""          # how the engine reads the statement, where that needs a word
    after_data: bool = False  # a comparison chosen after the data were seen (labelled so)
    per: tuple = ()         # one comparison per variant v (a = b = v), e.g. a trend in N


S = Statement
STATEMENTS = [
    # §4.4, Fig. 4 (FPE)
    S("S01", "§4.4, Fig. 4 (H1)", "both versions of SIRL … outperform all baselines", ("grid", "jaco"),
      "direction", "fpe", "sirl", BASELINES, "<", family="H1"),
    S("S02", "§4.4, Fig. 4 (H1)", "both versions of SIRL … outperform all baselines (SIRL+VAE)",
      ("grid", "jaco"), "direction", "fpe", "sirl+vae", BASELINES, "<", family="H1"),
    S("S03", "§4.4, Fig. 4", "both versions of SIRL … perform similarly", ("grid",), "equivalent",
      "fpe", "sirl", ["sirl+vae"], family="fpe"),
    S("S04", "§4.4, Fig. 4", "MultiPref with 10 humans performs better than SinglePref or MultiPref "
      "with 50", ("grid",), "direction", "fpe", "multipref10", ["singlepref", "multipref50"], "<",
      family="fpe"),
    S("S05", "§4.4, Fig. 4", "MultiPref-50 ends up learning a worse representation than Random",
      ("grid",), "direction", "fpe", "multipref50", ["random"], ">", family="fpe"),
    S("S08", "§4.4, Fig. 4", "SIRL without VAE scores better than with it", ("jaco",), "direction",
      "fpe", "sirl", ["sirl+vae"], "<", family="fpe"),
    S("S09", "Fig. 4, §4.4", "with enough data, SIRL learns representations more predictive of the "
      "true features (FPE falls with N)", ("grid", "jaco"), "direction", "fpe", "sirl", ["sirl"], "<",
      N="max", b_N="min", family="N", note="SIRL at the largest N against SIRL at the smallest"),
    # §4.4, Fig. 5 (TPA, the paper's protocol: SIRL frozen, the others unfrozen)
    S("S10", "§4.4, Fig. 5", "for GridRobot, each respective method performs comparably with "
      "different Ns", ("grid",), "equivalent", "tpa", N="min", b_N="max", family="N", per=tuple(QUERY_METHODS),
      note="each method that learns from queries at the smallest and the largest N (mean over M)"),
    S("S11", "§4.4, Fig. 5", "with just 100 queries, SIRL with VAE pre-training performs like VAE",
      ("jaco",), "equivalent", "tpa", "sirl+vae", ["vae"], N="min", family="N=min"),
    S("S12", "§4.4, Fig. 5", "SIRL without pre-training has random performance (it is frozen)",
      ("jaco",), "equivalent", "tpa", "sirl", ["chance"], N="min", family="N=min",
      note="SIRL at the smallest N against chance (0.5)"),
    S("S13", "§4.4, Fig. 5", "the preference baselines all perform close to Random", ("jaco",),
      "equivalent", "tpa", "random", PREF, N="min", family="N=min"),
    S("S14", "§4.4, Fig. 5", "for larger N, both versions of SIRL start performing better than the "
      "baselines", ("jaco",), "direction", "tpa", "sirl", BASELINES, ">", N="mid", family="N=mid",
      note="SIRL at the middle N of the profile's list"),
    S("S15", "§4.4, Fig. 5 (H2)", "at N = 1000 both SIRLs outperform all baselines in both "
      "environments", ("grid", "jaco"), "direction", "tpa", "sirl", BASELINES, ">", family="H2"),
    S("S16", "§4.4, Fig. 5 (H2)", "at N = 1000 both SIRLs outperform all baselines (SIRL+VAE)",
      ("grid", "jaco"), "direction", "tpa", "sirl+vae", BASELINES, ">", family="H2"),
    S("S17", "§4.4, Fig. 5 (H2)", "SIRL outperforms every baseline in the baseline's best "
      "configuration found here", ("grid", "jaco"), "direction", "ablation", "sirl", BASELINES, ">",
      family="H2-best", after_data=True,
      note="Fig. 7's cells: SIRL frozen without VAE against each baseline's configuration "
      "(frozen or not, VAE or not) of highest mean TPA in this file"),
    S("S19", "§4.4, Fig. 5", "for JacoRobot SIRL without VAE is better than with VAE", ("jaco",),
      "direction", "tpa", "sirl", ["sirl+vae"], ">", family="vae-init"),
    S("S20", "§4.4, Fig. 5", "in the GridRobot environment VAE pre-training helps SIRL", ("grid",),
      "direction", "tpa", "sirl+vae", ["sirl"], ">", family="vae-init"),
    S("S21", "§4.4, Fig. 5", "VAE performs comparably to other baselines in GridRobot", ("grid",),
      "equivalent", "tpa", "vae", PREF + ["random"], family="vae"),
    S("S22", "§4.4, Fig. 5", "it (VAE) severely underperforms in JacoRobot", ("jaco",),
      "direction", "tpa", "vae", PREF + ["random"], "<", family="vae"),
    S("S23", "§4.4, Fig. 5", "in GridRobot they (the preference methods) all perform similarly apart "
      "from MultiPref with 50 humans", ("grid",), "direction", "tpa", "multipref50",
      ["multipref10", "singlepref"], "<", family="pref",
      note="read as: MultiPref-50 below MultiPref-10 and SinglePref"),
    S("S24", "§4.4, Fig. 5", "more preference humans does not necessarily result in better "
      "performance", ("jaco",), "direction", "tpa", "multipref50", ["multipref10"], "<",
      family="pref", note="read as: MultiPref-50 below MultiPref-10"),
    S("S25", "§4.4, summary", "Random is often better than pre-training with preference queries",
      ("grid", "jaco"), "direction", "tpa", "random", PREF, ">", family="random"),
    S("S27", "§4.4 summary, §6", "SIRL's features are not perfectly aligned with the causal ones, "
      "just better aligned (the true features φ* do better)", ("grid", "jaco"), "direction", "tpa",
      "truth", ["sirl"], ">", family="truth"),
    S("S28", "§4.3, Fig. 5", "TPA as the head gets more queries (M from 10 to 190)",
      ("grid", "jaco"), "direction", "tpa", "sirl", ["sirl"], ">", M="max", b_M="min",
      family="M", note="SIRL at the largest M against the smallest"),
    # App. C, Fig. 7 (the ablation cells, mean over their N and M)
    S("A01", "App. C, Fig. 7", "SIRL does better when the learned representation is frozen",
      ("grid", "jaco"), "direction", "ablation", "sirl@frozen=1@vae=0", ["sirl@frozen=0@vae=0"], ">",
      family="ablation"),
    S("A02", "App. C, Fig. 7", "all the other methods do better when the representation is unfrozen "
      "(the preference methods)", ("grid", "jaco"), "direction", "ablation", "@frozen=0@vae=0",
      ["@frozen=1@vae=0"], ">", family="ablation", note="per method: MultiPref-10/50, SinglePref"),
    S("A03", "App. C, Fig. 7", "all the other methods do better when the representation is unfrozen "
      "(VAE and Random)", ("grid", "jaco"), "direction", "ablation", "@frozen=0@vae=0",
      ["@frozen=1@vae=0"], ">", family="ablation", note="per method: VAE, Random"),
    S("A04", "App. C, §4.3", "SinglePref and the MultiPref baselines perform better without VAE "
      "pre-training", ("grid", "jaco"), "direction", "ablation", "@frozen=0@vae=0",
      ["@frozen=0@vae=1"], ">", family="ablation",
      note="per method, unfrozen (their best mode): without against with VAE pre-training"),
    S("A05", "App. C", "SIRL sometimes benefits from pre-training in simple environments like "
      "GridRobot", ("grid",), "direction", "ablation", "sirl@frozen=1@vae=1",
      ["sirl@frozen=1@vae=0"], ">", family="ablation"),
    # §5.3, Fig. 6 (the user study's pipeline, on the profile's simulated cohort)
    S("U01", "§5.3, Fig. 6 (H3)", "SIRL recovers a representation twice as predictive of the true "
      "features", ("study",), "study", "fpe", better="<", paper_number="2-sided t-test, p < .0001"),
    S("U02", "§5.3, Fig. 6 (H4)", "Real: SIRL's TPA above Random's", ("study",), "study", "real",
      paper_number="F(1, 18) = 6.0175, p = .0246"),
    S("U03", "§5.3, Fig. 6 (H4)", "Held-out: SIRL's TPA above Random's", ("study",), "study",
      "heldout", paper_number="F(1, 18) = 4.7547, p = .0427"),
    S("U04", "§5.3, Fig. 6 (H4)", "Simulated: SIRL's TPA above Random's", ("study",), "study",
      "simulated", paper_number="F(1, 18) = 16.1068, p < .001"),
]
PREF_STATEMENTS = {"A02": PREF, "A03": ["vae", "random"], "A04": PREF}


def _nvalue(values, which):
    """N (or M) `which` ("max", "min", "mid" or a number) among `values`; None if absent."""
    vals = sorted(v for v in pd.unique(values) if pd.notna(v))
    if not vals:
        return None
    if which == "max":
        return vals[-1]
    if which == "min":
        return vals[0]
    if which == "mid":
        return vals[len(vals) // 2] if len(vals) >= 3 else None
    return which if which in vals else None


def _per_seed(d, col, N, M):
    """Per-seed value of `col` in rows d at N (rows without N serve every N) and M ("mean": the
    mean over M)."""
    if d.empty:
        return pd.Series(dtype=float)
    if N is not None and "N" in d:
        d = d[(d.N == N) | d.N.isna()]
    if M not in (None, "mean") and "M" in d:
        d = d[d.M == _nvalue(d.M, M)]
    return d.groupby("seed")[col].mean()


def _select_ablation(t, sel):
    """Rows of the ablation table t matching 'method@frozen=1@vae=0' (method may be empty)."""
    parts = sel.split("@")
    d = t if not parts[0] else t[t.method == parts[0]]
    for p in parts[1:]:
        k, v = p.split("=")
        d = d[d[k].astype(float) == float(v)]
    return d


def _comparisons(s, env, fpe, tpa):
    """The statement's comparisons in env: a list of claims.paired dicts (empty: no data), and a
    text of what was compared."""
    if s.metric == "fpe":
        d = methods(fpe)
        d = d[d.env == env] if not d.empty else d
        col, table = "fpe", d
    elif s.metric == "tpa":
        t = tpa[tpa.env == env] if not tpa.empty else tpa
        table = pd.concat([main_tpa(t, PAPER), references(of_protocol(t, PAPER))]) if not t.empty \
            else t
        col = "tpa"
    else:
        t = methods(of_protocol(tpa, PAPER)) if not tpa.empty else tpa
        t = t[(t.env == env)] if not t.empty else t
        table = t[t["in_ablation"].fillna(False).astype(bool)] if "in_ablation" in t else t.iloc[0:0]
        col = "tpa"
    if table.empty:
        return [], ""
    if s.metric == "ablation":
        return _ablation_comparisons(s, table)
    with_N = table[table.N.notna()] if "N" in table else table
    Na = _nvalue(with_N.N, s.N) if not with_N.empty else None
    Nb = _nvalue(with_N.N, s.b_N or s.N) if not with_N.empty else None
    if s.N not in ("max",) and Na is None:
        return [], ""
    out = []
    for va, vbs in ([(v, [v]) for v in s.per] if s.per else [(s.a, s.b)]):
        a = _per_seed(table[table.variant == va], col, Na, s.M)
        for b in vbs:
            if b == "chance":
                bb = pd.Series(0.5, index=a.index)
            else:
                bb = _per_seed(table[table.variant == b], col, Nb, s.b_M or s.M)
            if a.empty or bb.empty:
                continue
            if b == va and Na == Nb and not s.b_M:
                continue  # a trend in N with one N in the profile: nothing to compare
            c = claims_stats.paired(b, a, bb)
            if b == va:  # a trend of one variant: what is compared is N or M, not a method
                c["trend"] = (f"N = {Na} − N = {Nb}" if Na != Nb else
                              f"M = {_nvalue(table.M, s.M)} − M = {_nvalue(table.M, s.b_M)}")
            out.append(c)
    at = f"N = {Na}" + (f" vs {Nb}" if Nb != Na else "") if Na is not None else ""
    return out, at


def _ablation_comparisons(s, table):
    out = []
    if s.id == "S17":  # SIRL (frozen, no VAE) against each baseline's best configuration here
        a = _select_ablation(table, "sirl@frozen=1@vae=0").groupby("seed").tpa.mean()
        for b in s.b:
            x = table[table.method == b]
            if x.empty or a.empty:
                continue
            best = x.groupby(["frozen", "vae"]).tpa.mean().idxmax()
            bb = x[(x.frozen == best[0]) & (x.vae == best[1])].groupby("seed").tpa.mean()
            c = claims_stats.paired(b, a, bb)
            c["config"] = f"{'frozen' if best[0] else 'unfrozen'}, {'VAE' if best[1] else 'no VAE'}"
            out.append(c)
        return out, "Fig. 7's cells"
    for m in PREF_STATEMENTS.get(s.id, [None]):
        sel_a = (m or "") + s.a if s.a.startswith("@") else s.a
        a = _select_ablation(table, sel_a).groupby("seed").tpa.mean()
        for b in s.b:
            sel_b = (m or "") + b if b.startswith("@") else b
            bb = _select_ablation(table, sel_b).groupby("seed").tpa.mean()
            if a.empty or bb.empty:
                continue
            out.append(claims_stats.paired(m or b.split("@")[0], a, bb))
    return out, "Fig. 7's cells"


def _tost(c, margin):
    """Adds TOST's p (within ±margin) and the p of 'outside the margin' to a paired comparison."""
    n = c["n"]
    if n < 2 or not np.isfinite(c.get("lo", np.nan)):
        c.update(p_equiv=math.nan, p_outside=math.nan)
        return c
    half = c["hi"] - c["diff"]
    se = half / stats.t.ppf(0.975, n - 1) if half > 0 else math.nan
    if not se or not np.isfinite(se):
        c.update(p_equiv=math.nan, p_outside=math.nan)
        return c
    lower = stats.t.sf((c["diff"] + margin) / se, n - 1)   # H0: Δ ≤ −margin
    upper = stats.t.cdf((c["diff"] - margin) / se, n - 1)  # H0: Δ ≥ +margin
    c["p_equiv"] = max(lower, upper)
    # Outside: Δ > +margin or Δ < −margin, whichever side the estimate is on.
    c["p_outside"] = (stats.t.sf((c["diff"] - margin) / se, n - 1) if c["diff"] > 0 else
                      stats.t.cdf((c["diff"] + margin) / se, n - 1))
    return c


def _study_rows(study):
    """U01–U04 from a study analysis (sirl_bench.study_analysis's dict), or {} without one."""
    if not study:
        return {}
    rows = {}
    f_s, f_r = np.asarray(study.get("fpe_sirl", []), float), np.asarray(study.get("fpe_random", []), float)
    if len(f_s) >= 2 and len(f_r) >= 2:
        t = stats.ttest_ind(f_s, f_r, equal_var=False)
        rows["U01"] = (f_s.mean() - f_r.mean(), t.pvalue, f"Welch t = {t.statistic:.2f}, "
                       f"{len(f_s)} seeds; ratio Random/SIRL {f_r.mean() / f_s.mean():.2f}")
    for sid, key in (("U02", "real"), ("U03", "heldout"), ("U04", "simulated")):
        s = np.asarray(study.get(f"{key}_sirl", []), float)
        r = np.asarray(study.get(f"{key}_random", []), float)
        s, r = s[np.isfinite(s)], r[np.isfinite(r)]
        if len(s) >= 2 and len(r) >= 2 and np.ptp(np.r_[s, r]) > 0:
            F, p = stats.f_oneway(s, r)
            rows[sid] = (s.mean() - r.mean(), p, f"F(1, {len(s) + len(r) - 2}) = {F:.2f}")
    return rows


def ledger(fpe, tpa, envs, study=None):
    """Every statement × environment decided: a list of dicts (id, section, paper, env, verdict,
    comparisons, deciding, at, note, family)."""
    rows = []
    for s in STATEMENTS:
        if s.kind == "study":
            continue
        for env in s.envs:
            if env not in envs:
                continue
            comps, at = _comparisons(s, env, fpe, tpa)
            if s.kind == "equivalent":
                comps = [_tost(c, MARGIN["fpe" if s.metric == "fpe" else "tpa"]) for c in comps]
            rows.append({"id": s.id, "section": s.section, "paper": s.paper, "env": env,
                         "kind": s.kind, "better": s.better, "family": f"{env}/{s.family}",
                         "comparisons": comps, "at": at, "note": s.note, "metric": s.metric,
                         "after_data": s.after_data, "paper_number": s.paper_number})
    _decide_families(rows)
    st = _study_rows(study)
    for s in STATEMENTS:
        if s.kind != "study" or study is None:
            continue
        r = {"id": s.id, "section": s.section, "paper": s.paper, "env": "study", "kind": "study",
             "better": s.better, "family": "study", "comparisons": [], "at": "",
             "note": "the profile's simulated cohort, not the paper's participants",
             "after_data": False, "paper_number": s.paper_number}
        if s.id in st:
            diff, p, text = st[s.id]
            ok = diff < 0 if s.better == "<" else diff > 0
            r["verdict"] = ("confirmed" if ok and p < ALPHA else
                            "contradicted" if not ok and p < ALPHA else "undecided")
            r["deciding"] = {"name": "random", "diff": diff, "p": p, "p_holm": p, "n": 0,
                             "lo": math.nan, "hi": math.nan, "text": text}
        else:
            r["verdict"], r["deciding"] = "not run", None
        rows.append(r)
    return rows


def _decide_families(rows):
    """Holm over each family's directional comparisons (and, separately, its equivalence
    comparisons), then each statement's verdict from its own adjusted comparisons."""
    fams = {}
    for r in rows:
        fams.setdefault((r["family"], r["kind"]), []).append(r)
    for (fam, kind), rs in fams.items():
        comps = [c for r in rs for c in r["comparisons"]]
        if kind == "equivalent":
            for key in ("p_equiv", "p_outside"):
                for c, q in zip(comps, claims_stats.holm([c[key] for c in comps])):
                    c[key + "_holm"] = q
        else:
            for c, q in zip(comps, claims_stats.holm([c["p"] for c in comps])):
                c["p_holm"] = q
        for r in rs:
            r["verdict"], r["deciding"] = _verdict(r)
            if r["verdict"] == "undecided" and kind == "direction":
                r["seeds80"] = claims_stats.seeds_for_power(r["comparisons"], r["better"])


def _verdict(r):
    cs = r["comparisons"]
    if not cs:
        return "not run", None
    fin = lambda x: x if np.isfinite(x) else 2.0  # noqa: E731
    if r["kind"] == "equivalent":
        if all(fin(c["p_equiv_holm"]) < ALPHA for c in cs):
            return "confirmed", max(cs, key=lambda c: fin(c["p_equiv_holm"]))
        out = [c for c in cs if fin(c["p_outside_holm"]) < ALPHA]
        if out:
            return "contradicted", min(out, key=lambda c: fin(c["p_outside_holm"]))
        return "undecided", max(cs, key=lambda c: fin(c["p_equiv_holm"]))
    way = (lambda c: c["diff"] < 0) if r["better"] == "<" else (lambda c: c["diff"] > 0)
    sig = [c for c in cs if fin(c["p_holm"]) < ALPHA]
    if len([c for c in sig if way(c)]) == len(cs):
        return "confirmed", max(cs, key=lambda c: fin(c["p_holm"]))
    bad = [c for c in sig if not way(c) and c["diff"] != 0]
    if bad:
        return "contradicted", min(bad, key=lambda c: fin(c["p_holm"]))
    ways = [c for c in cs if way(c)]
    return "undecided", max(ways, key=lambda c: fin(c["p_holm"])) if ways else cs[0]


def counts(rows):
    """{verdict: number of statement × environment rows}, decided rows only."""
    out = {}
    for r in rows:
        out[r["verdict"]] = out.get(r["verdict"], 0) + 1
    return out


def _fmt(x, spec):
    return "—" if x is None or not np.isfinite(x) else format(x, spec)


def _hyper(profile_text, env):
    """An environment's head width, head epochs and SIRL epochs as the run used them: its
    profile's [hyper.<env>] (the file records the resolved profile; an axis's first value is the
    base point the claims use), else the engine's defaults, the paper's."""
    import tomllib
    try:
        h = tomllib.loads(profile_text or "").get("hyper", {}).get(env, {})
    except (tomllib.TOMLDecodeError, AttributeError):
        h = {}
    h = h if isinstance(h, dict) else {}
    p = PAPER_SCALE[env]

    def base(key, default):
        v = h.get(key, default)
        if isinstance(v, list) and v and isinstance(v[0], (list, int)) and key != "tpa.hidden":
            v = v[0]
        if key == "tpa.hidden" and isinstance(v, list) and v and isinstance(v[0], list):
            v = v[0]
        return v

    hidden = base("tpa.hidden", p["hidden"])
    width = "→".join(str(x) for x in hidden) if isinstance(hidden, list) else str(hidden)
    return {"head": f"φ→{width}→1", "tpa.epochs": base("tpa.epochs", p["tpa_epochs"]),
            "sirl.epochs": base("sirl.epochs", p["sirl_epochs"])}


def head_scale(profile_text, envs):
    """environment → "the paper's head φ→128→128→1, 200 of 500 epochs": the paper protocol's head
    as this run trained it, against the paper's (for the report's first table)."""
    out = {}
    for env in envs:
        if env not in PAPER_SCALE:
            continue
        p, h = PAPER_SCALE[env], _hyper(profile_text, env)
        same = h["head"] == p["head"]
        out[env] = ((f"the paper's head {h['head']}" if same else
                     f"head {h['head']} (paper: {p['head']})") +
                    f", {h['tpa.epochs']} of {p['tpa_epochs']} epochs")
    return out


def _env_scale(profile_text, fpe, tpa, env):
    """One environment's scale as this run has it: the paper's (PAPER_SCALE), the run's head and
    epochs (_hyper), its seeds and the N and M values of its cells."""
    p, h = PAPER_SCALE[env], _hyper(profile_text, env)
    f = fpe[fpe.env == env] if not fpe.empty else fpe
    t = tpa[tpa.env == env] if not tpa.empty else tpa
    seeds = len(pd.unique(pd.concat([f.get("seed", pd.Series(dtype=int)),
                                     t.get("seed", pd.Series(dtype=int))])))
    Ns = sorted(int(x) for x in pd.unique(f.N.dropna())) if "N" in f else []
    Ms = sorted(int(x) for x in pd.unique(t.M.dropna())) if "M" in t else []
    return p, h, seeds, Ns, Ms


def scale_lines(profile_text, fpe, tpa, envs):
    """This run's scale beside the paper's, per environment: the head's width and epochs, SIRL's
    epochs, seeds, N and M."""
    L = ["| environment | reward head (paper protocol) | SIRL epochs | seeds | N | M |",
         "|---|---|---|---:|---|---|"]
    for env in envs:
        if env not in PAPER_SCALE:
            continue
        p, h, seeds, Ns, Ms = _env_scale(profile_text, fpe, tpa, env)
        arch = ("the paper's architecture" if h["head"] == p["head"] else
                f"{h['head']} (paper: {p['head']})")
        L.append(f"| {env_title(env)} | {arch}, {h['tpa.epochs']} of {p['tpa_epochs']} "
                 f"epochs | {h['sirl.epochs']} of {p['sirl_epochs']} | {seeds} (paper: "
                 f"not stated) | {', '.join(map(str, Ns)) or '—'} (paper: {p['N']}) | "
                 f"{', '.join(map(str, Ms)) or '—'} (paper: {p['M']}) |")
    return L


def _span(values):
    """"100–1000", "200" or "—": the range of a list of N or M values."""
    if not values:
        return "—"
    return str(values[0]) if values[0] == values[-1] else f"{values[0]}–{values[-1]}"


def scale_phrases(profile_text, fpe, tpa, envs):
    """Per environment, this run's scale in one phrase with the paper's values in parentheses
    ("GridRobot: 2 seeds, N 100–200 (100–1000), …"): the report's opening sentence, so a reader
    knows before any verdict how far the run is from the paper's scale."""
    out = []
    for env in envs:
        if env not in PAPER_SCALE:
            continue
        p, h, seeds, Ns, Ms = _env_scale(profile_text, fpe, tpa, env)
        head = "" if h["head"] == p["head"] else f", reward head {h['head']} ({p['head']})"
        out.append(f"{env_title(env)}: {seeds} seeds, N {_span(Ns)} ({p['N']}), M {_span(Ms)} "
                   f"({p['M']}), SIRL {h['sirl.epochs']} epochs ({p['sirl_epochs']}), reward "
                   f"heads {h['tpa.epochs']} epochs ({p['tpa_epochs']}){head}")
    return out


def lines(rows, scale_text, name_of=lambda v: v):
    """The report's section: counts, the scale of this run beside the paper's, then one row per
    statement × environment (`name_of`: a variant's name as the figures show it)."""
    n = counts(rows)
    label_of = lambda v: v if v == "chance" else name_of(v)  # noqa: E731
    order = ["confirmed", "contradicted", "undecided", "not run"]
    L = ["", "## Paper says, we find", "",
         "Every statement of the paper this file can check (the list and its tests: "
         "docs/ledger.md), decided from this run: " +
         ", ".join(f"**{n.get(k, 0)} {k}**" for k in order) + ".", ""]
    L += scale_text
    L += ["", "Every seed of a run shares one trajectory set Ξ per environment (made from the "
          "environment's data seed, not from the run's seed): the seeds vary the queries, the "
          "simulated answers, the test rewards, initialisations and batch order, so the spread "
          "over seeds does not include a new Ξ."]
    L += ["", "| id | paper (section) | environment | we find: Δ [95 % CI] | adjusted p | seeds | "
          "verdict |", "|---|---|---|---|---:|---:|---|"]
    for r in rows:
        c = r["deciding"]
        env = "study (simulated cohort)" if r["env"] == "study" else env_title(r["env"])
        paper = f"“{r['paper']}” ({r['section']}" + (f"; {r['paper_number']}" if r["paper_number"]
                                                     else "") + ")"
        if r["after_data"]:
            paper += " — *chosen after the data were seen*"
        if c is None:
            L.append(f"| {r['id']} | {paper} | {env} | — | — | — | {r['verdict']} |")
            continue
        if r["kind"] == "study":
            label = "SIRL − Random"
        elif c.get("trend"):
            label = f"{label_of(c['name'])}, {c['trend']}"
        else:
            label = f"vs {label_of(c['name'])}"
        if c.get("config"):
            label += f" ({c['config']})"
        if r["kind"] == "equivalent":
            p = c.get("p_equiv_holm") if r["verdict"] != "contradicted" else c.get("p_outside_holm")
            label += f", margin ±{MARGIN['fpe' if r.get('metric') == 'fpe' else 'tpa']}"
        else:
            p = c.get("p_holm", c.get("p"))
        extra = f" ({c['text']})" if c.get("text") else ""
        where = f" at {r['at']}" if r["at"] and not c.get("trend") else ""
        verdict = r["verdict"]
        if verdict == "undecided" and r.get("seeds80"):
            verdict += f" ({r['seeds80']} seeds for 80 %)"
        note = f"; {r['note']}" if r["note"] else ""
        L.append(f"| {r['id']} | {paper} | {env} | {label}{where}: "
                 f"{_fmt(c['diff'], '+.4f')} [{_fmt(c['lo'], '+.4f')}, {_fmt(c['hi'], '+.4f')}]"
                 f"{extra}{note} | {_fmt(p, '.3g')} | {c['n'] or '—'} | **{verdict}** |")
    L += ["", "*confirmed*: every comparison goes the paper's way (or, for “similarly”, lies "
          f"inside the margin: TPA ±{MARGIN['tpa']}, FPE ±{MARGIN['fpe']}) with Holm-adjusted "
          f"p < {ALPHA} (Holm over each family of statements in one environment); *contradicted*: "
          "at least one goes the other way (or outside the margin) with adjusted p < "
          f"{ALPHA}; *undecided*: neither, with the seeds that would give 80 % power at the observed "
          "effects; *not run*: the profile has no cells for it. Δ = the paper's better side minus "
          "the other, paired by seed; the deciding comparison is shown. The study rows test the "
          "profile's simulated novices with the paper's tests, not the paper's participants."]
    return L
