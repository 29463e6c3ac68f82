#!/usr/bin/python3
"""The reader's typed attributes, embedding keys and on-demand /datasets (ctest; Debian's python3):

- every attribute under /datasets and at the root of the smoke files (`sirl run smoke`, `sirl
  dataset --profile smoke`) is declared in sirl_bench.ATTRIBUTE_TYPES and read as its type,
  equal to the raw h5py value; @seeds and @evaluate_N are the profile's (configs/smoke.toml as
  `sirl plan smoke --resolved` gives it) as ints, @in_claims / @vae_weak_claim / @fig3_rank are
  the environments' registrations (datasets/environments.{h,cpp}), @query_seed is the seed `sirl
  inspect` prints, @hyper is a dict whose keys and types are the engine's (`sirl plan --set`
  names them) and whose values are the profile's or the engine's defaults (engine/hyperparams.h);
- embedding_keys lists each environment's seeds × N of the profile with its HDF5 path, and
  embeddings written for exactly those keys are what `sirl evaluate` takes (one fewer: refused);
- reading attributes reads no array (h5py's Dataset reads counted); an array is read on first
  access, then kept, and equals the raw read; a group outlives the mapping it came from; reading
  after close is one line;
- a malformed attribute (@seeds = ["x"], @in_claims = 2, a bad @hyper line, a text
  @schema_version in a re-framed results file) is a ResultsError of one line naming the file.
"""
import gc
import os
import re
import shutil
import subprocess
import sys
import tempfile
import tomllib

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import sirl_testing  # noqa: E402
from results_frame import reframe  # noqa: E402

import h5py  # noqa: E402
import numpy as np  # noqa: E402

SRC = sirl_testing.source_dir()
sys.path.insert(0, os.path.join(SRC, "python"))
import sirl_bench  # noqa: E402
from sirl_bench import attributes as A  # noqa: E402

PY_TYPE = {"an integer": A.INT, "a number": A.FLOAT, "true or false": A.FLAG,
           "an array of integers": A.INTS, "a string": A.TEXT}


fail = sirl_testing.make_fail("reader_typed")


def sirl(*args, expect=0):
    p = sirl_testing.run_sirl(*args)
    if p.returncode != expect:
        fail(f"sirl {' '.join(args)}: exit {p.returncode}, expected {expect}\n{p.stdout}{p.stderr}")
    return p


# --- what the profile and the engine's sources say -------------------------------------------

def profile():
    return tomllib.loads(sirl("plan", "smoke", "--resolved").stdout)


def expected_axes(prof):
    """{env: (seeds, evaluate_N)} as `sirl dataset --profile` derives them: the environment's
    table overrides the profile's seeds and FPE/TPA N; evaluate_N is their union, ascending."""
    out = {}
    for env in prof["envs"]:
        t = prof.get(env, {})
        seeds = t.get("seeds", prof["seeds"])
        Ns = set(t.get("fpe_N", prof["fpe"]["N"])) | set(t.get("tpa_N", prof["tpa"]["N"]))
        if seeds:
            out[env] = (list(seeds), sorted(Ns))
    return out


def registrations():
    """{env: {in_claims, fig3_rank, vae_weak_claim}} from datasets/environments.{h,cpp}: the
    EnvSpec defaults, then built_in()'s statements in order (`b = a;` copies a spec)."""
    h = open(os.path.join(SRC, "datasets", "environments.h")).read()
    cpp = open(os.path.join(SRC, "datasets", "environments.cpp")).read()
    fields = ("in_claims", "fig3_rank", "vae_weak_claim")
    default = {}
    for f in fields:
        m = re.search(rf"\b(?:bool|int)\s+{f}\s*=\s*(\w+);", h)
        if not m:
            fail(f"datasets/environments.h: no default for {f}")
        default[f] = m.group(1)
    body = cpp[cpp.index("std::vector<EnvSpec> built_in() {"):]
    specs, names = {}, {}
    for stmt in re.finditer(r"EnvSpec& (\w+) = all\[\d+\];|(\w+) = (\w+);|(\w+)\.(\w+) = ([^;]+);",
                            body):
        if stmt.group(1):
            specs[stmt.group(1)] = dict(default)
        elif stmt.group(2) and stmt.group(2) in specs and stmt.group(3) in specs:
            specs[stmt.group(2)] = dict(specs[stmt.group(3)])
        elif stmt.group(4) in specs:
            var, f, v = stmt.group(4), stmt.group(5), stmt.group(6).strip()
            if f in fields:
                specs[var][f] = v
            elif f == "name":
                names[var] = v.strip('"')

    def value(v):
        return v == "true" if v in ("true", "false") else int(v)
    return {names[v]: {f: value(x) for f, x in s.items()} for v, s in specs.items() if v in names}


