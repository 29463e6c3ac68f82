#!/usr/bin/python3
"""Environments from a file (docs/environment-files.md), through the command line as a user runs
them (ctest; Debian's python3):

- the round trip: GridRobot exported by `sirl dataset` and declared from its file (streams =
  "grid") gives every FPE and TPA row of GridRobot's, bit for bit, in the same run;
- an environment written by sirl_bench.write_environment (no C++) runs every method: its tables,
  its /datasets group (@from_file, the points), the figures and the report, whose main claims on
  it are marked beyond the paper; moved elsewhere, the same file is the same environment (every
  task reused from the cache);
- the user study runs on an environment from a file with 2-D points (`--profile` declares it):
  simulate, serve (the page's path view draws the file's points) and analyze; the study records
  the file's digest, so a study is never analysed against another file under the same name (other
  streams are the same Ξ), merge keeps it and refuses studies on two files, and without the
  profile, or on a file with 3-D points, it is one line and exit 2;
- bad files and declarations are one line, exit 2, before anything is written: a wrong digest, a
  missing group, mismatched shapes, NaN, a constant feature, too few trajectories, names missing
  or repeated, a non-HDF5 file, values stored outside the file, a crafted shape of 2^40 values, a
  built-in name, unknown streams; write_environment refuses the same inputs in Python.
"""
import json
import os
import re
import shutil
import signal
import subprocess
import sys
import tempfile
import urllib.request

import h5py
import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import sirl_testing  # noqa: E402

SIRL = sirl_testing.sirl_binary()
SRC = sirl_testing.source_dir()
sys.path.insert(0, os.path.join(SRC, "python"))
import sirl_bench  # noqa: E402

HYPER = '"sirl.epochs" = 20\n"vae.epochs" = 2\n"pref.epochs" = 10\n"tpa.epochs" = 15\n'
GRID = """
seeds = [0, 1]
[queries]
similarity = 200
preference = 200
tpa_pairs = 100
fpe_trajectories = 300
[fpe]
methods = ["sirl", "sirl+vae", "vae", "multipref10", "singlepref", "random"]
N = [100, 200]
[tpa]
methods = ["sirl", "sirl+vae", "vae", "multipref10", "singlepref", "random"]
N = [200]
M = [10, 40]
frozen = "best"
"""


fail = sirl_testing.make_fail("file_environment")


def run(*args, cwd, expect=0):
    p = sirl_testing.run_sirl(*args, cwd=cwd, timeout=900)
    if p.returncode != expect:
        fail(f"sirl {' '.join(args)}: exit {p.returncode}, expected {expect}:\n{p.stderr[-2000:]}")
    return p


def xxh3(path):
    return subprocess.run(["xxh128sum", path], capture_output=True, text=True,
                          check=True).stdout.split()[0]


def declare(name, file, digest, extra=""):
    return f'[environments.{name}]\nfile = "{file}"\nxxh3 = "{digest}"\n{extra}'


def round_trip(tmp):
    run("dataset", "--env", "grid", "--out", "grid.h5", cwd=tmp)
    with open(os.path.join(tmp, "rt.toml"), "w") as f:
        f.write(f'name = "rt"\nenvs = ["grid", "gridfile"]\n{GRID}[hyper.all]\n{HYPER}'
                + declare("gridfile", "grid.h5", xxh3(os.path.join(tmp, "grid.h5")),
                          'dataset = "grid"\nstreams = "grid"\n'))
    run("run", "rt.toml", "--out", "rt.h5", "--quiet", cwd=tmp)
    with sirl_bench.open(os.path.join(tmp, "rt.h5")) as r:
        for name in ("fpe", "tpa"):
            t = r.raw_table(name)
            a = t[t.env == "grid"].drop(columns="env").reset_index(drop=True)
            b = t[t.env == "gridfile"].drop(columns="env").reset_index(drop=True)
            if len(a) == 0 or not a.equals(b):
                fail(f"{name}: GridRobot from its export differs from GridRobot ({len(a)} rows)")
        n = len(r.tables["fpe"]) // 2, len(r.tables["tpa"]) // 2
        if r.datasets["gridfile"]["attrs"]["from_file"] is not True or \
                r.datasets["grid"]["attrs"]["from_file"] is not False:
            fail("@from_file does not tell the file environment from the built-in one")
    print(f"ok: GridRobot declared from its export gives its {n[0]} FPE and {n[1]} TPA rows bit "
          "for bit (streams = \"grid\")")


