"""report.md, report.html and claims.json: the main claims first (a small table, its legend and
the metrics spelled out), then every claim, the ledger, the figures, learning curves and their
convergence, the claims in detail, compute against the roofs, diagnostics, notes and the
profile."""
import html
import json
import math
import os
import re

import numpy as np
import pandas as pd

import claims as claims_stats
from figures import STYLE
import ledger
import plot_beyond
from safe_output import write_text
from hypotheses import (detail_lines, fmt, hypotheses, main_claims_lines, summary_lines,
                        table_order)
from run_tables import (ENV, PAPER, beyond_paper, claim_trainings, env_title, main_tpa, methods, protocols_run,
                        sirl_bench)


def convergence_lines(t):
    """One line per (environment, kind, variant): how many of its trainings converged."""
    tr = t["training"]
    if tr.empty and (t.get("linear_fits") is None or t["linear_fits"].empty):
        return []
    L = ["", "## Did every training converge?", "",
         "Converged: the mean loss over the last 10 % of the epochs differs from the 10 % before "
         "by less than 1 % (+1e-4 absolute); a TPA cell counts when all of its heads did. "
         "Per-task values: /tables/training.", "",
         "| env | training | variant | epochs | converged | median Δ over the last 10 % |",
         "|---|---|---|---:|---:|---:|"]
    if "teacher" in tr:  # the [robustness] cells' trainings, one line per method
        tr = tr.assign(variant=tr.variant.where(tr.teacher == "", tr.variant + " (noisy teachers)"))
    for (env, kind, v), d in (tr.groupby(["env", "kind", "variant"]) if not tr.empty else []):
        L.append(f"| {env} | {kind} | {v} | {int(d.epochs.median())} | {int(d.converged.sum())} of "
                 f"{len(d)} | {100 * d.loss_relative_change.median():+.2f} % |")
    fits = t.get("linear_fits")
    if fits is not None and not fits.empty:
        L += ["", "The linear protocol's heads are fit by Newton's method, not by epochs: a cell "
              "converged when every one of its heads did; *iterations* is the most any head "
              "took.", "",
              "| env | fit | variant | iterations (max) | converged |", "|---|---|---|---:|---:|"]
        for (env, v), d in fits.groupby(["env", "variant"]):
            it = d.newton_iterations.max() if "newton_iterations" in d else None
            L.append(f"| {env} | tpa (linear) | {v} | {'—' if it is None or pd.isna(it) else int(it)} | "
                     f"{int(d.converged.fillna(False).sum())} of {len(d)} |")
    return L


def vae_lines(res, t):
    """The VAE's posterior (per-latent KL) and how alive each φ's last hidden layer is."""
    vl = t["vae_latents"]
    L = []
    if not vl.empty:
        L += ["", "## The VAE's posterior", "",
              "A latent dimension with KL < 0.01 nats carries no information about the trajectory "
              "(posterior collapse). Per dimension: /tables/vae_latents.", "",
              "| env | seed | ELBO form | active latents (KL > 0.01) | KL per latent (nats) | "
              "reconstruction MSE |", "|---|---:|---|---:|---|---:|"]
        for (env, seed), d in vl.groupby(["env", "seed"]):
            kl = d.sort_values("dim").kl.values
            L.append(f"| {env} | {seed} | {d.elbo.iloc[0]} | {(kl > 0.01).sum()} of {len(kl)} | "
                     f"{', '.join(f'{x:.3g}' for x in kl)} | {d.reconstruction_mse.iloc[0]:.4g} |")
    dead = []
    recs = res.records
    if not recs.empty and "variant" in recs:
        reps = recs[(recs.kind == "rep") & recs.arrays.str.split(",").map(lambda a: "dead_fraction" in a)]
        for row in reps.itertuples():
            df = res.array(row.key, "dead_fraction")
            dead.append((row.env, row.variant, float(df[-1]) if len(df) else 0.0))
    if dead:
        d = pd.DataFrame(dead, columns=["env", "variant", "dead"])
        L += ["", "## Dead units", "",
              "Share of φ's last hidden layer that is 0 on every trajectory of Ξ (a φ whose layer "
              "is all dead is a constant map: no head on it can learn, frozen or not).", "",
              "| env | variant | representations | median dead share | max |", "|---|---|---:|---:|---:|"]
        for (env, v), x in d.groupby(["env", "variant"]):
            L.append(f"| {env} | {v} | {len(x)} | {x.dead.median():.2f} | {x.dead.max():.2f} |")
    return L