def default_widths(env):
    """phi.hidden before a profile changes it: the environment's HyperDefault list, else the
    engine's default (engine/hyperparams.h)."""
    cpp = open(os.path.join(SRC, "datasets", "environments.cpp")).read()
    m = re.search(rf"\b{env}\.hyper = \{{\{{\"phi\.hidden\", std::vector<int>\{{([\d, ]+)\}}", cpp)
    if not m:
        m = re.search(r"std::vector<int> phi_hidden\{([\d, ]+)\};",
                      open(os.path.join(SRC, "engine", "hyperparams.h")).read())
    return [int(x) for x in m.group(1).split(",")]


def engine_hyper_types():
    """{key: type} as the engine states them: its known keys (an unknown key's error lists them)
    and each key's kind (a TOML table is of no kind, and the error says which it must be)."""
    err = sirl("plan", "smoke", "--set", 'hyper.grid."no.such.key"=1', expect=2).stderr
    m = re.search(r"\(known: ([^)]*)\)", err)
    if not m:
        fail(f"no list of known hyper-parameters in: {err!r}")
    out = {}
    for key in m.group(1).split(", "):
        err = sirl("plan", "smoke", "--set", f'hyper.grid."{key}"={{}}', expect=2).stderr
        kind = re.search(rf"{re.escape(key)} must be (an integer|a number|true or false|"
                         r"an array of integers|a string)", err)
        if not kind:
            fail(f"no type for {key} in: {err!r}")
        out[key] = PY_TYPE[kind.group(1)]
    return out


# --- typed against raw --------------------------------------------------------------------------

def raw_as(t, raw):
    """A raw h5py attribute as the declared type t would read it, computed here independently."""
    def text(x):
        return x.decode() if isinstance(x, bytes) else str(x)
    if t == A.TEXT:
        return text(raw)
    if t == A.TEXTS:
        return [text(x) for x in raw]
    if t == A.INT:
        return int(raw)
    if t == A.INTS:
        return [int(text(x)) for x in raw]
    if t == A.FLOAT:
        return float(text(raw) if isinstance(raw, (str, bytes)) else raw)
    if t == A.FLAG:
        if int(raw) not in (0, 1):
            fail(f"flag {raw!r}")
        return bool(int(raw))
    if t == A.SEED:
        return int(raw) % (1 << 64)
    if t == A.HYPER:
        return dict(line.split(" = ", 1) for line in text(raw).splitlines() if line)
    fail(f"type {t}")


def check_value(t, got, want, where):
    kind = {A.TEXT: str, A.TEXTS: list, A.INT: int, A.INTS: list, A.FLOAT: float, A.FLAG: bool,
            A.SEED: int, A.HYPER: dict}[t]
    if type(got) is not kind and not (t == A.HYPER and isinstance(got, sirl_bench.Hyper)):
        fail(f"{where}: {type(got).__name__}, expected {kind.__name__} ({got!r})")
    if t == A.HYPER:
        if list(got) != list(want) or got.text.splitlines() != [f"{k} = {v}" for k, v in want.items()]:
            fail(f"{where}: keys or text differ from the stored lines")
        return
    if t in (A.TEXTS, A.INTS) and any(type(x) is not (int if t == A.INTS else str) for x in got):
        fail(f"{where}: an element is not {'int' if t == A.INTS else 'str'}: {got!r}")
    if t == A.FLOAT and np.isnan(want):
        if not np.isnan(got):
            fail(f"{where}: {got!r}, stored NaN")
    elif got != want:
        fail(f"{where}: {got!r}, stored {want!r}")


