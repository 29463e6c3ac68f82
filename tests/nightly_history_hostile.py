#!/usr/bin/python3
"""bench/history.py on hostile input (night files and stores from elsewhere): each case runs the
command line and wants exit 2, exactly one line on stderr starting `history.py: error:` (naming
the field or file where the case says), no traceback, no hang, and every file the case made
unchanged (bytes, links and listing of its directory, compared before and after):

- night files: invalid UTF-8; 1e400, NaN, Infinity, 1e300, a 5000-digit integer where numbers
  belong; 20-digit integers where SQLite integers belong (cores, seeds); 100000 nested '['; a
  FIFO; 100 kB names (benchmark, metric, profile, label, digest); a newline or a lone surrogate
  in a name; wrong JSON types and missing keys;
- stores: an SQLite database of other tables, tables named like ours with other columns, ours
  plus another, rows of another kind, not SQLite, a directory;
- outputs: `dashboard --out` a regular file, or a directory whose index.html or plot names are
  someone else's; `check --json` a directory.

And what must still work: a dashboard of a store that already holds a 100 kB name (filed before
names were bounded) is drawn, bounded; a dashboard drawn among a user's files or over its own
earlier one leaves the user's files (and a link's target) alone.

SIRL_HISTORY_PY runs another bench/history.py (e.g. an older one, to see these cases fail).
"""
import concurrent.futures
import copy
import functools
import json
import os
import shutil
import sqlite3
import subprocess
import sys
import tempfile

SRC = os.environ["SIRL_SOURCE_DIR"]
HIST = os.environ.get("SIRL_HISTORY_PY") or os.path.join(SRC, "bench", "history.py")
PY = "/usr/bin/python3"

GOOD = {"date": "d1", "time": "2026-01-01T00:00:01", "git_commit": "c0ffee" + "0" * 34,
        "host": "h", "cpu_class": "c", "cores": 2,
        "micro": {"b1": {"seconds": 0.01, "repetitions": [0.010, 0.011, 0.012]}},
        "torch": None,
        "pipeline": {"smoke": {"wall_seconds": 10, "walls": [10, 11], "profile_digest": "pd",
                               "metrics": {"m": 0.5}, "metric_seeds": {"m": {"0": 0.4, "1": 0.6}},
                               "digests": {"tpa": "aaaa"}}}}
BIG = "x" * 100_000
failures = []
pending = []  # the cases, each a function returning (case, reasons it failed, stderr)


def night(change=None, raw=None):
    """GOOD as JSON bytes, changed by change(n) on a copy; raw replaces the string "@RAW@" by
    text json.dumps cannot write (1e400, a 20-digit literal)."""
    n = copy.deepcopy(GOOD)
    if change:
        change(n)
    text = json.dumps(n)
    if raw is not None:
        text = text.replace('"@RAW@"', raw)
    return text.encode()


def snapshot(root):
    """Every entry under root: bytes of files, targets of links, kinds of the rest."""
    out = {}
    for d, dirs, files in os.walk(root):
        for name in dirs + files:
            p = os.path.join(d, name)
            rel = os.path.relpath(p, root)
            if os.path.islink(p):
                out[rel] = ("link", os.readlink(p))
            elif os.path.isdir(p):
                out[rel] = ("dir",)
            elif os.path.isfile(p):
                out[rel] = ("file", open(p, "rb").read())
            else:
                out[rel] = ("other",)
    return out


def run(args, cwd, timeout=60):
    try:
        p = subprocess.run([PY, HIST, *args], cwd=cwd, capture_output=True, timeout=timeout,
                           stdin=subprocess.DEVNULL)
    except subprocess.TimeoutExpired:
        return None, "", ""
    return p.returncode, p.stdout.decode(errors="replace"), p.stderr.decode(errors="replace")


def refused(case, setup, args, names=(), timeout=10):
    """setup(dir) makes the case's files in a fresh directory and returns nothing; args are
    relative to it. Wants exit 2, one `history.py: error:` line naming each of `names`, no
    traceback, every file as it was."""
    pending.append(functools.partial(_refused, case, setup, args, names, timeout))


