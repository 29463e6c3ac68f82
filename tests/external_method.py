#!/usr/bin/python3
"""Bring your own representation, end to end (ctest; Debian's python3 with torch):

- `sirl dataset --profile smoke` writes what `sirl run smoke` trains on: Ξ equal to the results
  file's, seed 0's query sets equal to the results file's (which stores its first seed), every
  seed's sets, the N values and seeds of the FPE/TPA cells, the hyper-parameters the rep records
  state;
- the engine's own SIRL embeddings fed back through `sirl evaluate` give bit-identical FPE and
  TPA cells to SIRL's, and leave every built-in cell bit-identical to the plain run's;
- bad input is one line, exit code 2, nothing written: a missing seed, wrong T, d changing, NaN,
  an integer array, a built-in name, a file changed after a profile named it, an unknown env;
- --envs restricts the method to the environments it has embeddings for;
- --against reuses a finished run's cells and computes only the external method's, giving the
  tables a full evaluate gives; a base of another profile text is refused;
- examples/torch_sirl.py (SIRL in PyTorch) trains on the exported data, `sirl evaluate` scores
  it with figures, and the report compares it with SIRL.
"""
import os
import shutil
import subprocess
import sys
import tempfile

import h5py
import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import sirl_testing  # noqa: E402

SRC = sirl_testing.source_dir()
sys.path.insert(0, os.path.join(SRC, "python"))
import sirl_bench  # noqa: E402

KEYS = ["env", "seed", "N"]
fail = sirl_testing.make_fail("external_method")


def run(*args, expect=0):
    p = sirl_testing.run_sirl(*args, stdin=None)
    if p.returncode != expect:
        fail(f"sirl {' '.join(args)}: exit {p.returncode}, expected {expect}\n{p.stdout}{p.stderr}")
    return p


def check_training_data(d, results):
    train = sirl_bench.datasets(f"{d}/train.h5")
    with sirl_bench.open(results) as r:
        ds, fpe, tpa, rec = r.datasets, r.fpe, r.tpa, r.records
        for env, g in train.items():
            if not np.array_equal(g["inputs"], ds[env]["inputs"]):
                fail(f"{env}: Ξ differs from the run's")
            s0 = g["seeds"]["s0"]
            for q in ("similarity",):
                if not np.array_equal(s0["queries"][q], ds[env]["queries"][q]):
                    fail(f"{env}: seed 0's {q} differs from the run's")
            for q in ("singlepref", "multipref10"):
                for a in ("pairs", "label"):
                    if not np.array_equal(s0["queries"][q][a], ds[env]["queries"][q][a]):
                        fail(f"{env}: seed 0's {q}/{a} differs from the run's")
            if not np.array_equal(s0["queries"]["tpa"]["pairs"], ds[env]["queries"]["tpa"]["pairs"]):
                fail(f"{env}: seed 0's TPA pairs differ")
            seeds = sorted(int(s) for s in g["attrs"]["seeds"])
            if seeds != sorted(fpe[fpe.env == env].seed.unique()):
                fail(f"{env}: seeds {seeds} are not the run's")
            if sorted(k for k in g["seeds"] if k != "attrs") != [f"s{s}" for s in seeds]:
                fail(f"{env}: seed groups {sorted(g['seeds'])}")
            if len(seeds) > 1 and np.array_equal(g["seeds"][f"s{seeds[1]}"]["queries"]["similarity"],
                                                 s0["queries"]["similarity"]):
                fail(f"{env}: seed {seeds[1]} has seed 0's triplets")
            Ns = set(fpe[fpe.env == env].N.dropna()) | set(tpa[tpa.env == env].N.dropna())
            if sorted(int(n) for n in g["attrs"]["evaluate_N"]) != sorted(int(n) for n in Ns):
                fail(f"{env}: evaluate_N {g['attrs']['evaluate_N']} != the cells' N {sorted(Ns)}")
            hyper = rec[(rec.kind == "rep") & (rec.env == env) & (rec.variant == "sirl")]
            # The rep states the hyper-parameters it read (φ's, SIRL's, precision): each as the
            # dataset's full set has it (both typed by the reader, and both as written).
            said = r.record(hyper.key.iloc[0])["hyper"] if not hyper.empty else {}
            full = g["attrs"]["hyper"]
            if not said or any(k not in full or full[k] != v for k, v in said.items()) \
                    or "sirl.epochs" not in said \
                    or not set(said.text.splitlines()) <= set(full.text.splitlines()):
                fail(f"{env}: the rep record's hyper-parameters are not the dataset's")


def sirl_embeddings(results):
    with sirl_bench.open(results) as r:
        rec = r.records
        reps = rec[(rec.kind == "rep") & (rec.variant == "sirl") & (rec.teacher == "")]
        return {(x.env, int(x.seed), int(x.N)): r.embedding(x.key) for x in reps.itertuples()}