def check_typed_tree(path, typed_envs):
    """Every attribute of /datasets/* and of the root, through the reader and raw."""
    n = 0
    with h5py.File(path, "r") as f:
        prov = typed_envs.provenance
        for k, raw in f.attrs.items():
            t = A.ATTRIBUTE_TYPES["provenance"].get(k)
            if t is None:
                fail(f"{path}: root attribute @{k} is not declared in ATTRIBUTE_TYPES['provenance']")
            check_value(t, prov[k], raw_as(t, raw), f"{path}: /@{k}")
            n += 1

        def walk(g, mine):
            nonlocal n
            for k, raw in g.attrs.items():
                t = A.ATTRIBUTE_TYPES["datasets"].get(k)
                if t is None:
                    fail(f"{path}: {g.name}@{k} is not declared in ATTRIBUTE_TYPES['datasets']")
                check_value(t, mine["attrs"][k], raw_as(t, raw), f"{path}: {g.name}@{k}")
                n += 1
            for name, o in g.items():
                if isinstance(o, h5py.Group):
                    walk(o, mine[name])
                    continue
                for k, raw in o.attrs.items():
                    t = A.ATTRIBUTE_TYPES["datasets"].get(k)
                    if t is None:
                        fail(f"{path}: {o.name}@{k} is not declared")
                    check_value(t, mine["attrs"][f"{name}.{k}"], raw_as(t, raw), f"{o.name}@{k}")
                    n += 1
        for env in f["datasets"]:
            walk(f["datasets"][env], typed_envs[env])
    return n


def check_dataset_file(ds, prof):
    d = sirl_bench.datasets(ds)
    n = check_typed_tree(ds, d)
    axes, regs = expected_axes(prof), registrations()
    if sorted(d) != sorted(axes):
        fail(f"{ds}: environments {sorted(d)}, the profile's with seeds {sorted(axes)}")
    types = engine_hyper_types()
    if types != sirl_bench.HYPER_TYPES:
        diff = {k for k in set(types) | set(sirl_bench.HYPER_TYPES)
                if types.get(k) != sirl_bench.HYPER_TYPES.get(k)}
        fail(f"HYPER_TYPES differ from the engine's on {sorted(diff)}")
    py = {A.INT: int, A.FLOAT: float, A.FLAG: bool, A.INTS: list, A.TEXT: str}
    for env, (seeds, Ns) in axes.items():
        a = d[env]["attrs"]
        if a["seeds"] != seeds or a["evaluate_N"] != Ns:
            fail(f"{env}: seeds {a['seeds']!r}, evaluate_N {a['evaluate_N']!r}; the profile's: "
                 f"{seeds}, {Ns}")
        for k in ("in_claims", "fig3_rank", "vae_weak_claim"):
            if a[k] != regs[env][k] or type(a[k]) is not type(regs[env][k]):
                fail(f"{env}: @{k} is {a[k]!r}, its registration says {regs[env][k]!r}")
        beta = float(prof.get("teacher", {}).get("beta", "inf"))
        if a["teacher_beta"] != beta:
            fail(f"{env}: teacher_beta {a['teacher_beta']!r}, the profile's {beta!r}")
        inspected = sirl("inspect", ds, "--env", env).stdout
        if f"seed {a['query_seed']})" not in inspected.splitlines()[0]:
            fail(f"{env}: query_seed {a['query_seed']} is not what sirl inspect prints: "
                 f"{inspected.splitlines()[0]!r}")
        want_T = prof.get(env, {}).get("trajectories")
        if want_T is not None and a["trajectories"] != want_T:
            fail(f"{env}: trajectories {a['trajectories']}, the profile's {want_T}")
        h = a["hyper"]
        if list(h) != list(types):
            fail(f"{env}: @hyper keys {list(h)} are not the engine's {list(types)}")
        for key, value in h.items():
            if type(value) is not py[types[key]] or \
                    (types[key] == A.INTS and not all(type(w) is int for w in value)):
                fail(f"{env}: hyper {key} = {value!r} is not {types[key]}")
        set_here = prof.get("hyper", {}).get(env, {})
        for key, value in set_here.items():
            if h[key] != value or type(h[key]) is not type(value):
                fail(f"{env}: hyper {key} = {h[key]!r}, the profile sets {value!r}")
        widths = set_here.get("phi.hidden", default_widths(env))
        if h["phi.hidden"] != widths:
            fail(f"{env}: phi.hidden {h['phi.hidden']!r}, expected {widths}")
        for s in seeds:
            sa = d[env]["seeds"][f"s{s}"]["attrs"]
            if sa["seed"] != s or type(sa["seed"]) is not int or type(sa["query_seed"]) is not int:
                fail(f"{env}/seeds/s{s}: seed {sa['seed']!r}, query_seed {sa['query_seed']!r}")
    if d["grid"]["attrs"]["hyper"]["phi.hidden"] != [128, 128] or \
            d["grid"]["attrs"]["seeds"] != [0, 1]:
        fail("grid: seeds or phi.hidden")  # what the brief states, beside the derivation above
    print(f"ok: {n} attributes of {os.path.basename(ds)} typed as declared and equal to the raw "
          f"read; seeds, evaluate_N, registrations, query seeds and @hyper ({len(types)} keys, "
          "the engine's types) as the profile and the engine say")
    return d, axes


