"""The paper's claims decided from a results file's tables (claims.py's paired tests, Holm,
power), and their lines in the report: the main claims' table that opens it, the table of every
claim and the details."""
import math
import re

import claims as claims_stats
import figures
from figures import STYLE
import ledger
from run_tables import (ENV, PAPER, PROTOCOL_TEXT, PROTOCOLS, beyond_paper, claim_env_title,
                        env_title, main_tpa, methods, of_protocol)

ALPHA = claims_stats.ALPHA


def fmt(x, spec=".4f"):
    return "—" if x is None or (isinstance(x, float) and not math.isfinite(x)) else format(x, spec)


def comparison_text(c):
    name = c["name"]
    label = ("vs " + STYLE[name][1]) if name in STYLE else name
    return (f"{label}: Δ = {fmt(c['diff'], '+.4f')} [{fmt(c['lo'], '+.4f')}, {fmt(c['hi'], '+.4f')}], "
            f"d_z = {fmt(c['dz'], '+.2f')}, p = {fmt(c['p'], '.3g')}"
            f"{' (every seed differs by the same amount: exact sign test)' if c.get('test') == 'sign' else ''}"
            f", Holm p = {fmt(c.get('p_holm'), '.3g')} "
            f"(n = {c['n']})")


def claim(claims, env, name, comparisons, better, main=False, trainings=None, protocol=None,
          verdict=None, family=None):
    """Decides one hypothesis (claims.decide) and keeps it for the summary and the details;
    `trainings`: the /tables/training rows its numbers rest on (for the converged count);
    `protocol`: the TPA protocol a TPA claim is decided under (None: an FPE claim); `verdict`:
    a verdict given without a decision ("not run": the file has no rows of that protocol)."""
    v, deciding = claims_stats.decide(comparisons, better)
    if verdict is not None:
        v, deciding = verdict, None
    h = {"env": env, "claim": name, "protocol": protocol, "better": better,
         "comparisons": comparisons, "verdict": v, "deciding": deciding, "main": main,
         "family": family}
    if trainings is not None and not trainings.empty:
        h["converged"] = (int(trainings.converged.sum()), len(trainings))
    if comparisons:
        h["power"] = claims_stats.power(comparisons, better)
        h["seeds80"] = claims_stats.seeds_for_power(comparisons, better)
    claims.append(h)


def rested_on(tr, env, N, variants, tpa_cells, protocol=PAPER):
    """The trainings behind a main claim at N: the compared methods' φ at N and the VAE, and for
    a TPA claim their TPA cells of the main grid under `protocol` (the paper's: SIRL frozen, the
    others unfrozen)."""
    if tr is None or tr.empty:
        return None
    t = tr[(tr.env == env) & (tr.teacher == "")] if "teacher" in tr else tr[tr.env == env]
    use = ((t.kind == "rep") & (t.N == N) & t.variant.isin(variants)) | (t.kind == "vae")
    if tpa_cells:
        cells = (t.kind == "tpa") & ((t.N == N) | t.N.isna()) & t.variant.isin(variants) & t.best_mode
        if "protocol" in t:
            cells &= t.protocol.fillna(PAPER).replace("", PAPER) == protocol
        elif protocol != PAPER:  # a table without the column holds the paper's cells only
            cells &= False
        use |= cells.fillna(False)
    return t[use]


def baselines():
    """The paper's baselines, as the file's /methods declares them (figures.load_styles)."""
    return figures.methods_of("baseline")


def pretrained_on(queries):
    """The baselines whose φ learns from this kind of human answer ("preference")."""
    return [v for v in baselines() if figures.METHODS.queries[v] == queries]


