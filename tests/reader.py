#!/usr/bin/python3
"""The Python reader (python/sirl_bench) against the raw file (ctest; Debian's python3):

- every /tables/* through sirl_bench equals the raw h5py read, column by column: strings equal
  the decoded bytes, flags are booleans equal to the stored 0/1, N and M are <NA> exactly where
  the stored value is 0 and equal elsewhere, every other number is bit-identical;
- the learning curves: each TPA cell's rows are its heads' stored curves up to each head's stop
  (the number of rows is the sum of head_epochs), and every row carries its record's fields;
- records carry the fields the tables do (no key is taken apart anywhere);
- the TPA protocols and references (issue 56): `protocol` is str ("paper" or "linear"),
  `reference` a boolean flag; the references (truth, raw) have no N; every linear cell is frozen,
  best mode and in the main grid, never in the ablation;
- the schema-1 fixture (engine 0.1.0) opens, with protocol "paper" and reference False filled in
  where the file has no such column; a dataset file, a file of a future schema version and a
  non-HDF5 file are refused with one line naming the file;
- /methods (issue 59): every variant of the tables has its row, and the built-in methods'
  rows are what tests/declared_methods.py says (the fixture the report tests use without a
  file);
- the README's one-liner works;
- examples/analysis.py runs on the smoke file.
"""
import os
import shutil
import subprocess
import sys
import tempfile

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import sirl_testing  # noqa: E402
from results_frame import reframe  # noqa: E402

import h5py
import numpy as np

SIRL = sirl_testing.sirl_binary()
SRC = sirl_testing.source_dir()
sys.path.insert(0, os.path.join(SRC, "python"))
import sirl_bench  # noqa: E402

FLAGS = set(sirl_bench.FLAG_COLUMNS)
fail = sirl_testing.make_fail("reader")


def check_tables(path):
    r = sirl_bench.open(path)
    with h5py.File(path, "r") as f:
        names = sorted(f["tables"].keys())
        if sorted(r.tables) != names:
            fail(f"tables {sorted(r.tables)} != {names}")
        for name in names:
            raw = f["tables/" + name][:]
            t = r.tables[name]
            if list(t.columns) != list(raw.dtype.names) or len(t) != len(raw):
                fail(f"{name}: columns or length differ")
            for c in raw.dtype.names:
                a, b = raw[c], t[c]
                if raw.dtype[c].kind == "S":
                    if b.dtype != object or list(b) != [x.decode() for x in a]:
                        fail(f"{name}.{c}: strings differ")
                    if len(b) and not isinstance(b.iloc[0], str):
                        fail(f"{name}.{c}: not str")
                elif c in FLAGS:
                    if str(b.dtype) != "boolean":
                        fail(f"{name}.{c}: dtype {b.dtype}, expected boolean")
                    known = ~b.isna().to_numpy()
                    if not np.array_equal(b[known].to_numpy(dtype=bool), a[known] != 0):
                        fail(f"{name}.{c}: flags differ")
                    # <NA> only for frozen where a training has no M (not a TPA cell)
                    if (~known).any() and not (c == "frozen" and (raw["M"][~known] == 0).all()):
                        fail(f"{name}.{c}: <NA> where the row has the field")
                elif c in ("N", "M"):
                    if str(b.dtype) != "Int64":
                        fail(f"{name}.{c}: dtype {b.dtype}, expected Int64")
                    na = b.isna().to_numpy()
                    if not np.array_equal(na, a == 0):
                        fail(f"{name}.{c}: <NA> not exactly where the stored value is 0")
                    if not np.array_equal(b[~na].to_numpy(dtype=np.int64), a[~na]):
                        fail(f"{name}.{c}: values differ")
                elif c == "seed":
                    na = b.isna().to_numpy()
                    if not np.array_equal(na, a < 0) or \
                            not np.array_equal(b[~na].to_numpy(dtype=np.int64), a[~na]):
                        fail(f"{name}.seed: differs")
                elif c == "dead_fraction":
                    x = b.to_numpy()
                    if not np.array_equal(np.isnan(x), a < 0) or \
                            not np.array_equal(x[a >= 0], a[a >= 0]):
                        fail(f"{name}.dead_fraction: differs")
                else:
                    if b.dtype != a.dtype:
                        fail(f"{name}.{c}: dtype {b.dtype} != stored {a.dtype}")
                    if a.tobytes() != b.to_numpy().tobytes():
                        fail(f"{name}.{c}: values differ")
    print(f"ok: {len(names)} tables equal the raw read, column by column")
    return r


