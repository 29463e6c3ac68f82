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
2 an error: one line on stderr, `history.py: error: <what and where>`.

Night files and stores are read as untrusted input: a night is checked whole before anything is
filed (its shape, finite numbers, integers SQLite can hold, names of at most 200 printable
characters, at most 1000 series); a file that is not a store of this schema is refused without
being changed; the dashboard writes only its own index.html and plots.
"""
import argparse
import contextlib
import html
import json
import math
import os
import re
import sqlite3
import stat
import sys
import tempfile
import unicodedata

PROG = "history.py"

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
TABLES = ("nights", "speed", "science", "digests")

# Rows of another kind than this tool files (a hand-made or damaged store): each would fail the
# analysis or the dashboard later, so such a store is refused when opened. Seconds ≥ 0, as
# add_night files them; NaN cannot be stored (NOT NULL); ±inf and beyond ±1e100 are refused
# (MAX_MAGNITUDE).
CONTENT_CHECKS = {
    "nights": "typeof(label) != 'text' OR typeof(time) != 'text' OR typeof(git_commit) != 'text' "
              "OR typeof(host) != 'text' OR typeof(cpu_class) != 'text' OR typeof(cores) != 'integer'",
    "speed": "typeof(night) != 'integer' OR typeof(benchmark) != 'text' OR typeof(rep) != 'integer' "
             "OR typeof(seconds) NOT IN ('real', 'integer') OR NOT (seconds BETWEEN 0 AND 1e100)",
    "science": "typeof(night) != 'integer' OR typeof(profile) != 'text' "
               "OR typeof(profile_digest) != 'text' OR typeof(metric) != 'text' "
               "OR typeof(seed) != 'integer' OR typeof(value) NOT IN ('real', 'integer') "
               "OR NOT (value BETWEEN -1e100 AND 1e100)",
    "digests": "typeof(night) != 'integer' OR typeof(profile) != 'text' "
               "OR typeof(profile_digest) != 'text' OR typeof(tbl) != 'text' OR typeof(digest) != 'text'",
}

K_DEFAULT, FLOOR_DEFAULT, ALPHA_DEFAULT, SCIENCE_SD_DEFAULT = 7, 0.08, 0.01, 2.0

# Bounds of what a night may file, far above what bench/nightly writes (names of tens of
# characters, about a hundred series, five repetitions): a 100 kB name or a million series would
# otherwise stay in the store and break (or stall) every dashboard drawn after it.
MAX_TEXT = 200                # characters of any name, label, commit, host or digest
MAX_SERIES = 1000             # benchmarks, and science metrics, of one night
MAX_ROWS = 100_000            # repetitions, science values, digests of one night (each)
MAX_CORES = 1 << 20
MAX_SEED = (1 << 63) - 1      # SQLite's INTEGER is signed 64-bit; a larger int overflows it
MAX_MAGNITUDE = 1e100         # of seconds and science values: sums, squares and plot axes of
                              # values near the largest double overflow (matplotlib fails on them)
MAX_NIGHT_BYTES = 64 << 20    # a night file (bench/nightly's are well under a megabyte)
META_TEXT = ("label", "time", "git_commit", "host", "cpu_class")


class HistoryError(Exception):
    """A refusal or failure that the command line reports as one line (exit 2)."""


# ------------------------------------------------------------------------- checking a night

def _show(text, limit=60):
    """`text` for a one-line message: non-printable characters escaped (a newline in a name must
    not split the line) and cut to `limit` characters (None: not cut)."""
    text = str(text)
    n = len(text)
    if limit is not None and n > limit:
        text = text[:limit]
    text = "".join(c if c.isprintable() else ascii(c)[1:-1] for c in text)
    return text if limit is None or n <= limit else f"{text}… ({n} characters)"


def _quote(text, limit=60):
    return f'"{_show(text, limit)}"'


def _kind(value):
    """The JSON name of value's type, for messages (never the value: it may be megabytes)."""
    if value is None:
        return "null"
    if isinstance(value, bool):
        return "a boolean"
    if isinstance(value, (int, float)):
        return "a number"
    if isinstance(value, str):
        return "a string"
    if isinstance(value, (list, tuple)):
        return "a list"
    if isinstance(value, dict):
        return "an object"
    return f"a {type(value).__name__}"