def tpa_claims(H, tpa, env, protocol, training):
    """The TPA claims of one environment under one protocol (H2, and Random against preference
    pre-training), from the main grid's method rows (never the references)."""
    t = tpa[tpa.env == env]
    m = main_tpa(t, protocol)
    if m.empty:
        # "not run": the environment has TPA cells, none of this protocol (a profile's [tpa]
        # protocols, or a file of an engine before the linear protocol). Cells of the protocol
        # but none of the main grid (a file before best_mode): no claim, as before.
        if not t.empty and of_protocol(t, protocol).empty:
            h2 = ("H2 — SIRL's TPA (frozen, mean over M) is higher than every baseline's "
                  "(unfrozen)" if protocol == PAPER else
                  "H2 — SIRL's TPA (mean over M) is higher than every baseline's (every φ frozen)")
            claim(H, env, h2, [], ">", main=True, protocol=protocol, verdict="not run")
            claim(H, env, "Secondary — Random beats preference pre-training (TPA)", [], ">",
                  protocol=protocol, verdict="not run")
        return
    nmax = m.N.max()

    def tpa_at(v):
        x = m[(m.variant == v) & ((m.N == nmax) | m.N.isna())]
        return x.groupby("seed").tpa.mean()

    compared = ["sirl"] + baselines()
    if protocol == PAPER:
        h2 = (f"H2 — SIRL's TPA (frozen, mean over M) is higher than every baseline's "
              f"(unfrozen) at N = {nmax}")
    else:
        h2 = (f"H2 — SIRL's TPA (mean over M) is higher than every baseline's at N = {nmax} "
              f"(every φ frozen)")
    claim(H, env, h2,
          [claims_stats.paired(v, tpa_at("sirl"), tpa_at(v)) for v in baselines()
           if (m.variant == v).any()], ">", main=True,
          trainings=rested_on(training, env, nmax, compared, True, protocol), protocol=protocol,
          family="H2")
    claim(H, env, "Secondary — Random beats preference pre-training (TPA)",
          [claims_stats.paired(v, tpa_at("random"), tpa_at(v))
           for v in pretrained_on("preference") if (m.variant == v).any()],
          ">", protocol=protocol, family="random-vs-preference")


def hypotheses(fpe, tpa, envs, training=None):
    """Every claim the report checks, per environment, decided: the FPE claims and the paper's
    protocol's TPA claims first (environment by environment, as before the protocols), then the
    TPA claims of every other protocol. The references (truth φ*, raw input) are never a
    baseline: every table is restricted to the methods' rows."""
    H = []
    fpe, tpa = methods(fpe), methods(tpa)
    has_tpa = "env" in tpa and not tpa.empty
    base = baselines()
    compared = ["sirl"] + base
    for env in envs:
        d = fpe[fpe.env == env] if not fpe.empty else fpe
        if not d.empty:
            nmax = d.N.max()

            def fpe_at(v):
                x = d[(d.variant == v) & ((d.N == nmax) | d.N.isna())]
                return x.set_index("seed").fpe

            claim(H, env, f"H1 — SIRL's FPE is lower than every baseline's at N = {nmax}",
                  [claims_stats.paired(v, fpe_at("sirl"), fpe_at(v)) for v in base
                   if (d.variant == v).any()], "<", main=True,
                  trainings=rested_on(training, env, nmax, compared, False))
        if has_tpa:
            tpa_claims(H, tpa, env, PAPER, training)
        paper = of_protocol(tpa, PAPER) if has_tpa else tpa
        ab = paper[(paper.env == env) & (paper.vae == 0)] if has_tpa else paper
        # The paper's best modes, for every method that learns from answers: SIRL frozen, the
        # preference methods unfrozen (their /methods best_frozen).
        for meth in [v for v in figures.methods_of("sirl") + base if figures.METHODS.queries[v]]:
            frozen_best = bool(figures.METHODS.best_frozen[meth])
            text = f"{STYLE[meth][1]} is better {'frozen' if frozen_best else 'unfrozen'}"
            if ab.empty:
                break
            x = ab[ab.method == meth]
            if x.frozen.nunique() < 2:
                continue
            keys = ["N", "M"]
            cells = x.groupby(keys).frozen.nunique()
            cells = cells[cells == 2].index
            x = x.set_index(keys).loc[cells].reset_index()
            fr = x[x.frozen == 1].groupby("seed").tpa.mean()
            un = x[x.frozen == 0].groupby("seed").tpa.mean()
            claim(H, env, f"Secondary — {text} (ablation cells, mean over N, M)",
                  [claims_stats.paired("frozen − unfrozen", fr, un)], ">" if frozen_best else "<",
                  protocol=PAPER)
        if ENV.get(env, {}).get("vae_weak_claim"):
            x = fpe[(fpe.env == env)] if not fpe.empty else fpe
            if not x.empty and (x.variant == "vae").any():  # a profile may run no VAE FPE
                nmax = x.N.max()
                v = x[(x.variant == "vae")].set_index("seed").fpe
                s = x[(x.variant == "sirl") & (x.N == nmax)].set_index("seed").fpe
                claim(H, env, f"Secondary — VAE is weak on {env_title(env)} (FPE above SIRL's)",
                      [claims_stats.paired("vae", v, s)], ">")
    if has_tpa:
        for protocol in [p for p in PROTOCOLS if p != PAPER]:
            for env in envs:
                tpa_claims(H, tpa, env, protocol, training)
    across_protocols(H)
    return H