def check_results_file(smoke, ds):
    with sirl_bench.open(smoke) as r:
        n = check_typed_tree(smoke, r.datasets)
        p = r.provenance
        if p["schema_version"] != 3 or p["complete"] is not True or type(p["threads"]) is not int \
                or p["tasks_done"] != p["tasks_total"] or type(p["wall_seconds"]) is not float:
            fail(f"provenance: {p}")
        rec = r.records
        key = rec[(rec.kind == "rep") & (rec.env == "grid") & (rec.variant == "sirl")].key.iloc[0]
        said = r.record(key)["hyper"]
        full = sirl_bench.datasets(ds)["grid"]["attrs"]["hyper"]
        if not isinstance(said, sirl_bench.Hyper) or not said or \
                any(full[k] != v or type(full[k]) is not type(v) for k, v in said.items()):
            fail(f"{key}: the record's hyper {said!r} is not the dataset's")
    print(f"ok: {n} attributes of the smoke results file typed as declared; provenance typed; a "
          "rep record's hyper-parameters are a typed dict equal to the dataset's")


# --- embedding keys ----------------------------------------------------------------------------

def check_embedding_keys(tmp, d, axes, ds, smoke):
    keys = sirl_bench.embedding_keys(ds)
    want = [(e, s, N) for e, (seeds, Ns) in axes.items() for s in seeds for N in Ns]
    if sorted(keys) != sorted(want) or len(keys) != len(want):
        fail(f"embedding_keys {list(keys)} != the profile's {want}")
    if any(p != f"/{e}/s{s}/N{N}" or p != sirl_bench.embedding_name(e, s, N)
           for (e, s, N), p in keys.items()):
        fail(f"embedding_keys' paths: {keys}")
    if any(type(s) is not int or type(N) is not int for _, s, N in keys):
        fail("embedding_keys: seed or N not int")
    if sirl_bench.embedding_keys(d) != keys or \
            list(sirl_bench.embedding_keys(d, ["grid2"])) != [k for k in keys if k[0] == "grid2"]:
        fail("embedding_keys of the open mapping, or for --envs grid2, differ")
    one_line_error(lambda: sirl_bench.embedding_keys(smoke), smoke, "has no @seeds or @evaluate_N")
    one_line_error(lambda: sirl_bench.embedding_keys(ds, ["nope"]), ds, "no /datasets/nope")
    # What `sirl evaluate` reads: every key (and no other), checked by the engine itself.
    rng = np.random.default_rng(0)
    emb = {k: rng.standard_normal((d[k[0]]["attrs"]["trajectories"], 3)) for k in keys}
    less = dict(list(emb.items())[:-1])
    sirl_bench.write_embeddings(f"{tmp}/less.h5", less)
    last = list(keys)[-1]
    p = sirl("evaluate", f"{tmp}/less.h5", "--name", "probe", "--profile", "smoke", "--against",
             smoke, "--out", f"{tmp}/less-run.h5", "--quiet", expect=2)
    if keys[last] not in p.stderr:
        fail(f"sirl evaluate without {keys[last]}: {p.stderr!r}")
    sirl_bench.write_embeddings(f"{tmp}/all.h5", emb)
    sirl("evaluate", f"{tmp}/all.h5", "--name", "probe", "--profile", "smoke", "--against", smoke,
         "--out", f"{tmp}/all-run.h5", "--quiet", "--threads", "2")
    with sirl_bench.open(f"{tmp}/all-run.h5") as r:
        fpe = r.fpe[r.fpe.variant == "probe"]
        got = {(x.env, int(x.seed), int(x.N)) for x in fpe.itertuples()}
        if got != set(keys):
            fail(f"sirl evaluate's probe cells {sorted(got)} != embedding_keys {sorted(keys)}")
    print(f"ok: embedding_keys lists the profile's {len(keys)} (env, seed, N) with their paths; "
          "`sirl evaluate` takes exactly them (one fewer is refused, naming it)")