def _text(value, what):
    """value, a name the store files: a string of at most MAX_TEXT characters without line breaks
    or other control characters (or lone surrogates, which SQLite cannot encode)."""
    if not isinstance(value, str):
        raise HistoryError(f"{what} is {_kind(value)}, not a string")
    if len(value) > MAX_TEXT:
        raise HistoryError(f"{what} {_quote(value)} is too long (at most {MAX_TEXT} characters)")
    for c in value:
        if unicodedata.category(c) in ("Cc", "Cs", "Zl", "Zp"):
            raise HistoryError(f"{what} {_quote(value)} holds {ascii(c)}, a line break, control "
                               "character or lone surrogate")
    return value


def _number(value, what, low=None):
    """value as a finite float (not a boolean, not a string), at least `low` if given."""
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise HistoryError(f"{what} is {_kind(value)}, not a number")
    try:
        x = float(value)
    except OverflowError:  # an integer of hundreds of digits
        raise HistoryError(f"{what} is an integer too large for a number")
    if not math.isfinite(x):
        raise HistoryError(f"{what} is {x}, not a finite number")
    if abs(x) > MAX_MAGNITUDE:
        raise HistoryError(f"{what} is {x:g}, beyond ±{MAX_MAGNITUDE:g}")
    if low is not None and x < low:
        raise HistoryError(f"{what} is {x:g}, below {low:g}")
    return x


def _integer(value, what, low, high):
    """value as an int in [low, high] (SQLite's INTEGER overflows beyond 64 bits)."""
    if isinstance(value, float):
        raise HistoryError(f"{what} is {value!r}, not an integer")
    if isinstance(value, bool) or not isinstance(value, int):
        raise HistoryError(f"{what} is {_kind(value)}, not an integer")
    if not low <= value <= high:
        raise HistoryError(f"{what} is {_show(value, 30)}, not an integer from {low} to {high}")
    return value


def check_night(meta, speed, science=(), digests=()):
    """Refuses (HistoryError naming the field) a night the store must not file: the one place
    where what a night may hold is decided, for add_night's callers and for JSON nights alike."""
    for k in META_TEXT + ("cores",):
        if k not in meta:
            raise HistoryError(f"a night needs '{k}'")
    for k in META_TEXT:
        _text(meta[k], k)
    _integer(meta["cores"], "cores", 0, MAX_CORES)
    if not isinstance(speed, dict):
        raise HistoryError(f"the benchmarks are {_kind(speed)}, not an object")
    if len(speed) > MAX_SERIES:
        raise HistoryError(f"{len(speed)} benchmarks, at most {MAX_SERIES}")
    n_reps = 0
    for name, reps in speed.items():
        _text(name, "benchmark name")
        where = f"benchmark {_quote(name)}"
        if not isinstance(reps, (list, tuple)):
            raise HistoryError(f"{where}: its repetitions are {_kind(reps)}, not a list of seconds")
        if not reps:
            raise HistoryError(f"{where}: no repetition")
        n_reps += len(reps)
        if n_reps > MAX_ROWS:
            raise HistoryError(f"more than {MAX_ROWS} repetitions")
        for i, s in enumerate(reps):
            _number(s, f"{where}: repetition {i} (seconds)", low=0)
    science, digests = list(science), list(digests)
    for rows, what in ((science, "science values"), (digests, "digests")):
        if len(rows) > MAX_ROWS:
            raise HistoryError(f"{len(rows)} {what}, at most {MAX_ROWS}")
    metrics = set()
    for prof, pd, metric, seed, value in science:
        _text(prof, "profile name")
        _text(pd, f"profile {_quote(prof)}: profile digest")
        _text(metric, f"profile {_quote(prof)}: metric name")
        where = f"profile {_quote(prof)}, metric {_quote(metric)}"
        _integer(seed, f"{where}: seed", -1, MAX_SEED)  # -1: the mean over seeds only
        _number(value, f"{where}" + (f", seed {seed}" if seed >= 0 else "") + ": value")
        metrics.add((prof, metric))
    if len(metrics) > MAX_SERIES:
        raise HistoryError(f"{len(metrics)} science metrics, at most {MAX_SERIES}")
    for prof, pd, tbl, d in digests:
        _text(prof, "profile name")
        _text(pd, f"profile {_quote(prof)}: profile digest")
        _text(tbl, f"profile {_quote(prof)}: table name")
        _text(d, f"profile {_quote(prof)}, table {_quote(tbl)}: digest")