def across_protocols(H):
    """A TPA claim decided under several protocols is one claim tested several ways: Holm runs
    over the comparisons of all its protocols together, and each protocol's verdict is decided
    again from those adjusted p-values (so a second protocol cannot add a chance to hold)."""
    groups = {}
    for h in H:
        if h.get("family") and h["comparisons"]:
            groups.setdefault((h["env"], h["family"]), []).append(h)
    for hs in groups.values():
        if len(hs) < 2:
            continue
        comps = [c for h in hs for c in h["comparisons"]]
        for c, q in zip(comps, claims_stats.holm([c["p"] for c in comps])):
            c["p_holm"] = q
        for h in hs:
            h["verdict"], h["deciding"] = claims_stats.decide(h["comparisons"], h["better"],
                                                              adjusted=True)
            h["holm_across"] = len(hs)


def protocol_cell(h, scale=None):
    """The summary's protocol column: a TPA claim's protocol ("paper", the primary one, with the
    head's width and epochs this run used against the paper's; "linear", secondary), "—" for an
    FPE claim."""
    p = h.get("protocol")
    if not p:
        return "—"
    if p == PAPER:
        return f"paper (primary{'; ' + scale[h['env']] if scale and h['env'] in scale else ''})"
    return f"{p} (secondary)"


def summary_lines(H, missing=None, scale=None, study=None):
    """The table of every claim: one row per claim × environment × TPA protocol (an FPE claim has
    one, protocol "—"), in H's order. `missing`: environment → the number of its tasks a partial
    merge lacks; those environments' verdicts are marked ⧗. `scale`: environment → the paper
    protocol's head as this run trained it. `study`: the ledger's rows of the user study (H3,
    H4), listed after H's claims; None: the report says nothing of a study (an empty list: the
    profile ran none)."""
    missing = missing or {}
    L = ["| claim | environment | protocol | verdict | deciding comparison: Δ [95 % CI] | Holm p | "
         "seeds | power | seeds for 80 % | trainings converged |",
         "|---|---|---|---|---|---:|---:|---:|---:|---:|"]
    for h in H:
        c = h["deciding"]
        if c is None:
            verdict = h["verdict"] if h["verdict"] == "not run" else "not evaluated (no data)"
            L.append(f"| {h['claim']} | {claim_env_title(h['env'])} | {protocol_cell(h, scale)} | {verdict} | "
                     f"— | — | — | — | — | — |")
            continue
        conv = h.get("converged")
        conv_text = (f"{conv[0]} of {conv[1]}" + (" ⚠" if conv[0] < conv[1] else "")) if conv else "—"
        label = ("vs " + STYLE[c["name"]][1]) if c["name"] in STYLE else c["name"]
        s80 = h.get("seeds80")
        pw = h.get("power", math.nan)
        claim_text = f"**{h['claim']}**" if h["main"] else h["claim"]
        partial = " ⧗" if missing.get(h["env"]) else ""
        L.append(f"| {claim_text} | {claim_env_title(h['env'])} | {protocol_cell(h, scale)} | "
                 f"**{h['verdict']}**{partial} | {label}: "
                 f"{fmt(c['diff'], '+.4f')} [{fmt(c['lo'], '+.4f')}, {fmt(c['hi'], '+.4f')}] | "
                 f"{fmt(c.get('p_holm'), '.3g')} | {c['n']} | {fmt(100 * pw, '.0f') + ' %' if pw == pw else '—'} | "
                 f"{s80 if s80 else f'> {claims_stats.MAX_SEEDS}' if pw == pw else '—'} | "
                 f"{conv_text} |")
    L += [study_summary_row(r) for r in study or []]
    L += ["", f"Verdicts: *held* = every comparison goes the claimed way with Holm-adjusted p < "
          f"{ALPHA} (paired t-tests over seeds, Holm's correction within each claim); *not held* = "
          f"at least one goes the other way with adjusted p < {ALPHA}; *inconclusive* otherwise. "
          f"The deciding comparison is the one the verdict rests on (for *held* the weakest). "
          f"*Power* = the chance that a run with this many seeds decides (held or not held) if the "
          f"true effects were the observed ones (simulated noncentral t, Holm applied); *seeds for "
          f"80 %* = the fewest seeds with power ≥ 80 %. Both are planning numbers computed from this "
          f"run's effect sizes, which few seeds estimate poorly: they are not evidence. "
          f"*Trainings converged* (main claims): of the trainings the claim's numbers rest on (the "
          f"compared methods' φ at that N and the VAEs, and for TPA their cells of Fig. 5: the "
          f"paper protocol's head trainings, the linear protocol's Newton fits), how "
          f"many met the convergence criterion of the table below; ⚠ marks a verdict resting on "
          f"trainings that were still learning.",
          "", "*Protocol*: how a TPA claim's reward heads were fit. The paper's protocol is the "
          "primary one; the linear protocol is **secondary**: it was added after the paper "
          "protocol's result (JacoRobot's H2 inconclusive) was seen, and it freezes every φ, the "
          "baselines' included (their worse mode in the paper). A claim decided under both is one "
          "claim: Holm's correction runs over the comparisons of both protocols together. "
          + " ".join(
              f"*{p}* = {PROTOCOL_TEXT[p]}" + (" (SIRL frozen, the others unfrozen, as the paper)."
                                               if p == PAPER else
                                               " (every method's φ frozen: the standard "
                                               "linear-evaluation protocol; it has no ablation).")
              for p in PROTOCOLS)
          + " *—* = an FPE claim (the linear probe of the true features). *not run* = the file "
          "has no cells of that protocol. The references (truth φ\*, the ceiling; the raw "
          "input, the floor) are drawn in Figs. 4 and 5 and never counted as baselines."]
    if study is not None:
        L += ["", study_note(bool(study))]
    if missing:
        L += ["", "⧗ **Partial merge**: the results lack "
              + ", ".join(f"{n} {env_title(e)} task(s)" for e, n in sorted(missing.items()))
              + " (a shard failed or had not finished; the file's `missing_tasks` lists them). "
              "Verdicts marked ⧗ rest on the cells that exist: fewer seeds or M values than the "
              "profile asks, and figures show gaps where cells are missing."]
    return L