def check_mirror(d, plain):
    emb = sirl_embeddings(plain)
    sirl_bench.write_embeddings(f"{d}/mirror.h5", emb)
    run("evaluate", f"{d}/mirror.h5", "--name", "mirror", "--profile", "smoke", "--out",
        f"{d}/mirror-run.h5", "--quiet")
    with sirl_bench.open(f"{d}/mirror-run.h5") as r, sirl_bench.open(plain) as p:
        f, t = r.fpe, r.tpa
        m = f[f.variant == "mirror"].set_index(KEYS).sort_index()
        s = f[f.variant == "sirl"].set_index(KEYS).loc[m.index]
        if len(m) != len(emb) or not (m.fpe.to_numpy() == s.fpe.to_numpy()).all() \
                or not (m.train_mse.to_numpy() == s.train_mse.to_numpy()).all():
            fail("mirror's FPE is not SIRL's bit for bit")
        if not (m.method == "external").all():
            fail("an external cell's method is not 'external'")
        k = KEYS + ["M", "protocol"]  # each TPA protocol's cells (the paper's, linear) apart
        m = t[t.variant == "mirror"].set_index(k).sort_index()
        s = t[(t.variant == "sirl") & t.frozen & t.in_main].set_index(k).loc[m.index]
        if m.empty or not m.frozen.all() or not m.best_mode.all():
            fail("mirror's TPA cells are not frozen best-mode cells")
        for c in ("tpa", "tpa_std", "tpa_train"):
            if not (m[c].to_numpy() == s[c].to_numpy()).all():
                fail(f"mirror's TPA {c} is not SIRL's bit for bit")
        for name in ("fpe", "tpa"):
            a = getattr(r, name)
            a = a[a.variant != "mirror"].reset_index(drop=True)
            b = getattr(p, name).reset_index(drop=True)
            if not a.equals(b):
                fail(f"built-in {name} cells changed when an external method joined")
    return emb


def check_against(d, plain, reuse):
    """--against reuses a finished run's cells: only the external method's tasks run, and the
    file equals the one a full evaluate writes, table for table."""
    p = run("evaluate", f"{d}/mirror.h5", "--name", "mirror", "--profile", "smoke", "--against",
            plain, "--out", f"{d}/against.h5", "--quiet")
    if " of " not in p.stderr or "tasks are" not in p.stderr:
        fail(f"--against did not say what it reused: {p.stderr!r}")
    with sirl_bench.open(f"{d}/against.h5") as a, sirl_bench.open(f"{d}/mirror-run.h5") as f:
        for name in ("fpe", "tpa"):
            if not getattr(a, name).equals(getattr(f, name)):
                fail(f"--against: {name} differs from a full evaluate's")
        if not a.complete:
            fail("--against: the file is not complete")
    # A base of another profile text is refused, nothing written.
    other = f"{d}/other.h5"
    run("run", "smoke", "--set", "seeds=[0]", "--out", other, "--quiet", *reuse)
    p = run("evaluate", f"{d}/mirror.h5", "--name", "mirror", "--profile", "smoke", "--against",
            other, "--out", f"{d}/against2.h5", expect=2)
    if "another profile text" not in p.stderr or os.path.exists(f"{d}/against2.h5"):
        fail(f"--against a file of another profile: {p.stderr!r}")