def _refused(case, setup, args, names, timeout):
    d = tempfile.mkdtemp(prefix="hostile-", dir=TMP)
    setup(d)
    before = snapshot(d)
    rc, out, err = run(args, d, timeout)
    why = []
    if rc is None:
        why.append(f"hung (no exit within {timeout} s)")
    else:
        if rc != 2:
            why.append(f"exit {rc}, not 2")
        if "Traceback" in err:
            why.append("a traceback")
        if err.count("\n") != 1 or not err.endswith("\n"):
            why.append(f"{err.count(chr(10))} lines on stderr, not 1")
        if not err.startswith("history.py: error:"):
            why.append("stderr does not start with 'history.py: error:'")
        why += [f"{n!r} not named" for n in names if n not in err]
    after = snapshot(d)
    changed = sorted(k for k in set(before) | set(after) if before.get(k) != after.get(k))
    if changed:
        why.append(f"files changed: {changed[:5]}")
    return case, why, err


def report(case, why, err=""):
    if why:
        failures.append(case)
        print(f"FAIL {case}: {'; '.join(why)}\n     stderr: {err[-300:]!r}")
    else:
        print(f"ok   {case}: {err.strip()[:140]}")


def write(path, data):
    with open(path, "wb") as f:
        f.write(data)


def with_store(d):
    shutil.copy(STORE, os.path.join(d, "h.sqlite"))


def night_case(case, data, names=(), cmd="add"):
    """`add` (or `import`) of a night file holding `data` into a store of one good night."""
    def setup(d):
        with_store(d)
        if data is not None:
            write(os.path.join(d, "n.json"), data)
    refused(case, setup, [cmd, "h.sqlite", "n.json"], names)


def sqlite_file(statements):
    def setup(d):
        con = sqlite3.connect(os.path.join(d, "h.sqlite"))
        con.executescript(statements)
        con.commit()
        con.close()
    return setup


def set_in(path, value):
    """A change setting GOOD[path…] = value."""
    def change(n):
        for k in path[:-1]:
            n = n[k]
        n[path[-1]] = value
    return change