# The user study's claims (§5.3, Fig. 6) as the ledger decides them (its U01–U04: the study
# analysis's own tests, one per statement); claims.json keeps the results tables' claims only.
STUDY_CLAIMS = {
    "U01": "H3: SIRL's FPE is lower than Random's",
    "U02": "H4: SIRL's TPA is higher than Random's, own answers (the paper's Real: each "
           "participant's own preferences)",
    "U03": "H4: SIRL's TPA is higher than Random's, Held-out (SIRL without the participant's "
           "similarity answers)",
    "U04": "H4: SIRL's TPA is higher than Random's, Simulated (perfect answers for random "
           "rewards)",
}
# The ledger's words for the same rule (one comparison: the claimed way with p < α, the other
# way with p < α, neither) in the claims' words.
CLAIM_VERDICT = {v: k for k, v in ledger.VERDICT.items()}


def study_summary_row(r):
    """One row of the claims table for a user-study statement of the ledger (kind "study")."""
    claim = f"Secondary (user study, Fig. 6) — {STUDY_CLAIMS.get(r['id'], r['paper'])}"
    where = "user study (simulated cohort)"
    c = r["deciding"]
    if c is None:
        return f"| {claim} | {where} | — | {r['verdict']} | — | — | — | — | — | — |"
    return (f"| {claim} | {where} | — | **{CLAIM_VERDICT.get(r['verdict'], r['verdict'])}** | "
            f"SIRL − Random: {fmt(c['diff'], '+.4f')} ({c.get('text', '')}) | "
            f"{fmt(c.get('p'), '.3g')} | — | — | — | — |")


def study_note(ran):
    """What the study's rows are, or that the profile ran no study."""
    if not ran:
        return ("*H3, H4* (the user study, Fig. 6): this profile ran no study, so the report has "
                "no study claims.")
    return ("*H3, H4* (the user study, §5.3, Fig. 6): the study pipeline on the profile's "
            "simulated cohort, not the paper's participants, decided with the paper's tests "
            "(H3: two-sided Welch t over training seeds; H4: one-way ANOVA with the method as the "
            "factor). Each row is one test: its *Holm p* is that test's p, not adjusted. They are "
            "the ledger's U01–U04 below. Fig. 6 and the study's subsets (participants whose "
            "preference involves every feature; Random in its other mode) are in "
            "study/study_report.md beside this report when `sirl reproduce` drew it "
            "(`report/plot_study.py RESULTS.h5 --out DIR` draws it from this file).")