# --- on demand ----------------------------------------------------------------------------------

class Reads:
    """Counts h5py Dataset reads (every way the reader could read an array)."""

    def __init__(self):
        self.n = 0
        self.saved = {}

    def __enter__(self):
        for name in ("__getitem__", "read_direct", "__array__"):
            orig = getattr(h5py.Dataset, name)
            self.saved[name] = orig

            def counted(ds, *a, _orig=orig, **k):
                self.n += 1
                return _orig(ds, *a, **k)
            setattr(h5py.Dataset, name, counted)
        return self

    def __exit__(self, *exc):
        for name, orig in self.saved.items():
            setattr(h5py.Dataset, name, orig)


def check_lazy(ds, smoke):
    with Reads() as reads:
        d = sirl_bench.datasets(ds)
        for env in d:
            g = d[env]
            if "inputs" not in g or "attrs" not in list(g) or len(g) < 2:
                fail(f"{env}: in / iter / len")
            g["attrs"], g["seeds"]["s0"]["attrs"], g["queries"]["similarity"].__class__  # noqa: B018
        sirl_bench.embedding_keys(d)
        sirl_bench.embedding_keys(ds)
        r = sirl_bench.open(smoke)
        for env in r.datasets:
            r.datasets[env]["attrs"]  # noqa: B018
        if reads.n != len(d):  # the arrays asked for above: each queries/similarity
            fail(f"reading attributes and embedding keys read {reads.n - len(d)} arrays")
        X = r.datasets["grid"]["inputs"]
        X2 = r.datasets["grid"]["inputs"]
        if reads.n != len(d) + 1 or X is not X2:
            fail(f"an array is read once on first access and kept ({reads.n - len(d)} reads)")
    with h5py.File(smoke, "r") as f:
        raw = f["datasets/grid/inputs"][:]
        sim = f["datasets/grid/queries/similarity"][:]
        names = [x.decode() if isinstance(x, bytes) else x
                 for x in f["datasets/grid/features"].attrs["feature_names"]]
    g = r.datasets["grid"]
    if type(X) is not np.ndarray or X.dtype != np.float32 or not np.array_equal(X, raw) or \
            not np.array_equal(g["queries"]["similarity"], sim) or \
            g["attrs"]["features.feature_names"] != names:
        fail("res.datasets[env][...] is not the raw array / attribute")
    whole = r.datasets.to_dict()
    if type(whole["grid"]) is not dict or type(whole["grid"]["queries"]) is not dict or \
            not np.array_equal(whole["grid"]["queries"]["tpa"]["pairs"],
                               g["queries"]["tpa"]["pairs"]):
        fail("to_dict() is not plain nested dicts of the arrays")
    r.close()
    # A group outlives the mapping it came from (report/render_jaco.py's pattern) ...
    grp = sirl_bench.datasets(ds)["jaco"]
    gc.collect()
    if grp["inputs"].shape[0] != grp["attrs"]["trajectories"]:
        fail("a group of a dropped mapping cannot read its arrays")
    del grp
    # ... and reading after the file is closed is one line.
    with sirl_bench.datasets(ds) as d:
        grid = d["grid"]
    one_line_error(lambda: grid["inputs"], ds, "closed before")
    # Nothing holds the file open once the mapping and its groups are dropped (no reference
    # cycle: closed without the garbage collector, as when datasets() read everything at once),
    # so the same process can open it for writing right after.
    copy = ds + ".copy.h5"  # ds itself: main() holds its mapping open
    shutil.copy(ds, copy)
    gc.disable()
    try:
        for what in ("attrs", "inputs"):
            sirl_bench.datasets(copy)["grid"][what]
            h5py.File(copy, "r+").close()
    except OSError as e:
        fail(f"the file is still open after its mapping was dropped: {e}")
    finally:
        gc.enable()
    print("ok: attributes and embedding keys read no array; an array is read once, on first "
          "access, equal to the raw read; a group outlives its mapping; after close, one line")


