#!/usr/bin/python3
"""The nightly history: every night's raw benchmark repetitions and science values in one SQLite
file, compared as a history rather than night against night.

    bench/history.py add STORE NIGHT.json          file a night (bench/nightly writes these)
    bench/history.py import STORE OLD.json...      file nights of the older JSON format
    bench/history.py check STORE [--json F]        tonight (the newest night) against its history
    bench/history.py dashboard STORE --out DIR     index.html + one trend plot per series

Why SQLite (Python's standard library): one file, atomic transactions (a night is filed whole or
not at all, even if the process dies), queries by machine class and commit, no server.

What `check` reports (only ever within one machine class: CPU class and core count; a benchmark
of tonight with no earlier night of its class is listed as not compared):
  - speed, tonight against its baseline, the median of the last K nights of the class: slower
    when the median of tonight's repetitions is above the baseline by more than the threshold
    max(--floor, 3 × the baseline nights' relative spread (1.4826 × MAD / median); 15 % while
    fewer than 3 nights make the baseline) and a one-sided
    Mann–Whitney U test of tonight's repetitions against the baseline nights' says so at --alpha
    (a creep is caught as soon as it has grown past the threshold against the median);
  - steps over the whole history of the class: the split of the nights' medians into a before
    and an after (three nights at least on each side) with the smallest Mann–Whitney p; reported
    with the commit range it happened in when p < --alpha and the change exceeds the threshold;
  - science, per profile and metric: tonight's mean over seeds against the previous night of the
    same profile digest and class, in units of tonight's spread over seeds; moved when beyond
    --science-sd standard deviations; a result-table digest that changed under the same profile
    digest is a change of results.
Exit codes: 0 nothing found, 1 a regression (slower, a step up, science moved, results changed),
2 an error.
"""
import argparse
import contextlib
import html
import json
import math
import os
import sqlite3
import sys

SCHEMA = """
CREATE TABLE IF NOT EXISTS nights (
  id INTEGER PRIMARY KEY, label TEXT NOT NULL, time TEXT NOT NULL, git_commit TEXT NOT NULL,
  host TEXT NOT NULL, cpu_class TEXT NOT NULL, cores INTEGER NOT NULL,
  UNIQUE (label, host, time));
CREATE TABLE IF NOT EXISTS speed (
  night INTEGER NOT NULL REFERENCES nights(id), benchmark TEXT NOT NULL, rep INTEGER NOT NULL,
  seconds REAL NOT NULL);
CREATE TABLE IF NOT EXISTS science (
  night INTEGER NOT NULL REFERENCES nights(id), profile TEXT NOT NULL, profile_digest TEXT NOT NULL,
  metric TEXT NOT NULL, seed INTEGER NOT NULL, value REAL NOT NULL);
CREATE TABLE IF NOT EXISTS digests (
  night INTEGER NOT NULL REFERENCES nights(id), profile TEXT NOT NULL, profile_digest TEXT NOT NULL,
  tbl TEXT NOT NULL, digest TEXT NOT NULL);
CREATE INDEX IF NOT EXISTS speed_by_night ON speed(night);
CREATE INDEX IF NOT EXISTS science_by_night ON science(night);
"""

K_DEFAULT, FLOOR_DEFAULT, ALPHA_DEFAULT, SCIENCE_SD_DEFAULT = 7, 0.08, 0.01, 2.0


class HistoryError(Exception):
    pass


def open_store(path):
    """The store at `path` (created with its schema if new)."""
    try:
        con = sqlite3.connect(path, timeout=60)
        con.executescript(SCHEMA)
    except sqlite3.DatabaseError as e:
        raise HistoryError(f"{path}: not a history store ({e})")
    return con


def machine_class(night):
    return f"{night['cpu_class']}, {night['cores']} cores"