def compute_lines(res, tim):
    a = res.provenance
    if not len(tim):
        return []
    tim = tim.copy()
    tim["cores"] = tim["threads"] if "threads" in tim else 1  # files before engine 0.4.0: 1
    tim["core_seconds"] = tim.seconds * tim.cores
    by = tim.groupby("kind").agg(tasks=("key", "count"), seconds=("seconds", "sum"),
                                 core_seconds=("core_seconds", "sum"),
                                 wide=("cores", lambda x: int((x > 1).sum())),
                                 gflop=("flops", lambda x: x.sum() / 1e9))
    by["GFLOP/s"] = by.gflop / by.seconds.where(by.seconds > 0)
    by["per core"] = by.gflop / by.core_seconds.where(by.core_seconds > 0)
    roof = float(a.get("roof_fp32_gflops_per_core", 0) or 0)  # one core's, measured by the run
    roof_bf16 = float(a.get("roof_bf16_gflops_per_core", 0) or 0)  # bf16 runs with a bf16 unit
    # Each task's compute roof: that of its precision on its cores (a column from 2026-12-03 on;
    # before, the fp32 roof of its cores). A kind's share of a roof: the seconds its tasks would
    # take at their roofs over the seconds they took.
    if "compute_roof_gflops" in tim and (tim.compute_roof_gflops > 0).all():
        compute = tim.compute_roof_gflops
    else:
        compute = roof * tim.cores
    if roof:
        tim["compute_seconds"] = tim.flops / 1e9 / compute
        by["compute"] = tim.groupby("kind").compute_seconds.sum() / by.seconds.where(by.seconds > 0)
    # The relevant roof of each task: the lower of its compute roof and its memory roof (tasks that
    # stream their weights and Adam state; engines from 0.7.0 on).
    relevant = "memory_roof_gflops" in tim and roof > 0
    if relevant:
        limit = compute.where(tim.memory_roof_gflops <= 0,
                              np.minimum(compute, tim.memory_roof_gflops))
        tim["ideal_seconds"] = tim.flops / 1e9 / limit
        tim["streams"] = tim.memory_roof_gflops > 0
        rel = tim.groupby("kind").agg(ideal=("ideal_seconds", "sum"), streams=("streams", "sum"))
        by["relevant"] = rel.ideal / by.seconds.where(by.seconds > 0)
        by["streams"] = rel.streams
    L = ["", "## Compute by task kind (task-seconds, summed over tasks)", ""]
    if roof:
        L += [f"A task runs on one core, or on several when nothing else was ready or its chain "
              f"was critical (column "
              f"*on > 1 core*); this machine's fp32 roof is {roof:.0f} GFLOP/s per core (measured "
              "at the start of the run), and % of roof is the share of its cores' roof a kind "
              "held." + (f" Tasks whose products ran in bf16 are held to the bf16 unit's roof, "
                         f"{roof_bf16:.0f} GFLOP/s per core." if roof_bf16 else ""), ""]
    if relevant:
        L += ["Tasks whose weights and Adam state do not fit a core's share of the caches stream "
              "them from main memory every step (*memory-bound*, as the cost model counts bytes): "
              "their memory roof is their FLOPs per byte streamed times the bandwidth the run "
              "measured on one core (a STREAM triad). *% of the relevant roof* counts each task "
              "against the lower of its two roofs.", ""]
        L += ["| kind | tasks | on > 1 core | memory-bound | seconds | GFLOP | GFLOP/s | % of roof | "
              "% of the relevant roof |", "|---|---:|---:|---:|---:|---:|---:|---:|---:|"]
    else:
        L += ["| kind | tasks | on > 1 core | seconds | GFLOP | GFLOP/s | % of roof |",
              "|---|---:|---:|---:|---:|---:|---:|"]
    for k, r in by.iterrows():
        pct = f"{100 * r.compute:.0f} %" if roof and r.compute == r.compute else "—"
        if relevant:
            rp = f"{100 * r.relevant:.0f} %" if r.relevant == r.relevant else "—"
            L.append(f"| {k} | {int(r.tasks)} | {int(r.wide)} | {int(r.streams)} | {r.seconds:.1f} | "
                     f"{r.gflop:.1f} | {r['GFLOP/s']:.1f} | {pct} | {rp} |")
        else:
            L.append(f"| {k} | {int(r.tasks)} | {int(r.wide)} | {r.seconds:.1f} | {r.gflop:.1f} | "
                     f"{r['GFLOP/s']:.1f} | {pct} |")
    return L


