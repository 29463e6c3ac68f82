#!/usr/bin/python3
"""The nightly history (bench/history.py) on synthetic histories built here (no timing):

- a 15 % step at one commit is reported within 3 nights and attributed to that commit;
- a 5 %-per-night creep is found within 4 nights;
- ±5 % night-to-night noise (and ±2 % between repetitions) alone for 30 nights: nothing found at
  any night;
- a night of another machine class is compared with nothing, and the output says so; a history
  of another class at twice the speed changes nothing for this class;
- a science metric moved by 3 seed standard deviations is found; one moved by 0.5 is not; a
  changed table digest under the same profile is found;
- `check` exits 1 on a regression, 0 without, 2 on a store that is not one; the JSON findings
  and the dashboard are written, and the dashboard opens in chromium with every image loaded.
"""
import json
import os
import random
import subprocess
import sys
import tempfile

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import sirl_testing  # noqa: E402

SRC = sirl_testing.source_dir()
sys.path.insert(0, os.path.join(SRC, "bench"))
import history  # noqa: E402

BENCH = "BM_SirlStep/in:19/hidden:128/threads:1/real_time"


fail = sirl_testing.make_fail("nightly_history")


def build(path, levels, seed=1, cls="AMD EPYC Zen 5", cores=2, science=None, start=0):
    """A store with one night per level (its true speed, seconds), ±5 % night noise and ±2 %
    between its 5 repetitions; science(i) gives night i's (metric, seed, value) rows."""
    con = history.open_store(path)
    rng = random.Random(seed)
    for i, level in enumerate(levels):
        night = level * (1 + rng.uniform(-0.05, 0.05))
        reps = [night * (1 + rng.uniform(-0.02, 0.02)) for _ in range(5)]
        sci = [("smoke", "p1", m, s, v) for m, s, v in science(i)] if science else []
        history.add_night(con, {"label": f"n{start + i:03d}", "time": f"2026-01-01T{start + i:05d}",
                                "git_commit": f"c{start + i:03d}" + "0" * 37, "host": "h",
                                "cpu_class": cls, "cores": cores}, {BENCH: reps}, sci)
    return con


def regressions(con):
    return [f for f in history.check(con)["findings"] if f["regression"]]