def night_files():
    # 1. Not UTF-8 (add, and import).
    bad = night().replace(b'"host": "h"', b'"host": "h\xff\xfe"')
    night_case("invalid UTF-8 (add)", bad, ["n.json", "UTF-8"])
    night_case("invalid UTF-8 (import)", bad, ["n.json", "UTF-8"], cmd="import")
    # 2. Numbers that are not finite, or not numbers JSON can hold.
    night_case("seconds 1e400", night(set_in(["micro", "b1", "repetitions"], "@RAW@"),
                                      "[0.01, 1e400]"), ["b1", "finite"])
    night_case("seconds NaN", night(set_in(["micro", "b1", "repetitions"], "@RAW@"),
                                    "[NaN, 0.01]"), ["b1", "finite"])
    night_case("wall seconds -Infinity", night(set_in(["pipeline", "smoke", "walls"], "@RAW@"),
                                               "[-Infinity]"), ["pipeline/smoke"])
    night_case("metric Infinity", night(set_in(["pipeline", "smoke", "metrics", "m2"], "@RAW@"),
                                        "Infinity"), ["m2", "finite"])
    night_case("seed value 1e400", night(set_in(["pipeline", "smoke", "metric_seeds", "m"], "@RAW@"),
                                         '{"0": 1e400}'), ["m", "seed 0"])
    night_case("5000-digit seconds", night(set_in(["micro", "b1", "seconds"], "@RAW@"),
                                           "9" * 5000), ["n.json"])
    night_case("seconds 1e300 (finite, but sums and plot axes of it overflow)",
               night(set_in(["micro", "b1", "repetitions"], [1e300])), ["b1", "1e+300"])
    night_case("negative seconds", night(set_in(["micro", "b1", "repetitions"], [0.01, -1])),
               ["b1"])
    # 3. Integers beyond SQLite's 64 bits.
    night_case("cores 20 digits", night(set_in(["cores"], "@RAW@"), "123456789012345678901"),
               ["cores"])
    night_case("cores 1e400", night(set_in(["cores"], "@RAW@"), "1e400"), ["cores"])
    night_case("seed 20 digits", night(set_in(["pipeline", "smoke", "metric_seeds", "m"],
                                              {"123456789012345678901": 0.5})), ["seed"])
    # 4. Nesting, and a night file that would block a reader.
    night_case("100000 nested [", b"[" * 100_000 + b"]" * 100_000, ["n.json", "nested"])
    night_case("100000 nested [ (import)", b'{"micro": ' + b"[" * 100_000, ["n.json"], cmd="import")

    def fifo(d):
        with_store(d)
        os.mkfifo(os.path.join(d, "n.json"))
    refused("night file a FIFO (import)", fifo, ["import", "h.sqlite", "n.json"], ["n.json"])
    # 8. Names: 100 kB, a line break, a lone surrogate (SQLite cannot encode it).
    night_case("100 kB benchmark name", night(set_in(["micro", BIG], {"seconds": 1.0})),
               ["benchmark", "too long"])
    night_case("100 kB metric name", night(set_in(["pipeline", "smoke", "metrics", BIG], 0.5)),
               ["metric", "too long"])
    night_case("100 kB profile name",
               night(lambda n: n["pipeline"].update({BIG: n["pipeline"]["smoke"]})),
               ["profile", "too long"])
    night_case("100 kB label", night(set_in(["date"], BIG)), ["date", "too long"])
    night_case("100 kB digest", night(set_in(["pipeline", "smoke", "digests", "tpa"], BIG)),
               ["digest", "too long"])
    night_case("newline in a benchmark name",
               night(set_in(["micro", "b\nREGRESSION: fake"], {"seconds": 1.0})), ["benchmark"])
    night_case("lone surrogate in a benchmark name",
               night(set_in(["micro", "@KEY@"], {"seconds": 1.0})).replace(b"@KEY@", b"\\ud800"),
               ["benchmark"])
    # 9. Wrong JSON types, missing keys: the field is named.
    night_case("micro a string", night(set_in(["micro"], "fast")), ["micro", "not an object"])
    night_case("pipeline a list", night(set_in(["pipeline"], [1, 2])), ["pipeline"])
    night_case("a benchmark a list", night(set_in(["micro", "b1"], [0.01])), ["micro", "b1"])
    night_case("repetitions a string", night(set_in(["micro", "b1", "repetitions"], "0.01")),
               ["b1", "repetitions"])
    night_case("repetitions of strings", night(set_in(["micro", "b1", "repetitions"], ["0.01"])),
               ["b1", "not a number"])
    night_case("no seconds", night(set_in(["micro", "b1"], {"cv": 0.1})), ["b1", "seconds"])
    night_case("metrics a list", night(set_in(["pipeline", "smoke", "metrics"], [0.5])),
               ["metrics"])
    night_case("metric seeds a list", night(set_in(["pipeline", "smoke", "metric_seeds", "m"],
                                                   [0.4, 0.6])), ["metric_seeds", "m"])
    night_case("seed not an integer", night(set_in(["pipeline", "smoke", "metric_seeds", "m"],
                                                   {"one": 0.4})), ["seed", "one"])
    night_case("digest a number", night(set_in(["pipeline", "smoke", "digests", "tpa"], 7)),
               ["digest", "tpa"])
    night_case("host an object", night(set_in(["host"], {"name": "h"})), ["host"])
    night_case("cores true", night(set_in(["cores"], True)), ["cores"])
    night_case("torch ms a string", night(set_in(["torch"], {"case": {"ms": "slow"}})),
               ["torch", "case"])