def check_curves(r, path):
    recs = r.records
    if recs.key.tolist() != r.keys():
        fail("records are not the file's tasks in order")
    tpa = recs[recs.kind == "tpa"].head(12)
    c = r.curves_of(tpa)
    with h5py.File(path, "r") as f:
        for row in tpa.itertuples():
            g = f["runs/" + row.key]
            L, E = g["loss_curves"][:], g["head_epochs"][:]
            mine = c[c.key == row.key]
            if len(mine) != int(E.sum()):
                fail(f"{row.key}: {len(mine)} curve rows, expected {int(E.sum())}")
            for h in range(L.shape[0]):
                got = mine[mine["head"] == h].sort_values("epoch").loss.to_numpy()
                if not np.array_equal(got, L[h, :int(E[h])].astype(float)):
                    fail(f"{row.key} head {h}: curve differs")
            for fld in ("env", "variant", "method", "seed", "M", "frozen", "best_mode"):
                if (mine[fld] != getattr(row, fld)).any():
                    fail(f"{row.key}: curve rows' {fld} differs from the record's")
            env = g.attrs["env"]
            if (env.decode() if isinstance(env, bytes) else env) != row.env:
                fail(f"{row.key}: record env differs")
    # A 1-D curve (φ, VAE): head is <NA>, epochs 1..E
    rep = recs[recs.kind == "rep"].head(1)
    cr = r.curves_of(rep)
    if not cr["head"].isna().all() or cr.epoch.tolist() != list(range(1, len(cr) + 1)):
        fail("a φ's curve: head must be <NA> and epochs 1..E")
    print(f"ok: curves of {len(tpa)} TPA cells equal their stored heads up to each stop")


def check_protocols(r):
    """The columns of issue 56 as the reader types them, on a file that has them."""
    fpe, tpa = r.tables["fpe"], r.tables["tpa"]
    for name, t in (("fpe", fpe), ("tpa", tpa)):
        if str(t.reference.dtype) != "boolean":
            fail(f"{name}.reference: dtype {t.reference.dtype}, expected boolean")
        refs = t[t.reference]
        if refs.empty:
            fail(f"{name}: no reference rows (truth, raw)")
        if not refs.N.isna().all() or (refs.method != refs.variant).any() or \
                not set(refs.variant) <= {"truth", "raw"}:
            fail(f"{name}: a reference row with an N, or not truth / raw: {refs.head()}")
        if t[~t.reference].variant.isin(["truth", "raw"]).any():
            fail(f"{name}: truth or raw rows not marked reference")
    if tpa.protocol.dtype != object or not all(isinstance(x, str) for x in tpa.protocol):
        fail(f"tpa.protocol: not str ({tpa.protocol.dtype})")
    if not set(tpa.protocol) <= set(sirl_bench.PROTOCOLS):
        fail(f"tpa.protocol: {set(tpa.protocol)}")
    lin = tpa[tpa.protocol == "linear"]
    if len(lin) and not (lin.frozen.all() and lin.best_mode.all() and lin.in_main.all()
                         and not lin.in_ablation.any()):
        fail("a linear-protocol cell that is not frozen, best mode and in the main grid only")
    if (tpa[tpa.protocol == "paper"].variant == "raw").any():
        fail("raw has paper-protocol TPA cells")
    print(f"ok: protocol (str: {sorted(set(tpa.protocol))}) and reference (boolean; "
          f"{sorted(set(tpa[tpa.reference].variant))}, N <NA>) in /tables/tpa and fpe")


def check_methods(r):
    sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
    import declared_methods
    m = r.methods
    variants = set(r.tables["fpe"].variant) | set(r.tables["tpa"].variant)
    if not variants <= set(m.index):
        fail(f"/methods lacks {sorted(variants - set(m.index))}")
    want = declared_methods.Declared.methods
    shared = sorted(set(want.index) & set(m.index))
    for v in shared:
        for c in want.columns:
            # Positions in the catalog and the figures move when a method is added: their order
            # (and whether a variant is drawn at all) is checked below.
            if c in ("selection_order", "catalog_order", "figure_order"):
                continue
            if m.at[v, c] != want.at[v, c]:
                fail(f"/methods/{v} {c} is {m.at[v, c]!r}, the fixture says {want.at[v, c]!r}")
    by_file = sorted(shared, key=lambda v: (m.at[v, "catalog_order"], v))
    by_fixture = sorted(shared, key=lambda v: (want.at[v, "catalog_order"], v))
    if by_file != by_fixture:
        fail(f"/methods catalog order {by_file}, the fixture's {by_fixture}")
    drawn = [v for v in shared if m.at[v, "figure_order"] >= 0]
    if drawn != [v for v in shared if want.at[v, "figure_order"] >= 0]:
        fail(f"/methods: the variants Figs. 4-5 draw are {drawn}, the fixture's differ")
    if sorted(drawn, key=lambda v: m.at[v, "figure_order"]) != \
            sorted(drawn, key=lambda v: want.at[v, "figure_order"]):
        fail("/methods: the figures' order of the drawn variants is not the fixture's")
    if not {"sirl", "vae", "random", "truth", "raw"} <= set(m.index):
        fail(f"smoke's /methods: {sorted(m.index)}")
    print(f"ok: /methods declares the file's {len(m)} variants as the fixture does")