# --- malformed ----------------------------------------------------------------------------------

def one_line_error(call, path, text):
    try:
        call()
    except sirl_bench.ResultsError as e:
        msg = str(e)
        if path not in msg or text not in msg or "\n" in msg:
            fail(f"the refusal of {path} is not one line naming it and {text!r}: {msg!r}")
        return msg
    except Exception as e:  # noqa: BLE001
        fail(f"{path}: {type(e).__name__} instead of ResultsError: {e}")
    fail(f"{path}: no ResultsError ({text})")


def check_malformed(tmp, ds, smoke):
    cases = [("seeds", np.array(["x"], dtype=h5py.string_dtype()), "@seeds"),
             ("evaluate_N", np.array(["100", "1e3"], dtype=h5py.string_dtype()), "@evaluate_N"),
             ("in_claims", np.int64(2), "@in_claims"),
             ("trajectories", "lots", "@trajectories"),
             ("teacher_beta", "infinite", "@teacher_beta"),
             ("hyper", "phi.hidden = 128,x\nsirl.epochs = 3\n", "phi.hidden"),
             ("hyper", "sirl.epochs 30\n", "@hyper")]
    for i, (name, value, text) in enumerate(cases):
        bad = os.path.join(tmp, f"bad{i}.h5")
        shutil.copy(ds, bad)
        with h5py.File(bad, "r+") as f:
            del f["datasets/grid"].attrs[name]
            f["datasets/grid"].attrs[name] = value
        msg = one_line_error(lambda: sirl_bench.datasets(bad)["grid"]["attrs"], bad, text)
        one_line_error(lambda: sirl_bench.embedding_keys(bad), bad, text)
    # Results files are framed: an edit re-framed, as an engine writing these values would have.
    bad = os.path.join(tmp, "bad-results.h5")
    shutil.copy(smoke, bad)
    with h5py.File(bad, "r+") as f:
        f["datasets/jaco"].attrs["vae_weak_claim"] = "yes"
    reframe(bad)
    one_line_error(lambda: sirl_bench.open(bad).datasets["jaco"]["attrs"], bad, "@vae_weak_claim")
    bad = os.path.join(tmp, "bad-schema.h5")
    shutil.copy(smoke, bad)
    with h5py.File(bad, "r+") as f:
        f.attrs["schema_version"] = "three"
    reframe(bad)
    one_line_error(lambda: sirl_bench.open(bad), bad, "@schema_version")
    print(f"ok: {len(cases) + 2} malformed attributes are one-line ResultsErrors naming the file "
          f"(e.g. {msg})")