# ------------------------------------------------------------------------------------ the store

def _reference_columns():
    ref = sqlite3.connect(":memory:")
    try:
        ref.executescript(SCHEMA)
        return {t: ref.execute(f"PRAGMA table_info({t})").fetchall() for t in TABLES}
    finally:
        ref.close()


def _schema_problem(con):
    """Why the database behind `con` is not a history store (None if it is one or is empty, then
    creating the schema changes nothing of anyone's)."""
    objects = con.execute("SELECT type, name, tbl_name FROM sqlite_master").fetchall()
    if not objects:
        return None
    tables = sorted(name for kind, name, _ in objects
                    if kind == "table" and not name.startswith("sqlite_"))
    if tables != sorted(TABLES):
        shown = ", ".join(_show(t, 40) for t in tables[:5]) + (", …" if len(tables) > 5 else "")
        return f"its tables are {shown or 'none'}; a store's are {', '.join(TABLES)}"
    for kind, name, tbl in objects:  # views, triggers, an index on a table not ours
        if name.startswith("sqlite_"):  # SQLite's own (sqlite_stat1 of an ANALYZE)
            continue
        if kind not in ("table", "index") or tbl not in TABLES:
            return f"it holds the {kind} {_quote(name, 40)}"
    ref = _reference_columns()
    for t in TABLES:
        if con.execute(f"PRAGMA table_info({t})").fetchall() != ref[t]:
            return f"its table {t} has other columns than a store's"
    for t, bad in CONTENT_CHECKS.items():
        if con.execute(f"SELECT 1 FROM {t} WHERE {bad} LIMIT 1").fetchone():
            return f"its table {t} holds values of another kind than a store's"
    return None


def open_store(path):
    """The store at `path`, created with its schema if the file is new (or an empty database).
    Refuses (HistoryError), without changing it, anything else: another database or schema, a
    file that is not SQLite, a directory."""
    try:
        st = os.stat(path)
    except FileNotFoundError:
        st = None
    except OSError as e:
        raise HistoryError(f"{_show(path, None)}: {e.strerror or e}")
    if st is not None and not stat.S_ISREG(st.st_mode):
        # A FIFO would block SQLite's reads: only regular files are opened.
        kind = "a directory" if stat.S_ISDIR(st.st_mode) else "not a regular file"
        raise HistoryError(f"{_show(path, None)} is not a nightly history store ({kind})")
    try:
        con = sqlite3.connect(path, timeout=60)
    except sqlite3.Error as e:
        raise HistoryError(f"{_show(path, None)}: cannot open or create a store there ({e})")
    try:
        # The schema of a file from elsewhere must not run functions with side effects.
        con.execute("PRAGMA trusted_schema = OFF")
        problem = _schema_problem(con)
        if problem is None:
            # One transaction: the schema is created whole or not at all.
            con.executescript("BEGIN; " + SCHEMA + " COMMIT;")
    except sqlite3.OperationalError as e:  # locked past the timeout, an I/O error, read-only
        con.close()
        raise HistoryError(f"{_show(path, None)}: cannot read the store ({e})")
    except sqlite3.DatabaseError as e:  # "file is not a database", a damaged file
        con.close()
        raise HistoryError(f"{_show(path, None)} is not a nightly history store ({e})")
    if problem is not None:
        con.close()
        raise HistoryError(f"{_show(path, None)} is not a nightly history store ({problem})")
    return con


def machine_class(night):
    return f"{night['cpu_class']}, {night['cores']} cores"