def synthetic(T=240, seed=3):
    """A toy robot: 8 inputs per trajectory, 3 true features of them, a 2-D path of 5 points."""
    rng = np.random.default_rng(seed)
    x = rng.normal(size=(T, 8))
    phi = np.stack([x[:, 0] + x[:, 1], x[:, 2] ** 2, np.sin(x[:, 3])], axis=1) * [1, 2, 3]
    pts = np.cumsum(x[:, :10 // 2 * 2].reshape(T, 4, 2), axis=1)
    pts = np.concatenate([np.zeros((T, 1, 2)), pts], axis=1)
    return x, phi, pts


def own_environment(tmp):
    x, phi, pts = synthetic()
    digest = sirl_bench.write_environment(os.path.join(tmp, "mine.h5"), x, phi,
                                          names=["reach", "effort", "swing"],
                                          units=["m", "J", ""], points=pts, name="mine")
    if digest != xxh3(os.path.join(tmp, "mine.h5")):
        fail("write_environment's digest is not the file's XXH3-128")
    prof = (f'name = "mine"\nenvs = ["mine"]\n{GRID}[hyper.mine]\n{HYPER}'
            + declare("mine", "mine.h5", digest, 'title = "Toy robot"\n'))
    with open(os.path.join(tmp, "mine.toml"), "w") as f:
        f.write(prof)
    out = run("run", "mine.toml", "--out", "mine-run.h5", "--cache", "cache", cwd=tmp).stderr
    figs = os.path.join(tmp, "figs")
    subprocess.run(["/usr/bin/python3", os.path.join(SRC, "report", "plot_figures.py"),
                    os.path.join(tmp, "mine-run.h5"), "--out", figs], check=True,
                   capture_output=True, stdin=subprocess.DEVNULL, timeout=600)
    with sirl_bench.open(os.path.join(tmp, "mine-run.h5")) as r:
        d = r.datasets["mine"]
        if d["attrs"]["title"] != "Toy robot" or d["attrs"]["from_file"] is not True or \
                d["attrs"]["beyond_paper"] is not True:
            fail(f"/datasets/mine attributes: {d['attrs']}")
        if not np.array_equal(d["points"], pts.astype(np.float32)) or \
                not np.array_equal(d["features_raw"], phi.astype(np.float32)):
            fail("the stored points or true features are not the file's")
        lo, hi = phi.min(axis=0), phi.max(axis=0)
        if not np.allclose(d["features"], (phi - lo) / (hi - lo), atol=1e-6):
            fail("the true features are not normalised over Ξ")
        variants = set(r.tables["tpa"].variant)
        if not {"sirl", "sirl+vae", "vae", "multipref10", "singlepref", "random"} <= variants:
            fail(f"methods missing from TPA: {variants}")
    claims = json.load(open(os.path.join(figs, "claims.json")))
    if not claims or not all(h["env"] == "mine" and h["beyond_paper"] for h in claims):
        fail(f"claims on the file environment not marked beyond the paper: {claims[:2]}")
    report = open(os.path.join(figs, "report.md")).read()
    if "Toy robot (beyond the paper), paper protocol" not in report:
        fail("the report's main claims do not mark the environment beyond the paper")
    os.rename(figs, os.path.join(tmp, "mine-run-figures"))  # where `sirl show` looks
    shown = json.loads(run("show", "mine-run.h5", "--json", cwd=tmp).stdout)
    if not shown["verdicts"] or not all(v["beyond_paper"] for v in shown["verdicts"]):
        fail(f"sirl show does not mark the verdicts beyond the paper: {shown['verdicts']}")
    if "(beyond the paper)" not in run("show", "mine-run.h5", cwd=tmp).stdout:
        fail("sirl show's text does not mark the verdicts beyond the paper")
    # The same bytes in another folder: the same environment, every task from the cache.
    os.mkdir(os.path.join(tmp, "elsewhere"))
    shutil.copy(os.path.join(tmp, "mine.h5"), os.path.join(tmp, "elsewhere", "copy.h5"))
    with open(os.path.join(tmp, "elsewhere", "mine.toml"), "w") as f:
        f.write(prof.replace('file = "mine.h5"', 'file = "copy.h5"'))
    again = run("run", "elsewhere/mine.toml", "--out", "again.h5", "--cache", "cache", cwd=tmp).stderr
    m = re.search(r"(\d+) tasks \((\d+) already done\)", again)
    if not m or m.group(1) != m.group(2):
        fail(f"the copied file recomputed tasks:\n{again[-600:]}")
    print(f"ok: an environment written by write_environment runs every method; figures and report "
          f"({len(claims)} claims, all marked beyond the paper); a copy elsewhere reuses every task")
    return digest, prof


def study_on_file(tmp, digest):
    """The user study on the environment `own_environment` declared in mine.toml."""
    x, phi, pts = synthetic()
    sim = ["study", "simulate", "--env", "mine", "--users", "3", "--similarity", "60",
           "--preference", "20", "--out", "study.h5"]
    said = run(*sim, cwd=tmp, expect=2).stderr
    if "--profile" not in said or "mine" not in said or os.path.exists(os.path.join(tmp, "study.h5")):
        fail(f"a study on an undeclared environment: {said!r}")
    run(*sim, "--profile", "mine.toml", cwd=tmp)
    with h5py.File(os.path.join(tmp, "study.h5"), "r") as f:
        if digest not in f["study"].attrs["env_data"] or f["study"].attrs["trajectories"] != len(x):
            fail(f"the study file does not record the environment file: {dict(f['study'].attrs)}")
    analyze = ["study", "analyze", "study.h5", "--out", "study-out", "--seeds", "2", "--splits",
               "2", "--epochs", "5", "--tpa-epochs", "5"]
    said = run(*analyze, cwd=tmp, expect=2).stderr
    if "--profile" not in said or os.path.exists(os.path.join(tmp, "study-out")):
        fail(f"analyze without the profile that declares the environment: {said!r}")
    # Another file under the same name: never analysed as if it were the study's.
    x2, phi2, pts2 = synthetic(seed=4)
    other = sirl_bench.write_environment(os.path.join(tmp, "other.h5"), x2, phi2,
                                         names=["reach", "effort", "swing"], points=pts2,
                                         name="mine")
    mine = open(os.path.join(tmp, "mine.toml")).read()
    with open(os.path.join(tmp, "other.toml"), "w") as f:
        f.write(mine.replace('file = "mine.h5"', 'file = "other.h5"').replace(digest, other))
    said = run(*analyze, "--profile", "other.toml", cwd=tmp, expect=2).stderr
    if "not the same trajectories" not in said or os.path.exists(os.path.join(tmp, "study-out")):
        fail(f"a study analysed against another file under its environment's name: {said!r}")
    # The same file under other streams is the same Ξ: accepted (the study stores its queries).
    with open(os.path.join(tmp, "streams.toml"), "w") as f:
        f.write(mine.replace('title = "Toy robot"', 'title = "Toy robot"\nstreams = "grid"'))
    run(*[a if a != "study-out" else "study-streams" for a in analyze], "--profile",
        "streams.toml", cwd=tmp)
    run(*analyze, "--profile", "mine.toml", cwd=tmp)
    if not os.path.exists(os.path.join(tmp, "study-out", "study_report.md")):
        fail("analyze wrote no study_report.md")
    # merge: two files on the same environment file stay one analysable study; files on two
    # environment files under one name are not one study.
    run("study", "simulate", "--profile", "mine.toml", "--env", "mine", "--users", "2",
        "--seed", "0", "--out", "second.h5", cwd=tmp)
    with h5py.File(os.path.join(tmp, "second.h5"), "a") as f:  # other participants' ids
        g = f["study"]
        ids = [i.decode() for i in g["participant_ids"][()]]
        for i in ids:
            g.move(f"participants/{i}", f"participants/b{i}")
        del g["participant_ids"]
        g["participant_ids"] = [("b" + i).encode() for i in ids]
    run("study", "merge", "merged.h5", "study.h5", "second.h5", cwd=tmp)
    run("study", "analyze", "merged.h5", "--out", "merged-out", "--seeds", "2", "--splits", "2",
        "--epochs", "5", "--tpa-epochs", "5", "--profile", "mine.toml", cwd=tmp)
    run("study", "simulate", "--profile", "other.toml", "--env", "mine", "--users", "2",
        "--out", "third.h5", cwd=tmp)
    said = run("study", "merge", "mixed.h5", "study.h5", "third.h5", cwd=tmp, expect=2).stderr
    if "not one study" not in said or os.path.exists(os.path.join(tmp, "mixed.h5")):
        fail(f"merge of studies on two environment files: {said!r}")
    # [study] env = the file's name inside `sirl run`: its cache key is the file's bytes, so a
    # profile naming another file under the same name recomputes every study task.
    cohort = ('[study]\nenv = "mine"\nusers = 2\nsimilarity = 40\npreference = 10\nepochs = 5\n'
              'tpa_epochs = 5\nseeds = 2\nsplits = 2\n')
    for name, file, d in (("ms", "mine.h5", digest), ("os", "other.h5", other)):
        with open(os.path.join(tmp, name + ".toml"), "w") as f:
            f.write(f'name = "{name}"\nenvs = ["mine"]\nseeds = [0]\n{cohort}' + declare("mine", file, d))
    first = run("run", "ms.toml", "--out", "ms.h5", "--cache", "scache", cwd=tmp).stderr
    second = run("run", "os.toml", "--out", "os.h5", "--cache", "scache", cwd=tmp).stderr
    m = re.search(r"(\d+) tasks \((\d+) already done\)", second)
    if not m or m.group(2) != "0":
        fail(f"a cohort on another file under the same name reused tasks:\n{second[-600:]}")
    with sirl_bench.open(os.path.join(tmp, "ms.h5")) as r:
        if len(r.tables["study"]) == 0:
            fail(f"sirl run's cohort on the file environment stored no analysis: {list(r.tables)}")
    # The study page serves it as a path view of the file's points.
    srv = subprocess.Popen([SIRL, "study", "serve", "--profile", "mine.toml", "--env", "mine",
                            "--participant", "bob", "--scenario", "reach matters",
                            "--scenario-features", "reach", "--out", "served.h5", "--port", "0"],
                           cwd=tmp, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                           stdin=subprocess.DEVNULL)
    try:
        url = None
        for line in srv.stdout:
            if line.startswith("open: "):
                url = line.split()[1]
                break
        if not url:
            fail(f"sirl study serve printed no URL: {srv.stderr.read()[-800:]}")
        base, query = url.split("/?")
        state = json.load(urllib.request.urlopen(f"{base}/api/state?{query}", timeout=10))
        if state["view"] != "path" or state["features"] != ["reach", "effort", "swing"] or \
                state["title"] != "Toy robot" or state["env"] != "mine":
            fail(f"the study page's state for a file environment: {state}")
        row = state["next"]["trajectories"][0]
        t = json.load(urllib.request.urlopen(f"{base}/api/trajectory?{query}&id={row}", timeout=10))
        if not np.allclose(np.array(t["points"]), pts[row], atol=1e-5):
            fail(f"trajectory {row} is not drawn from the file's points: {t['points']}")
    finally:
        srv.send_signal(signal.SIGTERM)
        srv.wait(timeout=30)
    said = run("study", "serve", "--env", "mine", "--participant", "bob", "--scenario", "x",
               "--out", "served.h5", "--port", "0", cwd=tmp, expect=2).stderr
    if "--profile" not in said:
        fail(f"serve resumed without the profile that declares its environment: {said!r}")
    # A file with 3-D points: the study page has no view for it, said before anything is written.
    arm = sirl_bench.write_environment(os.path.join(tmp, "arm3.h5"), x, phi,
                                       names=["reach", "effort", "swing"],
                                       points=np.concatenate([pts, pts[:, :, :1]], axis=2),
                                       name="arm3")
    with open(os.path.join(tmp, "arm.toml"), "w") as f:
        f.write(mine.replace("mine", "arm3").replace(digest, arm))
    said = run("study", "simulate", "--profile", "arm.toml", "--env", "arm3", "--out", "arm-study.h5",
               cwd=tmp, expect=2).stderr
    if "2-D points" not in said or os.path.exists(os.path.join(tmp, "arm-study.h5")):
        fail(f"a study on a file environment with 3-D points: {said!r}")
    print("ok: the user study on a file environment: simulate, serve (path view of the file's "
          "points), analyze; refused without its profile, against another file, with 3-D points")


def bad_files(tmp, prof):
    x, phi, pts = synthetic()

    def env_file(name, **kw):
        path = os.path.join(tmp, name)
        with h5py.File(path, "w") as f:
            g = f.create_group("datasets/mine")
            g.create_dataset("inputs", data=kw.get("inputs", x.astype(np.float32)))
            d = g.create_dataset("features_raw", data=kw.get("features", phi.astype(np.float32)))
            if kw.get("names", True) is not None:
                d.attrs["feature_names"] = kw.get("names", ["a", "b", "c"])
            if "points" in kw:
                g.create_dataset("points", data=kw["points"])
        return path

    nan = phi.copy()
    nan[7, 1] = np.nan
    const = phi.copy()
    const[:, 2] = 4.0
    cases = {
        "shapes": (env_file("shapes.h5", features=phi[:-1].astype(np.float32)), "rows"),
        "nan": (env_file("nan.h5", features=nan.astype(np.float32)), "non-finite value"),
        "constant": (env_file("const.h5", features=const.astype(np.float32)),
                     "could not tell any two apart"),
        "too few": (env_file("few.h5", inputs=x[:2].astype(np.float32),
                             features=phi[:2].astype(np.float32)), "at least 3"),
        "no names": (env_file("nonames.h5", names=None), "no @feature_names"),
        "names twice": (env_file("twice.h5", names=["a", "b", "a"]), "appears twice"),
        "names count": (env_file("count.h5", names=["a", "b"]), "2 names for 3 columns"),
        "points": (env_file("points.h5", points=np.zeros((len(x), 4, 5), np.float32)),
                   "points are [T, L, 2 or 3]"),
    }
    garbage = os.path.join(tmp, "garbage.h5")
    with open(garbage, "wb") as f:
        f.write(b"\x89HDF\r\n\x1a\n" + bytes(range(256)) * 64)
    cases["not HDF5"] = (garbage, garbage)
    outside = os.path.join(tmp, "outside.h5")
    raw = os.path.join(tmp, "values.bin")
    x.astype(np.float32).tofile(raw)
    with h5py.File(outside, "w") as f:
        g = f.create_group("datasets/mine")
        g.create_dataset("inputs", shape=x.shape, dtype=np.float32,
                         external=[(raw, 0, x.astype(np.float32).nbytes)])
        d = g.create_dataset("features_raw", data=phi.astype(np.float32))
        d.attrs["feature_names"] = ["a", "b", "c"]
    cases["stored outside"] = (outside, "outside the file")
    huge = os.path.join(tmp, "huge.h5")
    with h5py.File(huge, "w") as f:  # 2^40 values declared, none written: a few KiB on disk
        g = f.create_group("datasets/mine")
        g.create_dataset("inputs", shape=(1 << 22, 1 << 18), dtype=np.float32, chunks=(1, 1024))
        d = g.create_dataset("features_raw", shape=(1 << 22, 3), dtype=np.float32)
        d.attrs["feature_names"] = ["a", "b", "c"]
    cases["crafted shape"] = (huge, "at most")
    mine_digest = xxh3(os.path.join(tmp, "mine.h5"))
    for what, (path, says) in cases.items():
        text = prof.replace('file = "mine.h5"', f'file = "{os.path.basename(path)}"').replace(
            mine_digest, xxh3(path))
        p = os.path.join(tmp, "bad.toml")
        with open(p, "w") as f:
            f.write(text)
        err = run("run", "bad.toml", "--out", "bad.h5", cwd=tmp, expect=2).stderr.strip()
        if "\n" in err or says not in err or os.path.exists(os.path.join(tmp, "bad.h5")):
            fail(f"{what}: not one line saying {says!r}, or something was written: {err}")
    declarations = {
        "wrong digest": (prof.replace(mine_digest, "0" * 32), "not the 0000"),
        "no group": (prof.replace('title = "Toy robot"', 'dataset = "other"'), "no group"),
        "built-in name": (prof.replace("[environments.mine]", "[environments.grid]"),
                          "built-in environment"),
        "unknown streams": (prof.replace('title = "Toy robot"', 'streams = "nowhere"'),
                            "unknown environment 'nowhere'"),
        "unknown key": (prof.replace('title = "Toy robot"', 'colour = "red"'), "colour"),
        "a section's name": (prof.replace("[environments.mine]", "[environments.fpe]")
                             .replace('envs = ["mine"]', 'envs = ["fpe"]'), "profile section"),
    }
    for what, (text, says) in declarations.items():
        with open(os.path.join(tmp, "bad.toml"), "w") as f:
            f.write(text)
        err = run("plan", "bad.toml", cwd=tmp, expect=2).stderr.strip()
        if "\n" in err or says not in err:
            fail(f"{what}: not one line saying {says!r}: {err}")
    refused = 0
    for kw, says in ((dict(features=nan), "NaN"), (dict(features=const), "same for every"),
                     (dict(names=["a", "a", "b"]), "distinct names"),
                     (dict(points=np.zeros((3, 2, 2))), "points")):
        args = dict(inputs=x, features=phi, names=["a", "b", "c"])
        args.update(kw)
        try:
            sirl_bench.write_environment(os.path.join(tmp, "py.h5"), **args)
        except sirl_bench.ResultsError as e:
            refused += says in str(e)
    if refused != 4:
        fail(f"write_environment refused {refused} of 4 bad inputs with the reason")
    print(f"ok: {len(cases)} bad files and {len(declarations)} bad declarations refused in one "
          "line (exit 2, nothing written); write_environment refuses bad inputs")


def main():
    with tempfile.TemporaryDirectory() as tmp:
        round_trip(tmp)
        digest, prof = own_environment(tmp)
        study_on_file(tmp, digest)
        bad_files(tmp, prof)
    print("file_environment: OK")


if __name__ == "__main__":
    main()