def add_night(con, meta, speed, science=(), digests=()):
    """Files one night in one transaction. meta: label, time (ISO 8601), git_commit, host,
    cpu_class, cores; speed: {benchmark: [seconds of each repetition]}; science: iterable of
    (profile, profile_digest, metric, seed, value); digests: (profile, profile_digest, table,
    digest). Returns the night's id."""
    for k in ("label", "time", "git_commit", "host", "cpu_class", "cores"):
        if k not in meta:
            raise HistoryError(f"a night needs '{k}'")
    with con:
        try:
            cur = con.execute(
                "INSERT INTO nights (label, time, git_commit, host, cpu_class, cores) "
                "VALUES (?, ?, ?, ?, ?, ?)",
                (meta["label"], meta["time"], meta["git_commit"], meta["host"], meta["cpu_class"],
                 int(meta["cores"])))
        except sqlite3.IntegrityError:
            raise HistoryError(f"night {meta['label']} of {meta['host']} at {meta['time']} is "
                               "already in the store")
        nid = cur.lastrowid
        con.executemany("INSERT INTO speed VALUES (?, ?, ?, ?)",
                        [(nid, b, i, float(s)) for b, reps in speed.items()
                         for i, s in enumerate(reps) if math.isfinite(float(s))])
        con.executemany("INSERT INTO science VALUES (?, ?, ?, ?, ?, ?)",
                        [(nid, *row) for row in science])
        con.executemany("INSERT INTO digests VALUES (?, ?, ?, ?, ?)", [(nid, *row) for row in digests])
    return nid


def night_from_json(night):
    """The store's view of a bench/nightly JSON night (repetitions when it kept them, else its
    medians as one repetition each). Raises HistoryError on a night of another shape (a list
    root, strings or non-finite values where numbers belong, a benchmark without its seconds)."""
    if not isinstance(night, dict):
        raise HistoryError(f"a night is a JSON object, not {type(night).__name__}")
    try:
        meta, speed, science, digests = _night_parts(night)
        for field in ("label", "time", "git_commit", "host", "cpu_class"):
            meta[field] = str(meta[field])
        meta["cores"] = int(meta["cores"])
    except (TypeError, ValueError, KeyError, AttributeError) as e:
        raise HistoryError(f"not a bench/nightly night ({type(e).__name__}: {e})")
    for name, reps in speed.items():
        if not reps or not all(isinstance(x, (int, float)) and not isinstance(x, bool)
                               and math.isfinite(x) and x >= 0 for x in reps):
            raise HistoryError(f"benchmark {name}: its seconds must be finite numbers ≥ 0")
    for prof, _, metric, _, value in science:
        if not math.isfinite(value):
            raise HistoryError(f"{prof}: metric {metric} is {value}, not a finite number")
    return meta, speed, science, digests


def _night_parts(night):
    meta = {"label": night.get("date", "?"), "time": night.get("time", night.get("date", "?")),
            "git_commit": night.get("git_commit", "?"), "host": night.get("host", "?"),
            "cpu_class": night.get("cpu_class", "?"), "cores": night.get("cores", 0)}
    speed = {}
    for name, v in night.get("micro", {}).items():
        speed[str(name)] = list(v.get("repetitions") or [v["seconds"]])
    for name, v in night.get("torch", {}).items() if isinstance(night.get("torch"), dict) else []:
        if isinstance(v, dict) and "ms" in v:  # the PyTorch baseline's cases: their medians
            speed["torch/" + name] = [v["ms"] * 1e-3]
    science, digests = [], []
    for prof, p in night.get("pipeline", {}).items():
        if not isinstance(p, dict):
            continue
        for k in ("wall_seconds", "walls"):
            if k in p:
                speed[f"pipeline/{prof}"] = p[k] if isinstance(p[k], list) else [p[k]]
        pd = p.get("profile_digest", "")
        for metric, value in p.get("metrics", {}).items():
            seeds = p.get("metric_seeds", {}).get(metric)
            if seeds:
                science += [(prof, pd, metric, int(s), float(x)) for s, x in seeds.items()]
            else:
                science.append((prof, pd, metric, -1, float(value)))  # the mean only
        for tbl, d in p.get("digests", {}).items():
            digests.append((prof, str(pd), str(tbl), str(d)))
    return meta, speed, science, digests