FIGURES = [("fig3_grid_similar", "Fig. 3"), ("fig4_fpe", "Fig. 4"), ("fig5_tpa", "Fig. 5"),
           ("fig5_tpa_linear", "Fig. 5, linear protocol"), ("fig7_ablation", "Fig. 7")]


def paths_lines(envs, out):
    """Each environment's top-down view (plot_paths.py: fig_paths_<env>) that was drawn, with its
    caption (the environment's title as text: no bracket of it can end the image's markup)."""
    L = []
    for env in envs:
        if os.path.exists(os.path.join(out, f"fig_paths_{env}.png")):
            title = re.sub(r"[\[\]\\]", "", " ".join(env_title(env).split()))
            L += [f"![{title}: the first trajectories seen from above, coloured by each true "
                  f"feature](fig_paths_{env}.png)", ""]
    return L


def profile_description(profile_text):
    """The profile's `description` (its TOML's), on one line; "" without one."""
    import tomllib
    try:
        d = tomllib.loads(profile_text or "").get("description", "")
    except (tomllib.TOMLDecodeError, AttributeError):
        return ""
    return " ".join(d.split()) if isinstance(d, str) else ""


def run_sentence(a, scale):
    """The report's opening sentence: the profile, how many of its tasks the file holds, and its
    scale per environment beside the paper's (`scale`: ledger.scale_phrases)."""
    desc = profile_description(a.get("profile_text", ""))
    done = (f"{a.get('tasks_done')} of {a.get('tasks_total')} tasks done"
            + ("" if a.get("complete") else " (a **partial run**: figures show gaps)"))
    return (f"This run: profile `{a.get('profile_name')}`" + (f" (“{desc}”)" if desc else "")
            + f", {done}" + ("; its scale, the paper's in parentheses: " + "; ".join(scale)
                             if scale else "") + ".")