def main():
    tmp = tempfile.mkdtemp(prefix="sirl-history-")
    # A 15 % step at night 12 (commit c012).
    levels = [1e-3] * 12 + [1.15e-3] * 10
    con = build(os.path.join(tmp, "step.sqlite"), levels)
    steps = [f for f in history.check(con)["findings"] if f["kind"] == "step"]
    if len(steps) != 1 or steps[0]["commits"] != ["c011" + "0" * 8, "c012" + "0" * 8]:
        fail(f"the 15 % step: {steps}")
    con.close()
    first = None  # the first night after the step whose check reports it
    for n in range(13, 16):
        con = build(os.path.join(tmp, f"step-night{n}.sqlite"), levels[:n])
        if regressions(con):
            first = n - 12
            break
    if first is None:
        fail("the 15 % step was not reported within 3 nights")
    print(f"nightly_history: a 15 % step reported on its night {first}, then attributed: "
          f"{steps[0]['detail']}")

    # A 5 %-per-night creep from night 10 on: found within 4 nights.
    found_at = None
    for extra in range(1, 5):
        levels = [1e-3] * 10 + [1e-3 * 1.05 ** j for j in range(1, extra + 1)]
        con = build(os.path.join(tmp, f"creep{extra}.sqlite"), levels)
        if regressions(con):
            found_at = extra
            break
    if found_at is None:
        fail("a 5 %-per-night creep was not found within 4 nights")
    print(f"nightly_history: a 5 %-per-night creep found on its night {found_at}")

    # Noise alone, 30 nights, several noise draws: nothing at any night.
    for seed in range(1, 6):
        for n in range(2, 31):
            con = build(os.path.join(tmp, f"noise{seed}-{n}.sqlite"), [1e-3] * n, seed=seed)
            if regressions(con):
                fail(f"noise alone (draw {seed}) flagged night {n}: {regressions(con)}")
            con.close()
    print("nightly_history: ±5 % noise alone, 30 nights × 5 draws: nothing found")

    # Other machine classes: never compared.
    path = os.path.join(tmp, "classes.sqlite")
    con = build(path, [1e-3] * 8)
    build(path, [0.5e-3], cls="Intel Xeon AMX", start=100).close()
    r = history.check(con)
    if r["machine_class"] != "Intel Xeon AMX, 2 cores" or \
            [f["verdict"] for f in r["findings"]] != ["not compared"] or \
            "never compared" not in r["findings"][0]["detail"]:
        fail(f"a new class's first night: {r}")
    build(path, [0.5e-3] * 7, cls="Intel Xeon AMX", start=101, seed=2).close()
    build(path, [1e-3], start=200, seed=3).close()  # class A again, as fast as before
    if regressions(history.open_store(path)):
        fail("a night of class A was compared with class B's faster nights")
    print("nightly_history: other classes are not compared:", r["findings"][0]["detail"])

    # Science: 3 seed-sds found, 0.5 not; a changed digest found.
    for shift, want in ((3.0, True), (0.5, False)):
        values = [0.70, 0.72, 0.68, 0.71, 0.69]
        sd = (sum((v - 0.70) ** 2 for v in values) / 4) ** 0.5

        def science(i, shift=shift):
            return [("tpa/grid/sirl", s, v + (shift * sd if i == 9 else 0)) for s, v in enumerate(values)]
        con = build(os.path.join(tmp, f"science{shift}.sqlite"), [1e-3] * 10, science=science)
        got = [f for f in regressions(con) if f["kind"] == "science"]
        if bool(got) != want:
            fail(f"science moved by {shift} sd: {got}")
    print("nightly_history: science moved by 3 seed-sds found, by 0.5 not")
    path = os.path.join(tmp, "digest.sqlite")
    con = history.open_store(path)
    for i, d in enumerate(("aaaa", "aaaa", "bbbb")):
        history.add_night(con, {"label": f"d{i}", "time": f"t{i}", "git_commit": f"c{i}",
                                "host": "h", "cpu_class": "c", "cores": 2}, {BENCH: [1e-3] * 3},
                          digests=[("smoke", "p1", "tpa", d)])
    if [f["kind"] for f in regressions(con)] != ["digest"]:
        fail(f"a changed digest: {history.check(con)['findings']}")

    # The command line: exit codes, JSON, dashboard.
    hist = os.path.join(SRC, "bench", "history.py")
    step = os.path.join(tmp, "step.sqlite")
    p = subprocess.run(["/usr/bin/python3", hist, "check", step, "--json",
                        os.path.join(tmp, "f.json")], capture_output=True, text=True)
    if p.returncode != 1 or "REGRESSION" not in p.stdout:
        fail(f"check of the step history: exit {p.returncode}\n{p.stdout}{p.stderr}")
    if not json.load(open(os.path.join(tmp, "f.json")))["findings"]:
        fail("no findings in the JSON")
    p = subprocess.run(["/usr/bin/python3", hist, "check", os.path.join(tmp, "noise1-30.sqlite")],
                       capture_output=True, text=True)
    if p.returncode != 0 or "no regression" not in p.stdout:
        fail(f"check of a noise history: exit {p.returncode}\n{p.stdout}{p.stderr}")
    junk = os.path.join(tmp, "junk.sqlite")
    open(junk, "w").write("not a database\n" * 100)
    p = subprocess.run(["/usr/bin/python3", hist, "check", junk], capture_output=True, text=True)
    if p.returncode != 2 or p.stderr.count("\n") != 1:
        fail(f"a store that is not one: exit {p.returncode}, {p.stderr!r}")
    out = os.path.join(tmp, "dash")
    p = subprocess.run(["/usr/bin/python3", hist, "dashboard", path.replace("digest", "classes"),
                        "--out", out], capture_output=True, text=True)
    if p.returncode != 0:
        fail(f"dashboard: {p.stderr}")
    page = open(os.path.join(out, "index.html")).read()
    if "Intel Xeon AMX, 2 cores" not in page or "AMD EPYC Zen 5, 2 cores" not in page:
        fail("the dashboard does not name both machine classes")
    p = subprocess.run(["node", os.path.join(SRC, "tests", "dashboard_browser.mjs"),
                        os.path.join(out, "index.html"), "2"],
                       cwd=os.path.join(SRC, "app", "study_web"), capture_output=True, text=True)
    if p.returncode != 0:
        fail(f"the dashboard in chromium: {p.stdout}{p.stderr}")
    print("nightly_history: dashboard:", p.stdout.strip())