def _plain(text):
    """`text` for a matplotlib label, drawn as written: a '$' would start mathtext, and a name
    such as '$\\frac{1}{$' would make the figure fail to draw."""
    return str(text).replace("$", r"\$")


# ----------------------------------------------------------------------------------- analysis

def _median(xs):
    xs = sorted(xs)
    n = len(xs)
    return (xs[n // 2] + xs[(n - 1) // 2]) / 2 if n else float("nan")


def _spread(values):
    """Relative spread of values: 1.4826 × MAD / median (a robust standard deviation)."""
    m = _median(values)
    if not values or m == 0:
        return 0.0
    return 1.4826 * _median([abs(v - m) for v in values]) / abs(m)


def _mwu_greater(a, b):
    """One-sided Mann–Whitney U p that a's values are larger than b's (scipy)."""
    from scipy.stats import mannwhitneyu
    if len(a) < 1 or len(b) < 1:
        return 1.0
    return float(mannwhitneyu(a, b, alternative="greater").pvalue)


def _mwu_two_sided(a, b):
    from scipy.stats import mannwhitneyu
    return float(mannwhitneyu(a, b, alternative="two-sided").pvalue)


def nights(con):
    cols = ("id", "label", "time", "git_commit", "host", "cpu_class", "cores")
    return [dict(zip(cols, r)) for r in
            con.execute(f"SELECT {', '.join(cols)} FROM nights ORDER BY time, id")]


def speed_series(con, cls_nights):
    """{benchmark: [(night, [seconds…])…]} over the given nights, in their order."""
    out = {}
    ids = {n["id"]: n for n in cls_nights}
    rows = con.execute("SELECT night, benchmark, seconds FROM speed ORDER BY night, rep").fetchall()
    by = {}
    for nid, b, s in rows:
        if nid in ids:
            by.setdefault(b, {}).setdefault(nid, []).append(s)
    for b, per in by.items():
        out[b] = [(n, per[n["id"]]) for n in cls_nights if n["id"] in per]
    return out


def _threshold(base_medians, floor):
    # Fewer than 3 nights say nothing of the noise between nights: 15 % until they do.
    return max(floor, 3 * _spread(base_medians), 0.15 if len(base_medians) < 3 else 0.0)


def check_speed(series, k, floor, alpha, tonight):
    """Findings of one benchmark's series (tonight last): tonight against the last k nights'
    median, and the strongest step over the whole series."""
    found = []
    if not series or series[-1][0]["id"] != tonight["id"]:
        return found
    base = series[:-1][-k:]
    reps = series[-1][1]
    if base:
        base_meds = [_median(r) for _, r in base]
        ref = _median(base_meds)
        ratio = _median(reps) / ref if ref > 0 else float("nan")
        thr = _threshold(base_meds, floor)
        pooled = [s for _, r in base for s in r]
        p = _mwu_greater(reps, pooled) if len(reps) >= 3 and len(pooled) >= 3 else None
        if ratio > 1 + thr and (p is None or p < alpha):
            found.append({"kind": "speed", "verdict": "slower", "regression": True,
                          "ratio": ratio, "threshold": thr, "p": p, "baseline_nights": len(base),
                          "detail": f"{100 * (ratio - 1):+.1f} % against the median of the last "
                                    f"{len(base)} nights (threshold {100 * thr:.1f} %"
                                    + (f", Mann–Whitney p {p:.2g})" if p is not None else ")")})
        elif ratio < 1 - thr and (p is None or _mwu_greater(pooled, reps) < alpha):
            found.append({"kind": "speed", "verdict": "faster", "regression": False,
                          "ratio": ratio, "threshold": thr,
                          "detail": f"{100 * (ratio - 1):+.1f} % against the median of the last "
                                    f"{len(base)} nights"})
    step = find_step(series, floor, alpha)
    if step:
        found.append(step)
    return found


def find_step(series, floor, alpha, min_side=3):
    """The split of the nights' medians into before/after with the smallest two-sided
    Mann–Whitney p; a finding when p < alpha and the change exceeds the threshold."""
    meds = [_median(r) for _, r in series]
    best = None
    for i in range(min_side, len(meds) - min_side + 1):
        before, after = meds[:i], meds[i:]
        p = _mwu_two_sided(after, before)
        ratio = _median(after) / _median(before)
        thr = max(_threshold(before, floor), _threshold(after, floor))
        if abs(ratio - 1) > thr and (best is None or p < best[0]):
            best = (p, i, ratio)
    if not best or best[0] >= alpha:
        return None
    p, i, ratio = best
    first, last = series[i - 1][0], series[i][0]
    return {"kind": "step", "verdict": "step up" if ratio > 1 else "step down",
            "regression": ratio > 1, "ratio": ratio, "p": p,
            "commits": [last_commit(first), last_commit(last)], "night": last["label"],
            "detail": f"{100 * (ratio - 1):+.1f} % from night {last['label']} on: between commits "
                      f"{last_commit(first)} (last before) and {last_commit(last)} "
                      f"(Mann–Whitney p {p:.2g})"}


def last_commit(n):
    return n["git_commit"][:12]


def check_science(con, cls_nights, tonight, science_sd):
    found = []
    ids = [n["id"] for n in cls_nights]
    if tonight["id"] not in ids:
        return found
    earlier = [n for n in cls_nights if n["id"] != tonight["id"]]
    rows = con.execute("SELECT profile, profile_digest, metric, seed, value FROM science "
                       "WHERE night = ?", (tonight["id"],)).fetchall()
    now = {}
    for prof, pd, metric, seed, value in rows:
        now.setdefault((prof, pd, metric), []).append(value)
    for (prof, pd, metric), values in sorted(now.items()):
        prev = None
        for n in reversed(earlier):
            v = [r[0] for r in con.execute(
                "SELECT value FROM science WHERE night = ? AND profile = ? AND profile_digest = ? "
                "AND metric = ?", (n["id"], prof, pd, metric))]
            if v:
                prev = (n, v)
                break
        if prev is None:
            continue
        m_now, m_prev = sum(values) / len(values), sum(prev[1]) / len(prev[1])
        sd = math.sqrt(sum((x - m_now) ** 2 for x in values) / (len(values) - 1)) \
            if len(values) > 1 else 0.0
        if m_now == m_prev:
            continue
        z = abs(m_now - m_prev) / sd if sd > 0 else float("inf")
        if z > science_sd:
            found.append({"kind": "science", "name": f"{prof}: {metric}", "verdict": "moved",
                          "regression": True, "z": z,
                          "detail": f"mean {m_now:.4g} against {m_prev:.4g} on night "
                                    f"{prev[0]['label']} ({z:.1f} seed standard deviations)"})
    dig_now = con.execute("SELECT profile, profile_digest, tbl, digest FROM digests WHERE night = ?",
                          (tonight["id"],)).fetchall()
    for prof, pd, tbl, d in dig_now:
        for n in reversed(earlier):
            r = con.execute("SELECT digest FROM digests WHERE night = ? AND profile = ? AND "
                            "profile_digest = ? AND tbl = ?", (n["id"], prof, pd, tbl)).fetchone()
            if r:
                if r[0] != d:
                    found.append({"kind": "digest", "name": f"{prof}: /tables/{tbl}",
                                  "verdict": "results changed", "regression": True,
                                  "detail": f"digest {d} (night {n['label']}: {r[0]}), same "
                                            "profile, same machine class"})
                break
    return found


def check(con, k=K_DEFAULT, floor=FLOOR_DEFAULT, alpha=ALPHA_DEFAULT, science_sd=SCIENCE_SD_DEFAULT):
    """Findings for the newest night, each a dict with kind, name, verdict, regression, detail."""
    all_nights = nights(con)
    if not all_nights:
        raise HistoryError("the store holds no night")
    tonight = all_nights[-1]
    cls = machine_class(tonight)
    same = [n for n in all_nights if machine_class(n) == cls]
    found = []
    others = sorted({machine_class(n) for n in all_nights} - {cls})
    series = speed_series(con, same)
    for b, s in sorted(series.items()):
        if s[-1][0]["id"] != tonight["id"]:
            continue
        if len(s) == 1:
            found.append({"kind": "speed", "name": b, "verdict": "not compared", "regression": False,
                          "detail": f"no earlier night of this machine class ({cls})"
                                    + (f"; nights of {len(others)} other class(es) are never "
                                       "compared" if others else "")})
            continue
        for f in check_speed(s, k, floor, alpha, tonight):
            f["name"] = b
            found.append(f)
    found += check_science(con, same, tonight, science_sd)
    return {"night": tonight, "machine_class": cls, "other_classes": others, "findings": found}


def text_report(result):
    n = result["night"]
    lines = [f"night {n['label']} (commit {last_commit(n)}, {n['host']}), machine class "
             f"{result['machine_class']}"]
    if result["other_classes"]:
        lines.append(f"  not compared with {len(result['other_classes'])} other class(es): "
                     + "; ".join(result["other_classes"]))
    bad = [f for f in result["findings"] if f["regression"]]
    for f in result["findings"]:
        mark = "REGRESSION" if f["regression"] else "note"
        lines.append(f"  {mark}: {f['name']}: {f['verdict']}: {f['detail']}")
    lines.append(f"{len(bad)} regression(s)" if bad else "no regression")
    return "\n".join(lines) + "\n"


# ---------------------------------------------------------------------------------- dashboard

def dashboard(con, out, k=K_DEFAULT, floor=FLOOR_DEFAULT, alpha=ALPHA_DEFAULT):
    """index.html and one PNG per series and machine class: the nights' medians (speed) or seed
    means (science) in commit order, each night's findings marked."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    os.makedirs(out, exist_ok=True)
    all_nights = nights(con)
    classes = []
    for n in all_nights:
        if machine_class(n) not in classes:
            classes.append(machine_class(n))
    body = []
    for ci, cls in enumerate(classes):
        same = [n for n in all_nights if machine_class(n) == cls]
        body.append(f"<h2>{html.escape(cls)}</h2><p>{len(same)} nights, "
                    f"{html.escape(same[0]['label'])} to {html.escape(same[-1]['label'])}</p>")
        for b, s in sorted(speed_series(con, same).items()):
            meds = [_median(r) for _, r in s]
            marks = []
            for j in range(1, len(s)):
                if any(f["regression"] for f in check_speed(s[:j + 1], k, floor, alpha, s[j][0])
                       if f["kind"] == "speed"):
                    marks.append(j)
            step = find_step(s, floor, alpha)
            fig, ax = plt.subplots(figsize=(8, 2.6))
            ax.plot(range(len(s)), meds, "o-", ms=3, color="#1f77b4")
            for j in marks:
                ax.plot(j, meds[j], "o", ms=8, mfc="none", mec="#d62728", mew=2)
            if step:
                i = [x[0]["label"] for x in s].index(step["night"])
                ax.axvline(i - 0.5, color="#d62728", ls="--", lw=1)
            ax.set_xticks(range(len(s)))
            ax.set_xticklabels([_plain(last_commit(n)[:7]) for n, _ in s], rotation=90,
                               fontsize=6)
            ax.set_ylabel("seconds (median)")
            ax.set_title(_plain(f"{b} — {cls}"), fontsize=8)
            ax.grid(alpha=0.3)
            name = f"c{ci}-speed-{len(body)}.png"
            fig.savefig(os.path.join(out, name), dpi=110, bbox_inches="tight")
            plt.close(fig)
            body.append(f'<figure><img src="{name}" alt="{html.escape(b)}">'
                        f"<figcaption>{html.escape(b)}: {len(marks)} slower night(s)"
                        + (f"; {html.escape(step['detail'])}" if step else "")
                        + "</figcaption></figure>")
        rows = con.execute(
            "SELECT night, profile, metric, AVG(value) FROM science GROUP BY night, profile, metric"
        ).fetchall()
        ids = {n["id"]: j for j, n in enumerate(same)}
        metrics = {}
        for nid, prof, metric, v in rows:
            if nid in ids:
                metrics.setdefault(f"{prof}: {metric}", []).append((ids[nid], v))
        for m, pts in sorted(metrics.items()):
            fig, ax = plt.subplots(figsize=(8, 2.2))
            ax.plot([p[0] for p in pts], [p[1] for p in pts], "o-", ms=3, color="#2ca02c")
            ax.set_xticks(range(len(same)))
            ax.set_xticklabels([_plain(last_commit(n)[:7]) for n in same], rotation=90,
                               fontsize=6)
            ax.set_title(_plain(f"{m} — {cls}"), fontsize=8)
            ax.grid(alpha=0.3)
            name = f"c{ci}-science-{len(body)}.png"
            fig.savefig(os.path.join(out, name), dpi=110, bbox_inches="tight")
            plt.close(fig)
            body.append(f'<figure><img src="{name}" alt="{html.escape(m)}">'
                        f"<figcaption>{html.escape(m)} (mean over seeds)</figcaption></figure>")
    page = ("<!doctype html><html><head><meta charset='utf-8'><title>sirl-bench nightly history"
            "</title><style>body{font-family:sans-serif;max-width:60em;margin:auto}"
            "figure{margin:1em 0}img{max-width:100%}</style></head><body>"
            "<h1>sirl-bench nightly history</h1><p>Speed is compared only within a machine "
            "class; red circles: nights slower than their baseline; dashed line: a step.</p>"
            + "".join(body) + "</body></html>")
    with open(os.path.join(out, "index.html"), "w") as f:
        f.write(page)
    return os.path.join(out, "index.html")


# ---------------------------------------------------------------------------------------- CLI

def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0],
                                 formatter_class=argparse.RawDescriptionHelpFormatter, epilog=__doc__)
    sub = ap.add_subparsers(dest="cmd", required=True)
    a_add = sub.add_parser("add", help="file a bench/nightly JSON night")
    a_imp = sub.add_parser("import", help="file nights of the older JSON format")
    a_chk = sub.add_parser("check", help="tonight against its history")
    a_dash = sub.add_parser("dashboard", help="draw index.html and the trend plots")
    for p in (a_add, a_imp, a_chk, a_dash):
        p.add_argument("store")
    a_add.add_argument("night")
    a_imp.add_argument("nights", nargs="+")
    for p in (a_chk, a_dash):
        p.add_argument("--k", type=int, default=K_DEFAULT, help="baseline nights (median)")
        p.add_argument("--floor", type=float, default=FLOOR_DEFAULT,
                       help="smallest relative slowdown reported")
        p.add_argument("--alpha", type=float, default=ALPHA_DEFAULT)
    a_chk.add_argument("--science-sd", type=float, default=SCIENCE_SD_DEFAULT)
    a_chk.add_argument("--json", help="write the findings here")
    a_dash.add_argument("--out", required=True)
    a = ap.parse_args(argv)
    try:
        if a.cmd in ("add", "import") or os.path.exists(a.store):
            con = open_store(a.store)
        else:
            raise HistoryError(f"{a.store}: no such store")
        with contextlib.closing(con):
            if a.cmd == "add" or a.cmd == "import":
                for path in ([a.night] if a.cmd == "add" else a.nights):
                    try:
                        night = json.load(open(path))
                    except (OSError, json.JSONDecodeError) as e:
                        raise HistoryError(f"{path}: {e}")
                    try:
                        parts = night_from_json(night)
                    except HistoryError as e:
                        raise HistoryError(f"{path}: {e}")
                    add_night(con, *parts)
                    print(f"history: filed {path}")
                return 0
            if a.cmd == "check":
                r = check(con, a.k, a.floor, a.alpha, a.science_sd)
                sys.stdout.write(text_report(r))
                if a.json:
                    with open(a.json, "w") as f:
                        json.dump(r, f, indent=1, default=str)
                return 1 if any(f["regression"] for f in r["findings"]) else 0
            print("history: wrote", dashboard(con, a.out, a.k, a.floor, a.alpha))
            return 0
    except HistoryError as e:
        print(f"history: error: {e}", file=sys.stderr)
        return 2


if __name__ == "__main__":
    sys.exit(main())