def table_order(H):
    """H for the claims table: the main claims first, then each claim with its environments and
    protocols together (a claim's linear row right after its paper twin). H itself keeps the
    order the claims were decided in (claims.json, claims.csv)."""
    groups, envs = {}, {}
    for h in H:
        groups.setdefault(main_family(h) if h["main"] else h["claim"], len(groups))
        envs.setdefault(h["env"], len(envs))
    rank = {None: 0, PAPER: 1, **{p: 2 + i for i, p in enumerate(PROTOCOLS) if p != PAPER}}

    def key(h):
        return (not h["main"], groups[main_family(h) if h["main"] else h["claim"]],
                envs[h["env"]], rank.get(h.get("protocol"), len(rank)))
    return sorted(H, key=key)


# The main claims: their name (the first word of their text), what they claim in words, and the
# ledger's statement of the paper that they test (its words and section, for "the paper").
MAIN_CLAIMS = {
    "H1": ("SIRL's FPE is lower than every baseline's", "S01"),
    "H2": ("SIRL's TPA (mean over M) is higher than every baseline's", "S15"),
}


def main_family(h):
    """"H1" or "H2": the name a main claim's text starts with."""
    return h["claim"].split(" ", 1)[0]


def main_columns(H):
    """The main claims table's columns, (environment, protocol): the paper's protocol first (its
    columns also hold H1, FPE having one protocol), then each other protocol that decided a main
    claim somewhere in this file; environments in H's order."""
    mains = [h for h in H if h["main"]]
    envs = list(dict.fromkeys(h["env"] for h in mains))
    protocols = [PAPER] + [p for p in PROTOCOLS if p != PAPER and any(
        h["protocol"] == p and h["verdict"] != "not run" for h in mains)]
    return [(env, p) for p in protocols for env in envs]


def md_cell(text):
    """Text from a file as one Markdown table cell: on one line, its pipes escaped."""
    return " ".join(str(text).split()).replace("|", "\\|")


def method_label(name):
    return STYLE[name][1] if name in STYLE else name


def verdict_sentence(h):
    """A main claim's verdict in one sentence: the comparison it rests on, in words (for *held*
    the least clear baseline, for *not held* the one clearly better than SIRL, for
    *inconclusive* the one that kept it undecided)."""
    c = h["deciding"]
    if c is None:
        return ("the file has no cells of this protocol" if h["verdict"] == "not run"
                else "no data")
    metric = "FPE" if h.get("protocol") is None else "TPA"
    label, d = md_cell(method_label(c["name"])), c["diff"]
    if d is None or not math.isfinite(d):
        return f"too few seeds to compare SIRL with {label}"
    by, p = fmt(abs(d), ".2g"), fmt(c.get("p_holm"), ".2g")
    if h["verdict"] == "held":
        way = "lower" if h["better"] == "<" else "higher"
        return (f"SIRL's {metric} is {way} than every baseline's, least clearly {label}'s, by "
                f"{by} (Holm p {p})")
    if h["verdict"] == "not held":
        return f"{label}'s {metric} is {by} {'lower' if d > 0 else 'higher'} than SIRL's (Holm p {p})"
    than = (f"equals {label}'s" if d == 0 else
            f"is {by} {'lower' if d < 0 else 'higher'} than {label}'s")
    if c.get("p_holm") is None or not math.isfinite(c["p_holm"]):
        return f"SIRL's {metric} {than}, untested: {c['n']} seed{'s' * (c['n'] != 1)} (a test needs 2)"
    return f"SIRL's {metric} {than}, not significantly (Holm p {p}, {c['n']} seeds)"


def main_cell(h, missing):
    """One cell of the main claims table: the verdict in bold (report.html colours the cell by it),
    ⚠ (unconverged trainings), ⧗ (a partial merge), then the sentence."""
    if h is None:
        return "—"
    conv = h.get("converged")
    marks = (" ⚠" if conv and conv[0] < conv[1] else "") + (" ⧗" if missing.get(h["env"]) else "")
    return f"**{h['verdict']}**{marks}: {verdict_sentence(h)}"


def paper_expectation(family):
    """The paper's column: what it reports for the claim, in its words."""
    s = next(s for s in ledger.STATEMENTS if s.id == MAIN_CLAIMS[family][1])
    return (f"held in both environments at N = 1000: “{s.paper}” ({s.section})"
            + ("; under the paper's protocol (linear evaluation is not the paper's)"
               if family == "H2" else ""))