def torch_ratio_uses_the_fastest_form():
    """bench/nightly's speed-up takes the fastest form of each PyTorch case (plain, stacked,
    batched) and names it; a suspect fastest form gives no ratio."""
    import importlib.machinery
    import importlib.util
    path = os.path.join(SRC, "bench", "nightly")
    spec = importlib.util.spec_from_loader("nightly", importlib.machinery.SourceFileLoader("nightly", path))
    nightly = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(nightly)
    ours = "BM_SirlStep/in:2037/hidden:1024/threads:1/real_time"
    micro = {ours: {"seconds": 0.010}}
    torch_ = {"sirl_step_jaco": {"ms": 160.0, "cpu_percent": 99, "config": "default"},
              "sirl_step_jaco_stacked": {"ms": 40.0, "cpu_percent": 99, "config": "no-coretype"}}
    row = [r for r in nightly.torch_lines(micro, torch_) if r.startswith("| sirl_step_jaco ")]
    if len(row) != 1 or "| stacked, no-coretype |" not in row[0] or "4.00×" not in row[0]:
        fail(f"the ratio should be 40 ms / 10 ms against the stacked form: {row}")
    torch_["sirl_step_jaco_stacked"]["suspect"] = True
    row = [r for r in nightly.torch_lines(micro, torch_) if r.startswith("| sirl_step_jaco ")]
    if "suspect baseline" not in row[0]:
        fail(f"a suspect fastest form gives no ratio: {row}")
    print("nightly_history: PyTorch ratios against the fastest form:", row[0])


def malformed_nights_are_refused_and_odd_names_drawn():
    """`add` of a night of another shape exits 2 with one line naming the file, and files nothing;
    a benchmark or commit named like TeX ('$\\frac{1}{$') is drawn as written."""
    tmp = tempfile.mkdtemp(prefix="sirl-history-bad-")
    hist = os.path.join(SRC, "bench", "history.py")
    store = os.path.join(tmp, "h.sqlite")
    good = {"date": "d1", "time": "2026-01-01T00:00:01", "git_commit": "$\\frac{1}{$" + "0" * 20,
            "host": "h", "cpu_class": "c", "cores": 2,
            "micro": {"BM_$\\frac{1}{$": {"seconds": 0.01}},
            "pipeline": {"smoke": {"wall_seconds": 10, "metrics": {"fpe $x$": 0.5}}}}
    bad = [[1, 2],                                                     # a list root
           dict(good, micro={"b": {"seconds": "fast"}}),                # a string for a number
           dict(good, micro={"b": {"seconds": float("nan")}}),          # NaN
           dict(good, micro={"b": {"ms": 3}}),                          # no seconds
           dict(good, pipeline={"smoke": {"metrics": {"m": float("nan")}}}),
           dict(good, micro=[1]), dict(good, cores="two")]
    for i, night in enumerate(bad):
        path = os.path.join(tmp, f"bad{i}.json")
        json.dump(night, open(path, "w"))
        p = subprocess.run(["/usr/bin/python3", hist, "add", store, path], capture_output=True,
                           text=True)
        if p.returncode != 2 or p.stderr.count("\n") != 1 or path not in p.stderr \
                or "Traceback" in p.stderr:
            fail(f"malformed night {i}: exit {p.returncode}, {p.stderr!r}")
    con = history.open_store(store)
    if con.execute("SELECT COUNT(*) FROM nights").fetchone()[0] != 0:
        fail("a malformed night was filed")
    con.close()
    for i in range(2):
        night = dict(good, date=f"d{i}", time=f"2026-01-01T00:00:0{i}")
        path = os.path.join(tmp, f"good{i}.json")
        json.dump(night, open(path, "w"))
        p = subprocess.run(["/usr/bin/python3", hist, "add", store, path], capture_output=True,
                           text=True)
        if p.returncode != 0:
            fail(f"a good night was refused: {p.stderr}")
    p = subprocess.run(["/usr/bin/python3", hist, "dashboard", store, "--out",
                        os.path.join(tmp, "dash")], capture_output=True, text=True)
    if p.returncode != 0 or not os.path.exists(os.path.join(tmp, "dash", "index.html")):
        fail(f"dashboard with TeX-like names: exit {p.returncode}, {p.stderr[-500:]}")
    print("nightly_history: 7 malformed nights refused (exit 2, one line), TeX-like names drawn")


if __name__ == "__main__":
    main()
    torch_ratio_uses_the_fastest_form()
    malformed_nights_are_refused_and_odd_names_drawn()
    print("nightly_history: OK")