def report(res, t, envs, out, notes, fig3_key, beyond=None):
    """report.md and report.html: the main claims first (after the title and a sentence on the
    run), then every claim, the ledger, the figures, the learning curves with their convergence
    table, the claims in detail, compute, diagnostics, notes, and the profile's text last."""
    fpe, tpa, tim = t["fpe"], t["tpa"], t["timings"]
    beyond = beyond or {}
    envs = [e for e in envs if ENV.get(e, {}).get("in_claims", 1)]  # e.g. Fig. 3's own env
    a = res.provenance
    H = hypotheses(fpe, tpa, envs, claim_trainings(t))
    for h in H:  # a claim decided on an environment from a file: not the paper's own
        h["beyond_paper"] = beyond_paper(h["env"])
    title = f"sirl-bench report: profile `{a.get('profile_name')}`"
    missing = {}
    for key in res.missing_tasks:
        # A missing task has no row to read its environment from: the environment whose
        # registration names the key's prefix (the key itself is never taken apart).
        env = next((e for e in ENV if key.startswith(e + "/")), "other")
        missing[env] = missing.get(env, 0) + 1
    try:
        study = sirl_bench.study_analysis(res.path)
    except sirl_bench.ResultsError:
        study = None  # the profile ran no study
    book = ledger.ledger(fpe, tpa, envs, study)
    prof_text = a.get("profile_text", "")
    L = [f"# {title}", "",
         run_sentence(a, ledger.scale_phrases(prof_text, methods(fpe), methods(tpa), envs)), ""]
    L += main_claims_lines(H, missing)
    L += ["", "## Every claim: main and secondary, in numbers", ""]
    L += summary_lines(table_order(H), missing, ledger.head_scale(prof_text, envs),
                       [r for r in book if r["kind"] == "study"])
    L += ledger.lines(book, ledger.scale_lines(prof_text, methods(fpe), methods(tpa), envs),
                      lambda v: STYLE[v][1] if v in STYLE else v)
    L += ["", f"Engine {a.get('engine_version')} (commit {a.get('git_commit')}), host "
          f"{a.get('host')}, {a.get('threads')} threads; started {a.get('started')}, finished "
          f"{a.get('finished')}, wall time {float(a.get('wall_seconds', 0)):.0f} s; tasks: "
          f"{a.get('tasks_done')} of {a.get('tasks_total')} done"
          + ("." if a.get("complete") else " — **PARTIAL RUN**: figures show gaps.")]
    L += ["", "## Figures", ""]
    for name, cap in FIGURES:
        if os.path.exists(os.path.join(out, name + ".png")):
            L += [f"![{cap}]({name}.png)", ""]
    L += paths_lines(beyond.get("paths", []), out)
    L += plot_beyond.active_lines(fpe, tim, beyond.get("active", []))
    L += plot_beyond.robustness_lines(fpe, tpa, t["robust_fpe"], t["robust_tpa"],
                                      beyond.get("robustness", []))
    L += external_lines(fpe, tpa, envs)
    L += beyond.get("hyper", [])
    L += ["", "## Learning curves and convergence", ""]
    if os.path.exists(os.path.join(out, "fig_learning_curves.png")):
        L += ["![Learning curves](fig_learning_curves.png)", ""]
    L += convergence_lines(t)
    L += detail_lines(H, envs)
    L += compute_lines(res, tim)
    L += vae_lines(res, t)
    if fig3_key:
        L += ["", f"Fig. 3 uses the representation `{fig3_key}`."]
    if notes:
        L += ["", "## Notes", ""] + [f"- {n}" for n in notes]
    prof = a.get("profile_text", "")
    if prof:
        L += ["", "## Configuration (the profile this file was run with)", ""]
        L += fenced(prof.strip(), "toml")
    L.append("")
    text = "\n".join(L)
    write_text(os.path.join(out, "report.md"), text)
    write_text(os.path.join(out, "report.html"), report_html(title, "\n".join(L[2:])))
    write_text(os.path.join(out, "ledger.json"),
               json.dumps(json_safe({"counts": ledger.counts(book),
                                     "statements": [{k: v for k, v in r.items() if k != "deciding"}
                                                    for r in book]}), indent=1))
    write_text(os.path.join(out, "claims.csv"), comparisons_csv(H, ["env", "claim", "protocol", "main"]))
    write_text(os.path.join(out, "ledger.csv"),
               comparisons_csv(book, ["id", "section", "env", "kind", "metric", "at", "family",
                                      "after_data"]))
    write_text(os.path.join(out, "claims.json"),
               json.dumps(json_safe([{k: v for k, v in h.items() if k != "deciding"} for h in H]),
                          indent=1))
    return text


def fenced(text, lang):
    """A Markdown code block of `text` whose fence is longer than any run of backticks in it, so
    no text (a profile's, from any file) can close the block and continue as markup."""
    fence = "`" * max(3, 1 + max((len(r) for r in re.findall(r"`+", text)), default=0))
    return [fence + lang, text, fence]