def check_bad_inputs(d, emb, reuse):
    def variant(name, edit):
        arrays = {}
        for key, z in emb.items():
            z = edit(key, z.copy())
            if z is not None:
                arrays[key] = z
        with h5py.File(f"{d}/{name}.h5", "w") as f:  # raw h5py: the writer refuses some of these
            for (env, seed, N), z in arrays.items():
                f[sirl_bench.embedding_name(env, seed, N)] = z
        return f"{d}/{name}.h5"

    last = sorted(emb)[-1]
    first = sorted(emb)[0]

    def nan(k, z):
        if k == first:
            z[3, 1] = np.nan
        return z

    def outside(name):
        """The embeddings with the last array's values in HDF5 external raw storage: the file's
        digest does not cover them, and such storage may name any file (e.g. /etc/passwd)."""
        path = variant(name, lambda k, z: None if k == last else z)
        z = np.ascontiguousarray(emb[last], dtype=np.float32)
        z.tofile(f"{d}/{name}.raw")
        with h5py.File(path, "a") as f:
            f.create_dataset(sirl_bench.embedding_name(*last), shape=z.shape, dtype=np.float32,
                             external=[(f"{d}/{name}.raw", 0, z.nbytes)])
        return path

    cases = [
        (outside("external"), "outside the file"),
        (variant("missing", lambda k, z: None if k == last else z), "no array"),
        (variant("short", lambda k, z: z[:-1] if k == last else z), "rows;"),
        (variant("nan", nan), "nan at row 3, column 1"),
        (variant("ints", lambda k, z: z.astype(np.int32) if k == last else z), "not a 2-D float32"),
        (variant("width", lambda k, z: z[:, :2] if k == last else z), "has d = 2"),
        (variant("cube", lambda k, z: z[:, :, None] if k == last else z), "3 dimensions"),
    ]
    out = f"{d}/bad.h5"
    for path, words in cases:
        p = run("evaluate", path, "--name", "x", "--profile", "smoke", "--out", out, expect=2)
        lines = p.stderr.strip().splitlines()
        if len(lines) != 1 or words not in lines[0]:
            fail(f"{os.path.basename(path)}: expected one line with {words!r}, got {p.stderr!r}")
        if os.path.exists(out):
            fail(f"{os.path.basename(path)}: wrote {out}")
    for name, words in (("sirl", "built-in"), ("9lives", "starting with a-z"), ("a+b", "only a-z")):
        p = run("evaluate", f"{d}/mirror.h5", "--name", name, "--profile", "smoke", "--out", out,
                expect=2)
        if words not in p.stderr:
            fail(f"--name {name}: {p.stderr!r}")
    p = run("evaluate", f"{d}/mirror.h5", "--name", "x", "--envs", "grid,nowhere", "--profile",
            "smoke", "--out", out, expect=2)
    if "not one of the profile's envs" not in p.stderr:
        fail(f"--envs nowhere: {p.stderr!r}")
    # A profile naming a file by its digest refuses the file once it changed.
    prof = f"{d}/ext.toml"
    with open(os.path.join(SRC, "configs", "smoke.toml")) as fh:
        text = fh.read()
    shutil.copy(f"{d}/mirror.h5", f"{d}/moving.h5")
    digest = sirl_bench_digest(f"{d}/moving.h5")
    with open(prof, "w") as fh:
        fh.write(text + f'\n[external.moving]\nembeddings = "moving.h5"\nxxh3 = "{digest}"\n'
                 'envs = ["grid2"]\n')
    run("run", prof, "--out", f"{d}/moving-run.h5", "--quiet", *reuse)
    with sirl_bench.open(f"{d}/moving-run.h5") as r:
        envs = set(r.fpe[r.fpe.variant == "moving"].env)
        if envs != {"grid2"}:
            fail(f"envs = [\"grid2\"] gave cells in {envs}")
    with h5py.File(f"{d}/moving.h5", "a") as f:
        f.attrs["changed"] = 1
    p = run("run", prof, "--out", f"{d}/moving-run2.h5", "--quiet", expect=1)
    if "the file changed since" not in p.stderr:
        fail(f"a changed embeddings file: {p.stderr!r}")


def sirl_bench_digest(path):
    """XXH3-128 as xxh128sum prints it (the xxhash package setup installs)."""
    out = subprocess.run(["xxh128sum", path], capture_output=True, text=True, check=True).stdout
    return out.split()[0]


def check_torch_example(d, reuse):
    ex = os.path.join(SRC, "examples", "torch_sirl.py")
    p = subprocess.run(["/usr/bin/python3", ex, f"{d}/train.h5", "--out", f"{d}/torch.h5",
                        "--threads", "2"], capture_output=True, text=True)
    if p.returncode != 0:
        fail(f"examples/torch_sirl.py: {p.stderr[-2000:]}")
    run("evaluate", f"{d}/torch.h5", "--name", "torch_sirl", "--profile", "smoke", "--out",
        f"{d}/torch-run.h5", "--figures", f"{d}/figs", "--quiet", *reuse)
    with open(f"{d}/figs/report.md") as fh:
        report = fh.read()
    if "| torch_sirl | FPE" not in report or "| torch_sirl | TPA" not in report:
        fail("the report does not compare torch_sirl with SIRL")
    import json
    with open(f"{d}/figs/figures.json") as fh:
        drawn = json.load(fh)
    if not any("torch_sirl" in panel for env in drawn["fig5"].values() for panel in env.values()):
        fail("Fig. 5 does not draw torch_sirl")


def main():
    d = tempfile.mkdtemp(prefix="sirl-external-")
    try:
        plain = f"{d}/smoke.h5"
        # The smoke fixture's file and a copy of its cache: the runs that check refusals,
        # environments and the report reuse the built-in tasks from that copy (mirror's evaluate
        # computes on an empty cache: it checks the built-in cells against the plain run's).
        # Without the fixture (a run by hand), computed here and no cache shared, as before.
        if sirl_testing.copy_fixture("smoke", plain):
            reuse = ["--cache", plain + ".tasks"]
        else:
            run("run", "smoke", "--out", plain, "--quiet")
            reuse = []
        run("dataset", "--profile", "smoke", "--out", f"{d}/train.h5")
        check_training_data(d, plain)
        emb = check_mirror(d, plain)
        check_against(d, plain, reuse)
        check_bad_inputs(d, emb, reuse)
        check_torch_example(d, reuse)
    finally:
        shutil.rmtree(d, ignore_errors=True)
    print("external_method: OK")


if __name__ == "__main__":
    main()