def check_refusals(smoke, tmp):
    v1 = sirl_bench.open(sirl_testing.data_path("results_v1.h5"))
    if v1.schema_version != 1 or len(v1.tables["tpa"]) != 1 or len(v1.records) != 5:
        fail("the schema-1 fixture does not open as written")
    t1, f1 = v1.tables["tpa"], v1.tables["fpe"]
    if list(t1.protocol) != ["paper"] or str(t1.reference.dtype) != "boolean" or \
            t1.reference.any() or f1.reference.any() or "protocol" in f1 or \
            "protocol" in v1.raw_table("tpa"):
        fail("the schema-1 fixture: protocol 'paper' / reference False not filled in (or stored)")
    v1.curves  # noqa: B018 (reads every curve)
    future = os.path.join(tmp, "future.h5")
    shutil.copy(smoke, future)
    with h5py.File(future, "r+") as f:
        f.attrs["schema_version"] = 99
    reframe(future)  # as a future engine would have written it: its checksums hold
    text = os.path.join(tmp, "notes.h5")
    open(text, "w").write("not hdf5\n")
    ds = os.path.join(tmp, "ds.h5")
    subprocess.run([SIRL, "dataset", "--env", "grid", "--out", ds], check=True,
                   stdout=subprocess.DEVNULL)
    for path, want in ((future, "schema version 99"), (text, "not an HDF5 file"),
                       (ds, "a dataset file")):
        try:
            sirl_bench.open(path)
        except sirl_bench.ResultsError as e:
            msg = str(e)
            if path not in msg or want not in msg or "\n" in msg:
                fail(f"refusal of {path}: {msg!r}")
        else:
            fail(f"{path} was not refused")
    print("ok: v1 fixture opens; a future schema, a dataset file and a text file are refused by name")


def main():
    with tempfile.TemporaryDirectory() as tmp:
        smoke = os.path.join(tmp, "smoke.h5")
        if not sirl_testing.copy_fixture("smoke", smoke, with_cache=False):
            subprocess.run([SIRL, "run", "smoke", "--out", smoke, "--threads", "2"], check=True,
                           stdout=subprocess.DEVNULL)
        r = check_tables(smoke)
        prov = r.provenance
        libs = prov.get("libraries", "")
        for name in ("compiler", "eigen", "libxsmm", "onednn", "cholmod", "mujoco", "hdf5",
                     "onetbb", "xxhash"):
            if f"{name} " not in libs or not r.libraries.get(name):
                fail(f"provenance lacks {name}'s version: {libs!r} / {r.libraries}")
        paths = prov.get("kernel_paths", "")
        if not paths.startswith("build ") or "; gemm " not in paths or "; bf16 " not in paths:
            fail(f"provenance: kernel_paths {paths!r}")
        if f"build {paths.split(';')[0].split()[1]}" not in prov.get("cpu_class", ""):
            fail(f"cpu_class {prov.get('cpu_class')!r} does not name the build of {paths!r}")
        if prov.get("schema_version") != 3 or not prov.get("cpu_class"):
            fail(f"provenance: {prov}")
        print(f"ok: provenance names the libraries: {libs}")
        check_curves(r, smoke)
        check_protocols(r)
        check_methods(r)
        check_refusals(smoke, tmp)
        p = subprocess.run(["/usr/bin/python3", "-c",
                            f"import sirl_bench as s; t = s.open({smoke!r}).tables['tpa']; "
                            "assert isinstance(t.env.iloc[0], str)"],
                           env=dict(os.environ, PYTHONPATH=os.path.join(SRC, "python")))
        if p.returncode:
            fail("README's one-liner")
        ex = subprocess.run(["/usr/bin/python3", os.path.join(SRC, "examples", "analysis.py"),
                             smoke, smoke, "--out", os.path.join(tmp, "ex.png")],
                            capture_output=True, text=True)
        if ex.returncode or not os.path.exists(os.path.join(tmp, "ex.png")):
            fail(f"examples/analysis.py: {ex.stderr[-2000:]}")
        print("ok: the README's one-liner and examples/analysis.py")
    print("reader: OK")


if __name__ == "__main__":
    main()