def external_lines(fpe, tpa, envs):
    """Each external method next to SIRL, per environment: FPE at the largest N and, under each
    TPA protocol the file ran, TPA (Fig. 5's cells, mean over M) at the largest N, paired over
    seeds. Reported, not decided: these are not claims of the paper."""
    fpe, tpa = methods(fpe), methods(tpa)
    ext = sorted({v for d in (fpe, tpa) if not d.empty
                  for v in d[d.method == "external"].variant.unique()})
    if not ext:
        return []
    L = ["", "## Methods evaluated from outside the engine (`sirl evaluate`)", "",
         "Each method's embeddings of Ξ ran through the engine's own FPE and frozen TPA cells (the "
         "same rows, test rewards, pairs, M values, head initialisations and seeds as SIRL's), "
         "so the difference from SIRL is paired by seed: Δ = method − SIRL with its 95 % t "
         "interval and the two-sided paired t-test's p. No verdict: these are not claims of the "
         "paper.", "",
         "| env | method | metric | N | method | SIRL | Δ [95 % CI] | p | seeds |",
         "|---|---|---|---:|---:|---:|---|---:|---:|"]
    mains = [(p, main_tpa(tpa, p)) for p in protocols_run(tpa)]
    for env in envs:
        for v in ext:
            rows = []
            d = fpe[fpe.env == env] if not fpe.empty else fpe
            if not d.empty and (d.variant == v).any():
                N = d[d.variant == v].N.max()
                at = [d[(d.variant == x) & (d.N == N)].set_index("seed").fpe for x in (v, "sirl")]
                rows.append(("FPE (lower is better)", N, at))
            for protocol, m in mains:
                d = m[m.env == env] if not m.empty else m
                if not d.empty and (d.variant == v).any():
                    N = d[d.variant == v].N.max()
                    at = [d[(d.variant == x) & (d.N == N)].groupby("seed").tpa.mean()
                          for x in (v, "sirl")]
                    rows.append(("TPA (frozen, mean over M)" if protocol == PAPER else
                                 f"TPA ({protocol} protocol, mean over M)", N, at))
            for metric, N, (a, b) in rows:
                c = claims_stats.paired(v, a, b)
                L.append(f"| {env_title(env)} | {v} | {metric} | {N} | {fmt(a.mean())} | "
                         f"{fmt(b.mean())} | {fmt(c['diff'], '+.4f')} [{fmt(c['lo'], '+.4f')}, "
                         f"{fmt(c['hi'], '+.4f')}] | {fmt(c['p'], '.3g')} | {c['n']} |")
    return L


def comparisons_csv(rows, keys):
    """One CSV row per (claim, comparison): the claim's `keys`, its verdict, then the comparison
    (against, n, Δ with its 95 % CI, p, Holm-adjusted p, effect size, test); a claim without
    comparisons gets one row with those empty. For pandas: pd.read_csv(...)."""
    cols = keys + ["verdict", "better", "against", "n", "diff", "lo", "hi", "p", "p_holm", "dz",
                   "test", "power", "seeds80"]
    out = []
    for r in rows:
        base = {k: r.get(k) for k in keys + ["verdict", "better", "power", "seeds80"]}
        for c in r.get("comparisons") or [{}]:
            row = dict(base)
            row.update({k: c.get(k) for k in ("n", "diff", "lo", "hi", "p", "p_holm", "dz", "test")})
            row["against"] = c.get("name")
            out.append(json_safe(row))
    df = pd.DataFrame(out, columns=cols)
    for c in ("n", "seeds80"):
        df[c] = pd.to_numeric(df[c]).round().astype("Int64")
    return df.to_csv(index=False)


def json_safe(x):
    """Plain JSON: numpy scalars as Python numbers, nan/inf as null."""
    if isinstance(x, dict):
        return {k: json_safe(v) for k, v in x.items()}
    if isinstance(x, (list, tuple)):
        return [json_safe(v) for v in x]
    if isinstance(x, (np.integer,)):
        return int(x)
    if isinstance(x, (float, np.floating)):
        return float(x) if math.isfinite(x) else None
    return x


CSS = ("body{font-family:system-ui,sans-serif;max-width:1200px;margin:1em auto;padding:0 1em}"
       "h1{font-size:1.5em}"
       "table{border-collapse:collapse;margin:0.5em 0 1em}th,td{border:1px solid #bbb;"
       "padding:3px 7px;font-size:0.9em;vertical-align:top}th{background:#eee}"
       "caption{font-size:1.2em;font-weight:bold;text-align:left;padding:0.3em 0}"
       "td.v-held{background:#d6f0d6}td.v-not-held{background:#f7d4d4}"
       "td.v-inconclusive{background:#fbedc4}td.v-none{background:#ececec;color:#444}"
       "#main-claims td{min-width:8em}#contents{margin:1em 0;padding:0.3em 1em;"
       "background:#f6f6f6}#contents ul{columns:2;margin:0.3em 0}"
       # A figure may be as wide as the window, not only the text column: Figs. 4, 5 (linear), 7
       # and the learning curves are 2000+ pixels wide and unreadable at 1200.
       "p.figure{width:calc(100vw - 4em);margin-left:calc(50% - 50vw + 2em);text-align:center}"
       "img{max-width:100%;height:auto}pre{background:#f6f6f6;padding:0.6em;overflow-x:auto}")