def stores():
    good_night = night()

    def foreign(statements):
        def setup(d):
            sqlite_file(statements)(d)
            write(os.path.join(d, "n.json"), good_night)
        return setup
    users = ("CREATE TABLE users (id INTEGER PRIMARY KEY, name TEXT); "
             "INSERT INTO users VALUES (1, 'ada');")
    for cmd in ("check", "add", "dashboard"):
        args = {"check": ["check", "h.sqlite"], "add": ["add", "h.sqlite", "n.json"],
                "dashboard": ["dashboard", "h.sqlite", "--out", "dash"]}[cmd]
        refused(f"store of unrelated tables ({cmd})", foreign(users), args,
                ["h.sqlite", "not a nightly history store"])
    like_ours = ("CREATE TABLE nights (id INTEGER PRIMARY KEY, name TEXT); "
                 "CREATE TABLE speed (x); CREATE TABLE science (x); CREATE TABLE digests (x); "
                 "INSERT INTO nights VALUES (1, 'n');")
    refused("tables named like ours, other columns (check)", foreign(like_ours),
            ["check", "h.sqlite"], ["not a nightly history store", "columns"])
    refused("tables named like ours, other columns (add)", foreign(like_ours),
            ["add", "h.sqlite", "n.json"], ["not a nightly history store"])

    def ours_plus(extra):
        def setup(d):
            with_store(d)
            con = sqlite3.connect(os.path.join(d, "h.sqlite"))
            con.executescript(extra)
            con.commit()
            con.close()
            write(os.path.join(d, "n.json"), night(set_in(["date"], "d2")))
        return setup
    refused("our tables plus another (add)", ours_plus("CREATE TABLE notes (t TEXT);"),
            ["add", "h.sqlite", "n.json"], ["not a nightly history store", "notes"])
    refused("rows of another kind: seconds 'fast' (check)",
            ours_plus("INSERT INTO speed VALUES (1, 'b1', 9, 'fast');"),
            ["check", "h.sqlite"], ["not a nightly history store", "speed"])
    refused("rows of another kind: a night's cores 'two' (dashboard)",
            ours_plus("UPDATE nights SET cores = 'two';"),
            ["dashboard", "h.sqlite", "--out", "dash"], ["not a nightly history store"])

    def junk(d):
        write(os.path.join(d, "h.sqlite"), b"not a database\n" * 100)
        write(os.path.join(d, "n.json"), good_night)
    refused("store not SQLite (add)", junk, ["add", "h.sqlite", "n.json"],
            ["not a nightly history store"])
    refused("store not SQLite (check)", junk, ["check", "h.sqlite"],
            ["not a nightly history store"])

    def a_dir(d):
        os.mkdir(os.path.join(d, "h.sqlite"))
        write(os.path.join(d, "h.sqlite", "mine.txt"), b"mine\n")
        write(os.path.join(d, "n.json"), good_night)
    refused("store a directory (check)", a_dir, ["check", "h.sqlite"], ["directory"])
    refused("store a directory (add)", a_dir, ["add", "h.sqlite", "n.json"], ["directory"])


def outputs():
    def out_file(d):
        with_store(d)
        write(os.path.join(d, "report.txt"), b"the user's report\n")
    refused("dashboard --out a regular file", out_file,
            ["dashboard", "h.sqlite", "--out", "report.txt"], ["report.txt"])

    def users_index(d):
        with_store(d)
        os.mkdir(os.path.join(d, "site"))
        write(os.path.join(d, "site", "index.html"), b"<html>the user's site</html>\n")
        write(os.path.join(d, "site", "notes.txt"), b"notes\n")
    refused("dashboard --out a directory with someone's index.html", users_index,
            ["dashboard", "h.sqlite", "--out", "site"], ["index.html"])

    def users_plot(d):
        with_store(d)
        os.mkdir(os.path.join(d, "site"))
        write(os.path.join(d, "site", "c0-speed-1.png"), b"the user's picture\n")
    refused("dashboard --out a directory with someone's c0-speed-1.png", users_plot,
            ["dashboard", "h.sqlite", "--out", "site"], ["c0-speed-1.png"])

    def json_dir(d):
        with_store(d)
        os.mkdir(os.path.join(d, "findings"))
    refused("check --json a directory", json_dir,
            ["check", "h.sqlite", "--json", "findings"], ["findings"])