def add_night(con, meta, speed, science=(), digests=()):
    """Files one night in one transaction. meta: label, time (ISO 8601), git_commit, host,
    cpu_class, cores; speed: {benchmark: [seconds of each repetition]}; science: iterable of
    (profile, profile_digest, metric, seed, value); digests: (profile, profile_digest, table,
    digest). Checked first (check_night): nothing is filed of a night it refuses. Returns the
    night's id."""
    science, digests = list(science), list(digests)
    check_night(meta, speed, science, digests)
    with con:
        try:
            cur = con.execute(
                "INSERT INTO nights (label, time, git_commit, host, cpu_class, cores) "
                "VALUES (?, ?, ?, ?, ?, ?)",
                (meta["label"], meta["time"], meta["git_commit"], meta["host"], meta["cpu_class"],
                 meta["cores"]))
        except sqlite3.IntegrityError:
            raise HistoryError(f"night {_quote(meta['label'])} of {_quote(meta['host'])} at "
                               f"{_quote(meta['time'])} is already in the store")
        nid = cur.lastrowid
        con.executemany("INSERT INTO speed VALUES (?, ?, ?, ?)",
                        [(nid, b, i, float(s)) for b, reps in speed.items()
                         for i, s in enumerate(reps)])
        con.executemany("INSERT INTO science VALUES (?, ?, ?, ?, ?, ?)",
                        [(nid, p, pd, m, seed, float(v)) for p, pd, m, seed, v in science])
        con.executemany("INSERT INTO digests VALUES (?, ?, ?, ?, ?)", [(nid, *row) for row in digests])
    return nid


# ------------------------------------------------------------------------------ a JSON night

def _at(where, key):
    """The JSON path of `key` in the object at `where`, for messages: micro["BM_x"]["seconds"]."""
    return f"{where}[{_quote(key)}]" if where else key


def _object(parent, key, where=""):
    """parent[key], an object ({} when absent or null)."""
    value = parent.get(key)
    if value is None:
        return {}
    if not isinstance(value, dict):
        raise HistoryError(f"{_at(where, key)} is {_kind(value)}, not an object")
    return value


def night_from_json(night):
    """The store's view of a bench/nightly JSON night (repetitions when it kept them, else its
    medians as one repetition each), checked by check_night. Raises HistoryError naming the
    field of a night of another shape (a list root, a string where an object or a number belongs,
    non-finite values, a benchmark without its seconds, a 100 kB name)."""
    if not isinstance(night, dict):
        raise HistoryError(f"a night is a JSON object, not {_kind(night)}")
    meta = {"label": night.get("date", "?"), "time": night.get("time", night.get("date", "?")),
            "git_commit": night.get("git_commit", "?"), "host": night.get("host", "?"),
            "cpu_class": night.get("cpu_class", "?"), "cores": night.get("cores", 0)}
    meta["label"] = _text(meta["label"], "date (the label)")
    for k in META_TEXT[1:]:
        _text(meta[k], k)
    speed = {}
    for name, v in _object(night, "micro").items():
        where = _at("micro", name)
        if not isinstance(v, dict):
            raise HistoryError(f"{where} is {_kind(v)}, not an object")
        reps = v.get("repetitions")
        if reps is not None and not isinstance(reps, list):
            raise HistoryError(f'{where}["repetitions"] is {_kind(reps)}, not a list')
        if not reps:  # older nights, or none kept: the median as the one repetition
            if "seconds" not in v:
                raise HistoryError(f'{where} has neither "repetitions" nor "seconds"')
            reps = [v["seconds"]]
        speed[name] = list(reps)
    torch = night.get("torch")
    for name, v in torch.items() if isinstance(torch, dict) else ():
        if isinstance(v, dict) and "ms" in v:  # the PyTorch baseline's cases: their medians
            ms = _number(v["ms"], f'{_at("torch", name)}["ms"]', low=0)
            speed["torch/" + name] = [ms * 1e-3]
    science, digests = [], []
    for prof, p in _object(night, "pipeline").items():
        if not isinstance(p, dict):
            continue
        where = _at("pipeline", prof)
        _text(prof, "profile name")  # before it names a benchmark: pipeline/<name>
        for k in ("wall_seconds", "walls"):
            if k in p:
                speed[f"pipeline/{prof}"] = list(p[k]) if isinstance(p[k], list) else [p[k]]
        pd = p.get("profile_digest", "")
        per_seed = _object(p, "metric_seeds", where)
        for metric, value in _object(p, "metrics", where).items():
            seeds = per_seed.get(metric)
            if not seeds:
                science.append((prof, pd, metric, -1, value))  # the mean only
                continue
            if not isinstance(seeds, dict):
                raise HistoryError(f'{_at(_at(where, "metric_seeds"), metric)} is {_kind(seeds)}, '
                                   "not an object")
            for s, x in seeds.items():
                if not re.fullmatch(r"[0-9]{1,19}", s):  # JSON keys are strings: "0", "1", …
                    raise HistoryError(f'{_at(_at(where, "metric_seeds"), metric)}: seed '
                                       f"{_quote(s)} is not an integer from 0 to {MAX_SEED}")
                science.append((prof, pd, metric, int(s), x))
        for tbl, d in _object(p, "digests", where).items():
            digests.append((prof, pd, tbl, d))
    check_night(meta, speed, science, digests)
    return meta, speed, science, digests