def check_xarray(smoke):
    """to_xarray puts every row of a long table at its cell's coordinates (checked row by row
    against the DataFrame), NaN elsewhere; a curve's losses are the record's array; rows the
    dims do not tell apart are refused naming the column; without xarray, one ImportError."""
    try:
        import xarray  # noqa: F401
    except ImportError:
        print("skipped: to_xarray (python3-xarray not installed; scripts/setup.sh installs it)")
        return
    import pandas as pd
    from sirl_bench import xarray_view
    with sirl_bench.open(smoke) as r:
        for name in ("fpe", "tpa", "vae_latents"):
            df, ds = r.tables[name], r.to_xarray(name)
            dims = xarray_view.DEFAULT_DIMS[name]
            value = {"fpe": "fpe", "tpa": "tpa", "vae_latents": "kl"}[name]
            for _, row in df.iterrows():
                at = {d: (-1 if pd.isna(row[d]) else row[d]) for d in dims}
                got = float(ds[value].sel(at).values)
                if got != float(row[value]):
                    fail(f"to_xarray({name}) at {at}: {got}, the table's row: {row[value]}")
            if int(ds[value].notnull().sum()) != len(df):
                fail(f"to_xarray({name}) holds {int(ds[value].notnull().sum())} values for "
                     f"{len(df)} rows")
        c = r.to_xarray("curves")
        key = r.records[r.records.kind == "rep"].key.iloc[0]
        want = r.array(key, "loss_curve").astype(float)
        got = c.loss.sel(key=key, head=-1).values[:len(want)]
        if not np.array_equal(got, want):
            fail(f"to_xarray(curves) of {key}: {got[:4]}…, the record's {want[:4]}…")
        two = pd.concat([r.tables["fpe"], r.tables["fpe"].assign(teacher="noisy")])
        try:
            xarray_view.frame_to_xarray(two, xarray_view.DEFAULT_DIMS["fpe"], "fpe")
            fail("two teachers' rows on one grid were accepted")
        except sirl_bench.ResultsError as e:
            if "teacher" not in str(e) or "\n" in str(e):
                fail(f"the refusal does not name the teacher column in one line: {e}")
    p = subprocess.run(["/usr/bin/python3", "-c",
                        "import sys; sys.modules['xarray'] = None; sys.path.insert(0, sys.argv[2]);"
                        " import sirl_bench; sirl_bench.open(sys.argv[1]).to_xarray('fpe')",
                        smoke, os.path.join(SRC, "python")], capture_output=True, text=True)
    if p.returncode == 0 or "python3-xarray" not in p.stderr.splitlines()[-1]:
        fail(f"without xarray: rc {p.returncode}, {p.stderr[-300:]}")
    print("ok: to_xarray puts every fpe, tpa and vae_latents row at its cell (NaN elsewhere), a "
          "curve at its key; two teachers refused naming the column; no xarray: one ImportError")


def main():
    with tempfile.TemporaryDirectory() as tmp:
        smoke, ds = os.path.join(tmp, "smoke.h5"), os.path.join(tmp, "ds.h5")
        if not sirl_testing.copy_fixture("smoke", smoke, with_cache=False):
            sirl("run", "smoke", "--out", smoke, "--threads", "2", "--quiet")
        sirl("dataset", "--profile", "smoke", "--out", ds)
        prof = profile()
        d, axes = check_dataset_file(ds, prof)
        check_results_file(smoke, ds)
        check_embedding_keys(tmp, d, axes, ds, smoke)
        check_lazy(ds, smoke)
        check_malformed(tmp, ds, smoke)
        check_xarray(smoke)
    print("reader_typed: OK")


if __name__ == "__main__":
    main()