def what_still_works():
    pending.append(legacy_names_drawn)
    pending.append(users_files_untouched)


def legacy_names_drawn():
    """A dashboard of a store holding 100 kB names (filed by a version before the bounds)."""
    d = tempfile.mkdtemp(prefix="works-", dir=TMP)
    legacy = os.path.join(d, "legacy.sqlite")
    shutil.copy(STORE, legacy)
    con = sqlite3.connect(legacy)
    con.execute("INSERT INTO speed VALUES (1, ?, 0, 0.5)", ("B" * 100_000,))
    con.execute("INSERT INTO science VALUES (1, 'smoke', 'pd', ?, -1, 0.5)", ("M\n" * 50_000,))
    con.commit()
    con.close()
    rc, out, err = run(["dashboard", legacy, "--out", os.path.join(d, "dash")], d, timeout=120)
    page = os.path.join(d, "dash", "index.html")
    why = [] if rc == 0 else [f"exit {rc}" if rc is not None else "hung"]
    if rc == 0 and os.path.getsize(page) > 20_000:
        why.append(f"index.html of {os.path.getsize(page)} bytes: the names are not bounded")
    return "dashboard of a store holding 100 kB names (drawn, bounded)", why, err


def users_files_untouched():
    """A dashboard into a directory of a user's files, then over itself, its plot now a link."""
    d = tempfile.mkdtemp(prefix="works-", dir=TMP)
    site = os.path.join(d, "site")
    os.mkdir(site)
    write(os.path.join(site, "notes.txt"), b"notes\n")
    outside = os.path.join(d, "precious.png")
    write(outside, b"precious\n")
    why = []
    for attempt in range(2):  # a new dashboard among the user's files, then over itself
        rc, out, err = run(["dashboard", STORE, "--out", site], d)
        if rc != 0:
            why.append(f"run {attempt + 1}: exit {rc}: {err[-300:]}")
        if attempt == 0 and rc == 0:  # the first plot replaced by a link to a file elsewhere
            os.remove(os.path.join(site, "c0-speed-1.png"))
            os.symlink(outside, os.path.join(site, "c0-speed-1.png"))
    if open(os.path.join(site, "notes.txt"), "rb").read() != b"notes\n":
        why.append("the user's notes.txt changed")
    if open(outside, "rb").read() != b"precious\n":
        why.append("a file outside --out was written through a link")
    if rc == 0 and [n for n in os.listdir(site) if n.endswith(".tmp")]:
        why.append("temporary files left")
    return "dashboard among a user's files, then over itself (their files untouched)", why, err


def main():
    global TMP, STORE
    TMP = tempfile.mkdtemp(prefix="sirl-history-hostile-")
    # The store every case starts from: one good night, filed by the command line.
    base = os.path.join(TMP, "base")
    os.mkdir(base)
    # (Another night than the cases' own, which would otherwise be refused as already filed.)
    write(os.path.join(base, "n.json"), night(lambda n: n.update(date="d0", time="2026-01-01T00:00:00")))
    STORE = os.path.join(base, "h.sqlite")
    rc, out, err = run(["add", STORE, os.path.join(base, "n.json")], base)
    if rc != 0:
        print(f"nightly_history_hostile: FAIL: a good night was refused: {err}")
        sys.exit(1)
    night_files()
    stores()
    outputs()
    what_still_works()
    # Each case is a few short processes in its own directory: run side by side.
    with concurrent.futures.ThreadPoolExecutor(min(4, max(2, os.cpu_count() or 1))) as ex:
        for case, why, err in ex.map(lambda f: f(), pending):
            report(case, why, err)
    shutil.rmtree(TMP, ignore_errors=True)
    if failures:
        print(f"nightly_history_hostile: FAIL: {len(failures)} case(s): {', '.join(failures)}")
        sys.exit(1)
    print("nightly_history_hostile: OK")


if __name__ == "__main__":
    main()