def _parse_int(digits):
    # Python refuses integers of over 4300 digits with advice about sys.set_int_max_str_digits,
    # and none of a night's needs 40.
    if len(digits) > 40:
        raise HistoryError(f"an integer of {len(digits)} digits")
    return int(digits)


def read_night(path):
    """The checked night (night_from_json) in the JSON file at `path`; HistoryError naming the
    file otherwise: not a regular file, too large, not UTF-8, not JSON, nested too deeply."""
    try:
        # O_NONBLOCK: a FIFO named like a night must not block the open; it is refused below.
        fd = os.open(path, os.O_RDONLY | os.O_NONBLOCK)
        with open(fd, "rb") as f:
            if not stat.S_ISREG(os.fstat(f.fileno()).st_mode):
                raise HistoryError(f"{_show(path, None)}: not a regular file")
            data = f.read(MAX_NIGHT_BYTES + 1)
    except OSError as e:
        raise HistoryError(f"{_show(path, None)}: cannot read it ({e.strerror or e})")
    if len(data) > MAX_NIGHT_BYTES:
        raise HistoryError(f"{_show(path, None)}: larger than {MAX_NIGHT_BYTES >> 20} MiB, "
                           "not a night")
    try:
        text = data.decode("utf-8")
    except UnicodeDecodeError as e:
        raise HistoryError(f"{_show(path, None)}: not UTF-8 (byte 0x{data[e.start]:02x} at "
                           f"offset {e.start})")
    try:
        night = json.loads(text, parse_int=_parse_int)
    except RecursionError:
        raise HistoryError(f"{_show(path, None)}: JSON nested too deeply")
    except (ValueError, HistoryError) as e:  # JSONDecodeError, or _parse_int's refusal
        raise HistoryError(f"{_show(path, None)}: not valid JSON ({_show(e, 200)})")
    try:
        return night_from_json(night)
    except HistoryError as e:
        raise HistoryError(f"{_show(path, None)}: {e}")


def _plain(text):
    """`text` for a matplotlib label, drawn as written: a '$' would start mathtext, and a name
    such as '$\\frac{1}{$' would make the figure fail to draw."""
    return str(text).replace("$", r"\$")


def _short(text, limit=MAX_TEXT):
    """`text` for the dashboard: cut to `limit` characters and control characters escaped, so
    that a name filed before names were bounded (a 100 kB metric) still draws."""
    text = str(text)
    cut = text[:limit] + "…" if len(text) > limit else text
    return "".join(c if c.isprintable() else ascii(c)[1:-1] for c in cut)


# ----------------------------------------------------------------------------------- analysis