# A verdict in bold at the start of a table cell → the cell's class (the claims' words and the
# ledger's): the colour repeats the word, it never replaces it.
VERDICT_CLASS = {"held": "v-held", "confirmed": "v-held", "not held": "v-not-held",
                 "contradicted": "v-not-held", "inconclusive": "v-inconclusive",
                 "undecided": "v-inconclusive", "not run": "v-none", "not evaluated": "v-none"}
VERDICT_CELL = re.compile(r"<td>(\s*<strong>(" + "|".join(sorted(VERDICT_CLASS, key=len,
                                                                  reverse=True)) + r")\b)")


def coloured_verdicts(body):
    """Every table cell that opens with a verdict in bold gets its verdict's class (held green,
    not held red, inconclusive amber, not run grey). Only the converter's own <strong> can match:
    a file's text reaches the page escaped."""
    return VERDICT_CELL.sub(lambda m: f'<td class="{VERDICT_CLASS[m.group(2)]}">{m.group(1)}',
                            body)


def named_tables(body):
    """The main claims' table (#main-claims, captioned) and the table of every claim (#summary),
    found by their first header cells, which the report writes."""
    body = re.sub(r"<table>(\s*<thead>\s*<tr>\s*<th>main claim</th>)",
                  r'<table id="main-claims"><caption>Main claims</caption>\1', body, count=1)
    return re.sub(r"<table>(\s*<thead>\s*<tr>\s*<th>claim</th>\s*<th>environment</th>)",
                  r'<table id="summary">\1', body, count=1)


def contents(body):
    """A list of links to every ## section, before the first of them (so after the main claims):
    the page is long and a reader looks for one part. The ids are the converter's (toc
    extension); the titles are the headings' text as the converter escaped it, tags dropped."""
    heads = re.findall(r'<h2 id="([^"]+)">(.*?)</h2>', body)
    if not heads:
        return body
    items = "".join(f'<li><a href="#{i}">{re.sub(r"<[^>]*>", "", t)}</a></li>' for i, t in heads)
    at = body.index("<h2")
    return body[:at] + f'<nav id="contents"><strong>Contents</strong><ul>{items}</ul></nav>\n' + body[at:]


def openable_figures(body):
    """A figure alone in its paragraph links to its file (a click shows it at full size) and may
    span the window (CSS p.figure). The src is the converter's, already escaped and checked."""
    return re.sub(r'<p>(<img [^>]*?src="([^"]*)"[^>]*>)</p>',
                  r'<p class="figure"><a href="\2">\1</a></p>', body)


def safe_url(m):
    """An href or src as the converter wrote it, kept only if it is an anchor, a relative path or
    an http(s) URL; anything else (javascript:, data:, …) goes nowhere. Judged on the value a
    browser would see: entities decoded (&#106;avascript:) and the characters it drops (spaces,
    control characters) removed."""
    seen = re.sub(r"[\x00-\x20\x7f]", "", html.unescape(m.group(2))).lower()
    scheme = re.match(r"([a-z][a-z0-9+.-]*):", seen)
    ok = scheme is None or scheme.group(1) in ("http", "https")
    return f'{m.group(1)}="{m.group(2) if ok else "#"}"'


def report_html(title, body_md):
    """The report's Markdown as HTML (Debian's python3-markdown, tables + fenced code + ids on
    headings): the title, the run's sentence, the main claims' table with its cells coloured by
    verdict, a table of contents, then the rest; figures open full size on a click."""
    import markdown
    # toc: ids on the headings for the contents; its "[TOC]" marker off (a file's text is text).
    md = markdown.Markdown(extensions=["tables", "fenced_code", "toc"],
                           extension_configs={"toc": {"marker": ""}})
    # Every value in the report comes from a results file or a profile, which anyone may have
    # written: raw HTML in them is shown as text, never passed through (no stored script).
    md.preprocessors.deregister("html_block")
    md.inlinePatterns.deregister("html")
    body = md.convert(body_md)
    body = re.sub(r'(href|src)="([^"]*)"', safe_url, body, flags=re.IGNORECASE)
    body = openable_figures(contents(named_tables(coloured_verdicts(body))))
    t = html.escape(title.replace("`", ""))
    return (f"<!doctype html><html><head><meta charset='utf-8'><title>{t}</title>"
            f"<style>{CSS}</style></head><body><h1>{t}</h1>\n{body}</body></html>\n")