def main_row_label(family, hs):
    """A main claim's row label, with the N its claims are decided at (the largest N each
    environment ran: one number when they agree)."""
    Ns = sorted({m.group(1) for h in hs if (m := re.search(r"at N = (\d+)", h["claim"]))}, key=int)
    at = (f"at N = {Ns[0]}" if len(Ns) == 1 else "at each environment's largest N" +
          (f" ({', '.join(Ns)})" if Ns else ""))
    return f"**{family}** — {MAIN_CLAIMS[family][0]} {at}"


def main_claims_lines(H, missing=None):
    """The table that opens the report: the two main claims (rows) × environment and TPA protocol
    (columns), each cell the verdict and one sentence, the paper's expectation beside them; then
    the legend of the verdicts and of ⚠ (⧗ when a merge was partial) and the metrics spelled
    out. Empty without main claims."""
    missing = missing or {}
    cols = main_columns(H)
    if not cols:
        return []
    head = [f"{md_cell(claim_env_title(env))}, " + ("paper protocol" if p == PAPER else f"{p} (secondary)")
            for env, p in cols]
    L = ["| main claim | " + " | ".join(head) + " | the paper |",
         "|---|" + "---|" * (len(cols) + 1)]
    for family in MAIN_CLAIMS:
        hs = [h for h in H if h["main"] and main_family(h) == family]
        if not hs:
            continue
        cells = []
        for env, p in cols:
            if family == "H1" and p != PAPER:
                cells.append("(FPE has one protocol)")
                continue
            want = None if family == "H1" else p
            cells.append(main_cell(next((h for h in hs if h["env"] == env and
                                         h.get("protocol") == want), None), missing))
        L.append(f"| {main_row_label(family, hs)} | " + " | ".join(cells) +
                 f" | {paper_expectation(family)} |")
    L += ["", f"*held*: SIRL beat every baseline, each paired comparison over seeds significant "
          f"after Holm's correction (p < {ALPHA}); *not held*: a baseline beat SIRL significantly; "
          f"*inconclusive*: neither, at this run's seeds. **⚠**: some of the trainings the verdict "
          f"rests on had not converged (their loss still changing over the last 10 % of the epochs; "
          f"counts under *trainings converged* below), so the verdict is provisional: longer training may "
          f"change it." + (" **⧗**: a partial merge, some of the environment's cells are missing."
                           if missing else "")
          + (" *Beyond the paper*: not one of the paper's environments (one read from a file, "
             "or from other work); the paper made no statement about it, so its verdicts are "
             "this benchmark's findings, neither confirming nor contradicting the paper."
             if any(beyond_paper(env) for env, _ in cols) else "")]
    L += ["", "**FPE** (feature prediction error): the held-out mean squared error of a "
          "least-squares linear probe from a method's representation φ(ξ) of a trajectory ξ to "
          "its true features φ\\*(ξ), normalised; lower is better. **TPA** (test preference "
          "accuracy): for each of 20 test rewards, a reward head trained on φ from M preference "
          "pairs, scored by the share of held-out pairs it orders as the true reward does (mean "
          "over the rewards); higher is better. **N**: the queries φ is trained on (similarity "
          "triplets for SIRL, preference pairs for the preference baselines; VAE and Random use "
          "none). **M**: the preference pairs each test reward's head is trained on."]
    return L


def detail_lines(H, envs):
    L = ["", "## The paper's claims in detail", ""]
    for env in envs:
        rows = [h for h in H if h["env"] == env]
        if not rows:
            continue
        L.append(f"### {env_title(env)}")
        for h in rows:
            under = f" [{h['protocol']} protocol]" if h.get("protocol") else ""
            if h["deciding"] is None:
                L.append(f"- **{h['claim']}**{under}: "
                         + ("not run" if h["verdict"] == "not run" else "not evaluated (no data)"))
                continue
            L.append(f"- **{h['claim']}: {h['verdict']}**{under} (paired t-test over seeds, α = {ALPHA}, "
                     f"Holm within the claim; Δ with its 95 % CI). "
                     + "; ".join(comparison_text(c) for c in h["comparisons"]))
        L.append("")
    if not any(ENV.get(e, {}).get("vae_weak_claim") for e in envs):
        L.append("- *VAE weak on JacoRobot*: not evaluated — this run has no JacoRobot cells.")
    return L