def _median(xs):
    xs = sorted(xs)
    n = len(xs)
    # Halves first: the mean of two seconds near the largest double must not overflow to inf.
    return xs[n // 2] / 2 + xs[(n - 1) // 2] / 2 if n else float("nan")


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
        if _median(before) <= 0:  # nights of 0 s (filed before seconds were checked): no ratio
            continue
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
        # (x - m) * (x - m), not ** 2: a square beyond the largest double is inf, not an error
        sd = math.sqrt(sum((x - m_now) * (x - m_now) for x in values) / (len(values) - 1)) \
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

# The page starts so (dashboards drawn before this check did too): an index.html that does not is
# someone else's, and is never overwritten.
PAGE_HEAD = ("<!doctype html><html><head><meta charset='utf-8'><title>sirl-bench nightly history"
             "</title>")
# Plot files are named by their position on the page, never by a series name (which may hold
# '/', '..' or 100 kB): no path separators, bounded length, no two alike.
PLOT_NAME = re.compile(r"c[0-9]+-(speed|science)-[0-9]+\.png")


def _drawn_here(index):
    """Whether the file at `index` is a page this tool wrote (not a link to anything)."""
    try:
        st = os.lstat(index)
        if not stat.S_ISREG(st.st_mode):
            return False
        with open(index, "rb") as f:
            return f.read(len(PAGE_HEAD)) == PAGE_HEAD.encode()
    except OSError:
        return False


def _prepare_out(out):
    """Makes `out` ready for a dashboard, or refuses (before anything is drawn) where drawing
    would overwrite a file this tool did not write: `out` a file, an index.html not ours, plot
    names taken in a directory without our index.html."""
    if os.path.lexists(out) and not os.path.isdir(out):
        raise HistoryError(f"--out {_show(out, None)} exists and is not a directory")
    try:
        os.makedirs(out, exist_ok=True)
        index = os.path.join(out, "index.html")
        if os.path.lexists(index):
            if not _drawn_here(index):
                raise HistoryError(f"{_show(index, None)} was not written by {PROG}; not "
                                   "overwriting it (give --out a new or empty directory)")
            return
        taken = sorted(n for n in os.listdir(out) if PLOT_NAME.fullmatch(n))
        if taken:
            raise HistoryError(f"{_show(os.path.join(out, taken[0]), None)} was not written by "
                               f"{PROG}; not overwriting it (give --out a new or empty directory)")
        # Marks the directory as a dashboard before any plot is drawn: a run that dies among
        # the plots leaves a directory the next run recognises as its own.
        _write_file(out, "index.html", (PAGE_HEAD + "</head><body>being drawn</body></html>").encode())
    except OSError as e:
        raise HistoryError(f"--out {_show(out, None)}: cannot write the dashboard there "
                           f"({e.strerror or e})")


def _write_file(out, name, data):
    """Writes `data` (bytes, or a function writing into a binary file) to out/name through a
    temporary file and a rename: a reader never sees half a file, and a link named `name`
    is replaced rather than written through to whatever it points at."""
    fd, tmp = tempfile.mkstemp(prefix=".history-", suffix=".tmp", dir=out)
    try:
        with os.fdopen(fd, "wb") as f:
            if callable(data):
                data(f)
            else:
                f.write(data)
        mask = os.umask(0)
        os.umask(mask)
        os.chmod(tmp, 0o666 & ~mask)  # as open() would have made it (mkstemp's is 0600)
        os.replace(tmp, os.path.join(out, name))
    except BaseException:
        with contextlib.suppress(OSError):
            os.unlink(tmp)
        raise


def dashboard(con, out, k=K_DEFAULT, floor=FLOOR_DEFAULT, alpha=ALPHA_DEFAULT):
    """index.html and one PNG per series and machine class: the nights' medians (speed) or seed
    means (science) in commit order, each night's findings marked. Writes nothing in `out` but
    these (HistoryError where it would overwrite a file of someone else's); removes nothing."""
    _prepare_out(out)
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    def save(fig, name):
        try:
            _write_file(out, name, lambda f: fig.savefig(f, format="png", dpi=110,
                                                         bbox_inches="tight"))
        except OSError as e:
            raise HistoryError(f"{_show(os.path.join(out, name), None)}: cannot write it "
                               f"({e.strerror or e})")
        finally:
            plt.close(fig)

    all_nights = nights(con)
    classes = []
    for n in all_nights:
        if machine_class(n) not in classes:
            classes.append(machine_class(n))
    body = []
    for ci, cls in enumerate(classes):
        same = [n for n in all_nights if machine_class(n) == cls]
        body.append(f"<h2>{html.escape(_short(cls))}</h2><p>{len(same)} nights, "
                    f"{html.escape(_short(same[0]['label']))} to "
                    f"{html.escape(_short(same[-1]['label']))}</p>")
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
            ax.set_xticklabels([_plain(_short(last_commit(n)[:7])) for n, _ in s], rotation=90,
                               fontsize=6)
            ax.set_ylabel("seconds (median)")
            ax.set_title(_plain(f"{_short(b)} — {_short(cls)}"), fontsize=8)
            ax.grid(alpha=0.3)
            name = f"c{ci}-speed-{len(body)}.png"
            save(fig, name)
            body.append(f'<figure><img src="{name}" alt="{html.escape(_short(b))}">'
                        f"<figcaption>{html.escape(_short(b))}: {len(marks)} slower night(s)"
                        + (f"; {html.escape(_short(step['detail'], 3 * MAX_TEXT))}" if step else "")
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
            ax.set_xticklabels([_plain(_short(last_commit(n)[:7])) for n in same], rotation=90,
                               fontsize=6)
            ax.set_title(_plain(f"{_short(m, 2 * MAX_TEXT)} — {_short(cls)}"), fontsize=8)
            ax.grid(alpha=0.3)
            name = f"c{ci}-science-{len(body)}.png"
            save(fig, name)
            body.append(f'<figure><img src="{name}" alt="{html.escape(_short(m, 2 * MAX_TEXT))}">'
                        f"<figcaption>{html.escape(_short(m, 2 * MAX_TEXT))} (mean over seeds)"
                        "</figcaption></figure>")
    page = (PAGE_HEAD + "<style>body{font-family:sans-serif;max-width:60em;margin:auto}"
            "figure{margin:1em 0}img{max-width:100%}</style></head><body>"
            "<h1>sirl-bench nightly history</h1><p>Speed is compared only within a machine "
            "class; red circles: nights slower than their baseline; dashed line: a step.</p>"
            + "".join(body) + "</body></html>")
    try:
        _write_file(out, "index.html", page.encode("utf-8"))
    except OSError as e:
        raise HistoryError(f"--out {_show(out, None)}: cannot write index.html ({e.strerror or e})")
    return os.path.join(out, "index.html")


# ---------------------------------------------------------------------------------------- CLI

def _check_options(a):
    """Option values the analysis needs (a NaN floor or --k 0 would silently compare nothing)."""
    if getattr(a, "k", 1) < 1:
        raise HistoryError(f"--k {a.k}: at least 1 night makes a baseline")
    if not (math.isfinite(getattr(a, "floor", 0.0)) and getattr(a, "floor", 0.0) >= 0):
        raise HistoryError(f"--floor {a.floor}: a finite number ≥ 0")
    if not 0 < getattr(a, "alpha", 0.5) <= 1:
        raise HistoryError(f"--alpha {a.alpha}: a number in (0, 1]")
    if not (math.isfinite(getattr(a, "science_sd", 1.0)) and getattr(a, "science_sd", 1.0) > 0):
        raise HistoryError(f"--science-sd {a.science_sd}: a finite number > 0")


def _run(a):
    _check_options(a)
    if a.cmd in ("add", "import"):
        # Every night is read and checked before the store is opened (or created): a refused
        # night leaves no trace, and `import` files all of its nights or, on a bad file, none.
        parts = [(path, read_night(path)) for path in ([a.night] if a.cmd == "add" else a.nights)]
        with contextlib.closing(open_store(a.store)) as con:
            for path, night in parts:
                try:
                    add_night(con, *night)
                except HistoryError as e:
                    raise HistoryError(f"{_show(path, None)}: {e}")
                print(f"history: filed {_show(path, None)}")
        return 0
    if not os.path.lexists(a.store):
        raise HistoryError(f"{_show(a.store, None)}: no such store")
    with contextlib.closing(open_store(a.store)) as con:
        if a.cmd == "check":
            r = check(con, a.k, a.floor, a.alpha, a.science_sd)
            sys.stdout.write(text_report(r))
            if a.json:
                try:
                    with open(a.json, "w") as f:
                        json.dump(r, f, indent=1, default=str)
                except OSError as e:
                    raise HistoryError(f"--json {_show(a.json, None)}: cannot write the findings "
                                       f"({e.strerror or e})")
            return 1 if any(f["regression"] for f in r["findings"]) else 0
        print("history: wrote", _show(dashboard(con, a.out, a.k, a.floor, a.alpha), None))
        return 0


def main(argv=None):
    ap = argparse.ArgumentParser(prog=PROG, description=__doc__.split("\n")[0],
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
        return _run(a)
    except (HistoryError, OSError, sqlite3.Error, UnicodeError, OverflowError,
            RecursionError) as e:
        # The last line of defence for input that slipped past the checks: one line, exit 2,
        # never a traceback (the checks above name the field; these name at least the error).
        msg = str(e) if isinstance(e, HistoryError) else f"{type(e).__name__}: {e}"
        print(f"{PROG}: error: {_show(msg, 2000)}", file=sys.stderr)
        return 2


if __name__ == "__main__":
    sys.exit(main())
