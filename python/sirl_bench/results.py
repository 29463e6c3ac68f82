"""A sirl-bench results file (`sirl run --out X.h5`) as typed pandas DataFrames.

The engine writes every table row with its cell's fields (env, seed, teacher, method, variant,
vae, selection, N, M, frozen, best_mode) as columns, and every task record in /runs/<key> with
the same fields as attributes. This module only converts types: it never takes a task key apart
and never restates a rule the engine decides (which cells are the paper's best mode, which
method a variant is). Task keys are opaque identifiers here.

Types, the same in every table:
  names (env, method, variant, selection, teacher, kind, key, ...)  str; teacher "" is the
                                                                   profile's main teacher
  flags (vae, frozen, in_main, in_ablation, best_mode, converged,   bool ("boolean", with <NA>,
         stopped, reference, newton_converged)                      where a row has no such field)
  N, M                                   Int64; <NA> where the cell has none (a method that uses
                                         no queries has no N; a training that is not a TPA cell
                                         has no M and no frozen)
  dead_fraction                          float; NaN where it was not measured

/tables/fpe and /tables/tpa (and robust_fpe, robust_tpa) also say what a row is, from the data
(engines up to 0.16.0 wrote neither column; this reader fills them so every file reads the same):
  reference   True for the reference representations every profile scores beside the methods
              (method "truth": the true features φ*, a ceiling; "raw": the trajectory input, a
              floor). They use no queries (N <NA>) and are never a method's competitor. Missing
              in an older file: False.
  protocol    the TPA tables only: how a cell's reward heads were fit. "paper" (the paper's head
              φ→1024→1024→1 trained by Adam) or "linear" (a Bradley–Terry linear head on the
              frozen φ, fit to convergence by Newton's method). Missing in an older file: "paper".

Attributes (provenance, the "attrs" of /datasets, a record's hyper-parameters) are typed by the
tables of attributes.py: @seeds [0, 1], @in_claims True, @teacher_beta inf, @hyper a dict.
/datasets is read on demand (lazy.py): its attributes without its arrays.
"""
from __future__ import annotations

import json
import os
import re
from collections.abc import Mapping

import h5py
import numpy as np
import pandas as pd

from . import untrusted
from .attributes import as_stored, typed_attrs
from .attributes import typed as typed_attr
from .errors import ResultsError  # re-exported: sirl_bench.ResultsError
from .lazy import Datasets, Group

# Results-file schema versions this reader understands (results/results_file.h).
SCHEMA_VERSIONS = (1, 2, 3)

FLAG_COLUMNS = ("vae", "frozen", "in_main", "in_ablation", "best_mode", "converged", "stopped",
                "reference", "newton_converged")
# The TPA protocols (the `protocol` column of /tables/tpa), the paper's first; a file written
# before the column existed holds the paper's only.
PROTOCOLS = ("paper", "linear")
# What a table lacking a column of a newer engine reads as: {table: {column: value}}.
FILLED = {"fpe": {"reference": False}, "tpa": {"protocol": "paper", "reference": False},
          "robust_fpe": {"reference": False},
          "robust_tpa": {"protocol": "paper", "reference": False}}
# Integer-valued numbers of a record (the file stores a record's numbers as float64).
INT_FIELDS = ("N", "M", "seed", "threads", "queries", "head", "epoch", "epochs", "max_epochs",
              "dim", "latent", "tasks_done", "tasks_total", "schema_version", "newton_iterations")


def _text(v):
    return v.decode("utf-8") if isinstance(v, bytes) else v


def _texts(a):
    return [_text(x) for x in a]


def typed(df: pd.DataFrame) -> pd.DataFrame:
    """Converts a raw table or record frame to the types above (a copy)."""
    df = df.copy()
    for c in df.columns:
        if df[c].dtype == object:
            df[c] = df[c].map(_text)
    absent_m = None
    if "M" in df:
        absent_m = df["M"].isna() | (df["M"] == 0)
    for c in ("N", "M"):
        if c in df:
            x = df[c].to_numpy(dtype=float)
            df[c] = _ints(x, np.isnan(x) | (x == 0))
    for c in INT_FIELDS:
        if c in df and c not in ("N", "M") and df[c].dtype != object:
            x = df[c].to_numpy(dtype=float)
            if c == "seed" and (x < 0).any():  # -1: a task with no seed (timings)
                x = np.where(x < 0, np.nan, x)
            if np.isnan(x).any():
                df[c] = _ints(x, np.isnan(x))
            elif len(x) == 0 or np.all(np.mod(x, 1) == 0):
                df[c] = x.astype("int64")
    for c in FLAG_COLUMNS:
        if c in df and df[c].dtype != object:
            b = pd.array(df[c].to_numpy(dtype=float) != 0, dtype="boolean")
            b[np.asarray(df[c].isna())] = pd.NA
            if c == "frozen" and absent_m is not None:
                b[np.asarray(absent_m)] = pd.NA
            df[c] = b
    if "dead_fraction" in df:
        df["dead_fraction"] = df["dead_fraction"].where(df["dead_fraction"] >= 0)
    return df


def filled(name, df: pd.DataFrame) -> pd.DataFrame:
    """Table `name` with the columns of FILLED it lacks (a file of an older engine), at the value
    every row of such a file has: protocol "paper", reference False."""
    for c, v in FILLED.get(name, {}).items():
        if c not in df:
            df[c] = pd.array([v] * len(df), dtype="boolean" if isinstance(v, bool) else object)
    return df


def _ints(x, missing):
    """Int64 (nullable) from floats x, <NA> where missing."""
    return pd.arrays.IntegerArray(np.where(missing, 0, x).astype("int64"), np.asarray(missing))


class _LazyTables(Mapping):
    def __init__(self, f):
        self._f = f
        self._names = sorted(f["tables"].keys()) if "tables" in f else []
        self._cache = {}

    def __getitem__(self, name):
        if name not in self._names:
            raise KeyError(f"no table '{name}' in this file (it has: {', '.join(self._names)})")
        if name not in self._cache:
            self._cache[name] = filled(name, typed(pd.DataFrame(self._f["tables/" + name][:])))
        return self._cache[name]

    def __iter__(self):
        return iter(self._names)

    def __len__(self):
        return len(self._names)


class Results:
    """One results file, open for reading. Use as a context manager or call close()."""

    def __init__(self, path):
        self.path = str(path)
        # Checksums, links and a sandboxed read of its structures before h5py opens it here.
        self.framed, self.verified = untrusted.check(self.path)
        try:
            self._f = h5py.File(self.path, "r")
        except OSError as e:
            raise ResultsError(f"{self.path}: cannot open as HDF5 ({e})") from None
        f = self._f
        if "runs" not in f or "engine_version" not in f.attrs:
            kind = "a dataset file" if "datasets" in f else "not a results file"
            self._f.close()
            raise ResultsError(f"{self.path}: {kind} (no /runs or engine_version); "
                               f"a results file is what `sirl run --out` writes")
        try:  # version 1 files carry no number
            v = typed_attr("provenance", "schema_version", f.attrs.get("schema_version", 1),
                           f"{self.path}: /")
        except ResultsError:
            self._f.close()
            raise
        if v not in SCHEMA_VERSIONS:
            self._f.close()
            raise ResultsError(f"{self.path}: results schema version {v}; this reader reads "
                               f"versions {SCHEMA_VERSIONS[0]} to {SCHEMA_VERSIONS[-1]}")
        if v >= 3 and not self.framed:
            self._f.close()
            raise ResultsError(f"{self.path}: a schema-{v} results file (engines from 0.8.0 frame "
                               "every file they write) without its checksum frame: it was "
                               "rewritten (h5repack, h5py) or its first 1024 bytes were cut off, "
                               "so nothing vouches for its values")
        self.schema_version = v
        self.tables = _LazyTables(f)
        self._records = None
        self._curves = None
        self._datasets = None

    # --- context manager ---
    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()

    def close(self):
        self._f.close()

    def __getattr__(self, name):
        # r.tpa, r.fpe, ...: the tables by attribute
        if name.startswith("_") or name not in self.__dict__.get("tables", {}):
            raise AttributeError(name)
        return self.tables[name]

    def raw_table(self, name) -> pd.DataFrame:
        """A table as stored (strings decoded, numbers untyped: flags 0/1, N and M 0 where a cell
        has none): for digests and bit-level comparisons across engine versions."""
        if name not in self.tables:
            raise KeyError(f"no table '{name}' in this file")
        df = pd.DataFrame(self._f["tables/" + name][:])
        for c in df.columns:
            if df[c].dtype == object:
                df[c] = df[c].map(_text)
        return df

    def verdicts(self) -> pd.DataFrame | None:
        """The report's verdicts stored in the file (/verdicts, written by `sirl reproduce`),
        one row per hypothesis × environment × TPA protocol, as claims() gives them; None when
        the file holds none (a run's file before its report, or rewritten by a later run)."""
        g = self._f.get("verdicts")
        if not isinstance(g, h5py.Group) or "claims" not in g.attrs:
            return None
        return _claims_frame(_text(g.attrs["claims"]), f"{self.path}: /verdicts@claims")

    # --- provenance ---
    @property
    def provenance(self) -> dict:
        """The run's root attributes: engine version, git commit, CPU class, kernel paths,
        libraries, host, threads, profile name and text, start and finish times, wall seconds,
        tasks done and total, typed (attributes.ATTRIBUTE_TYPES["provenance"]: schema_version,
        threads and tasks_* int, wall_seconds and the roofs float, complete bool)."""
        return typed_attrs("provenance", self._f.attrs, f"{self.path}: /")

    @property
    def hyper_points(self) -> dict:
        """{env: [base tag, other tags…]} for environments with hyper-parameter axes
        ([hyper.<env>] keys given as lists; {} when none). A table row's hyper_point is one of
        the tags, or "" for the base point (the first tag): the cells a profile without the axes
        has, and the only ones the paper's figures and claims use."""
        out = {}
        for line in self.provenance.get("hyper_points", "").splitlines():
            env, *tags = line.split("\t")
            out[env] = tags
        return out

    @property
    def libraries(self) -> dict:
        """The compiler and library versions the run's bits depend on, {name: version} (from
        /@libraries, "compiler GCC 12.2.0; eigen 3.4.0; ..."); {} for files before engine 0.8.0.
        Which code paths ran is provenance["kernel_paths"] (engine 0.9.0 on)."""
        text = self.provenance.get("libraries", "")
        out = {}
        for part in filter(None, (p.strip() for p in text.split(";"))):
            name, _, version = part.partition(" ")
            out[name] = version
        return out

    @property
    def methods(self) -> pd.DataFrame:
        """How figures show every variant of the file, one row per variant (index: its name, as
        the tables' `variant` column holds it): method, label, colour, role ("sirl", "baseline",
        "reference", "external"), queries (the answers it learns from: "similarity", "preference"
        or ""), figure_order (its place among the method lines of Figs. 4 and 5; -1: none),
        catalog_order, vae, best_frozen (the paper's best TPA mode is frozen), accepts_vae,
        selection, selection_label, selection_colour, selection_order, dashes (a reference line's dash pattern,
        "6 3"). Declared once per method in the engine
        (engine/method_catalog.cpp); empty for files of engines before 0.19.0."""
        cols = ["method", "label", "colour", "role", "queries", "figure_order", "catalog_order",
                "vae", "best_frozen", "accepts_vae", "selection", "selection_label",
                "selection_colour", "selection_order", "dashes"]
        rows = {}
        for name, g in (self._f["methods"].items() if "methods" in self._f else []):
            rows[name] = {k: as_stored(g.attrs[k]) for k in cols if k in g.attrs}
            _check_method(self.path, name, rows[name])
        df = pd.DataFrame.from_dict(rows, orient="index", columns=cols)
        df.index.name = "variant"
        if not df.empty:
            for c in ("figure_order", "catalog_order", "selection_order"):
                df[c] = df[c].astype(int)
            for c in ("vae", "best_frozen", "accepts_vae"):
                df[c] = df[c].astype(bool)
        return df

    @property
    def complete(self) -> bool:
        return bool(self.provenance.get("complete", 0))

    @property
    def missing_tasks(self) -> list:
        """The task keys a partial merge (`sirl merge --partial`) lacked; [] for a merge that
        had every task, and for a run (a partial run's missing tasks are its plan's keys not in
        keys())."""
        return self.provenance.get("missing_tasks", "").split()

    # --- task records ---
    def keys(self):
        """Every task key in the file, in the order the run committed them."""
        return _texts(self._f["runs_index"][:]) if "runs_index" in self._f else []

    def record(self, key) -> dict:
        """A task record's scalar fields (numbers and texts) and the names of its arrays; "hyper"
        (the hyper-parameters the task read) as a Hyper dict, its text as written in .text."""
        where = f"{self.path}: /runs/{key}"
        try:
            a = self._f["runs/" + key].attrs
            out = {"key": key, "kind": _text(a.get("task_kind", ""))}
            for k in _texts(a.get("record_texts", [])):
                out[k] = typed_attr("records", k, a[k], where)
            for k in _texts(a.get("record_numbers", [])):
                out[k] = float(a[k])
            out["arrays"] = _texts(a.get("record_arrays", []))
        except (KeyError, TypeError, ValueError) as e:
            # A record names a field it lacks, or one that is not a number: the engine writes
            # neither (a crafted or damaged file that passed its checksum).
            raise ResultsError(f"{where}: not a record as the engine writes it "
                               f"({' '.join(str(e).split())[:200]})") from None
        return out

    @property
    def records(self) -> pd.DataFrame:
        """One row per task: key, kind, its cell fields and scalar results (columns a kind does
        not have are missing values). Long texts (hyper-parameters) stay in record(key)."""
        if self._records is None:
            rows = []
            for k in self.keys():
                r = self.record(k)
                r.pop("hyper", None)
                r["arrays"] = ",".join(r["arrays"])
                rows.append(r)
            df = pd.DataFrame(rows)
            self._records = typed(df) if len(df) else df
        return self._records

    def array(self, key, name) -> np.ndarray:
        """One array of a task record: e.g. array(key, "embedding") is φ(Ξ) [T, d]."""
        g = self._f["runs/" + key]
        if name not in g:
            raise KeyError(f"task {key} has no array '{name}' (it has: {', '.join(g.keys())})")
        return g[name][:]

    def embedding(self, key) -> np.ndarray:
        """φ(Ξ) [T, d] of a representation record (kind "rep")."""
        return self.array(key, "embedding")

    # --- learning curves ---
    def curves_of(self, records: pd.DataFrame | None = None) -> pd.DataFrame:
        """The learning curves of the given records (a filtered `records` frame; default every
        record), one row per (task, head, epoch): the record's cell fields, head (<NA> for a
        training with one curve), epoch (from 1), and one column per curve it stores: loss and,
        for the VAE, kl and reconstruction. A reward head stopped by tpa.stop has no rows after
        its stop."""
        recs = self.records if records is None else records
        fields = [c for c in ("key", "kind", "env", "seed", "teacher", "method", "variant", "vae",
                              "selection", "N", "M", "frozen", "best_mode") if c in recs]
        parts = []
        for _, row in recs.iterrows():
            names = [n for n in str(row.get("arrays", "")).split(",") if n.endswith(("_curve", "_curves"))]
            if not names:
                continue
            cols = {}
            for n in names:
                a = self.array(row.key, n).astype(float)
                col = n.rsplit("_", 1)[0]
                cols[col] = a if a.ndim == 2 else a[None, :]
            R, E = cols.get("loss", next(iter(cols.values()))).shape
            d = {"head": np.repeat(np.arange(R), E), "epoch": np.tile(np.arange(1, E + 1), R)}
            for col, a in cols.items():
                if a.shape == (R, E):
                    d[col] = a.reshape(-1)
            part = pd.DataFrame(d)
            if "loss" in part:
                part = part[np.isfinite(part["loss"].to_numpy())]
            if R == 1 and not any(n.endswith("_curves") for n in names):
                part["head"] = pd.NA
            for c in fields:
                part[c] = row[c]
            parts.append(part)
        if not parts:
            return pd.DataFrame(columns=fields + ["head", "epoch", "loss"])
        out = pd.concat(parts, ignore_index=True)
        out["head"] = out["head"].astype("Int64")
        lead = fields + ["head", "epoch"]
        out = out[lead + [c for c in out.columns if c not in lead]]
        for c in ("N", "M"):
            if c in out:
                out[c] = out[c].astype("Int64")
        for c in ("vae", "frozen", "best_mode"):
            if c in out:
                out[c] = out[c].astype("boolean")
        return out

    @property
    def curves(self) -> pd.DataFrame:
        """Every learning curve in the file (curves_of every record); for a large file, filter
        `records` first and call curves_of."""
        if self._curves is None:
            self._curves = self.curves_of()
        return self._curves

    def to_xarray(self, name="tpa", dims=None):
        """A table (`fpe`, `tpa`, `tpa_heads`, `vae_latents`, ...) or "curves" as an
        xarray.Dataset: one dimension per cell field in `dims` (default
        xarray_view.DEFAULT_DIMS[name]), one data variable per other column, NaN where the grid
        has no cell; a missing cell field (N of VAE, head of a one-curve training) is −1.
        Needs xarray (python3-xarray). Rows the dims do not tell apart (two teachers,
        hyper-parameter points) are refused naming the column to add."""
        from . import xarray_view
        if dims is None:
            if name not in xarray_view.DEFAULT_DIMS:
                raise ResultsError(f"to_xarray: no default dimensions for '{name}': pass dims "
                                   f"(defaults exist for {', '.join(xarray_view.DEFAULT_DIMS)})")
            dims = xarray_view.DEFAULT_DIMS[name]
        df = self.curves if name == "curves" else self.tables[name]
        return xarray_view.frame_to_xarray(df, dims, f"{self.path}: {name}")

    # --- datasets ---
    @property
    def datasets(self) -> Datasets:
        """Per environment: {"attrs": its registration (title, trajectories, teacher, ...),
        "inputs": Ξ [T, input_dim], "features": the true features [T, F], "queries": {...},
        "rewards": {...}, ...}; every array of /datasets/<env>, nested as stored. Read on demand
        (lazy.py): "attrs" (typed: attributes.py) reads no array; an array is read on first
        access, while the file is open, and kept."""
        if self._datasets is None:
            self._datasets = Datasets(self._f, self.path, owns_file=False)
        return self._datasets


_COLOUR = re.compile(r"#[0-9a-fA-F]{6}")
_ROLES = {"sirl", "baseline", "reference", "external"}


def _check_method(path, name, a):
    """One /methods/<variant> group as the engine writes it, or ResultsError naming it: the
    figures draw its label and colour, so nothing else reaches them."""
    def bad(what):
        raise ResultsError(f"{path}: /methods/{name[:60]!r}: {what} (not as the engine writes it)")
    if len(name) > 100:
        bad("a variant name longer than 100 characters")
    for k in ("method", "label", "role", "queries", "selection", "selection_label", "dashes"):
        if k in a and (not isinstance(a[k], str) or len(a[k]) > 200):
            bad(f"{k} is not a short text")
    for k in ("colour", "selection_colour"):
        if k in a and not (isinstance(a[k], str) and _COLOUR.fullmatch(a[k])):
            bad(f"{k} is not a colour #rrggbb")
    for k in ("figure_order", "catalog_order", "selection_order", "vae", "best_frozen",
              "accepts_vae"):
        if k in a and not (isinstance(a[k], (int, np.integer, float, np.floating))
                           and np.isfinite(a[k]) and abs(a[k]) < 1e6 and a[k] == int(a[k])):
            bad(f"{k} is not a small integer")
    if a.get("role", "sirl") not in _ROLES:
        bad(f"role is not one of {sorted(_ROLES)}")
    if "dashes" in a:
        try:
            [float(x) for x in a["dashes"].split()]
        except ValueError:
            bad("dashes is not a list of numbers")


def _open_h5(path):
    untrusted.check(path)
    try:
        return h5py.File(str(path), "r")
    except OSError as e:
        raise ResultsError(f"{path}: cannot open as HDF5 ({e})") from None


def datasets(path) -> Datasets:
    """/datasets of any sirl-bench file (a results file or `sirl dataset --out`), as
    Results.datasets: {env: {"attrs": ..., "inputs": Ξ, ...}}, read on demand ("attrs" reads no
    array; an array is read on first access). The file stays open while the mapping or a group
    of it is in use: `with sirl_bench.datasets(path) as d:` closes it at the end of the block,
    and `.to_dict()` reads everything at once."""
    f = _open_h5(path)
    if "datasets" not in f:
        f.close()
        raise ResultsError(f"{path}: no /datasets (not a sirl-bench results or dataset file)")
    return Datasets(f, path, owns_file=True)


def embedding_keys(source, envs=None) -> dict:
    """What `sirl evaluate` reads from an embeddings file, from the file `sirl dataset --profile
    P --out F` wrote (its path, or what sirl_bench.datasets(F) returned): {(env, seed, N): the
    array's HDF5 path "/<env>/s<seed>/N<N>"}, for every environment of the file (or of `envs`,
    as `sirl evaluate --envs` takes them) × its @seeds × its @evaluate_N, in the file's order.
    Reads attributes only; its keys are the keys write_embeddings takes."""
    if isinstance(source, Datasets):
        return _embedding_keys(source, envs)
    with datasets(source) as d:
        return _embedding_keys(d, envs)


def _embedding_keys(d, envs):
    envs = [envs] if isinstance(envs, str) else list(d) if envs is None else list(envs)
    out = {}
    for env in envs:
        if env not in d:
            raise ResultsError(f"{d.path}: no /datasets/{env} (it has: {', '.join(d)})")
        a = d[env]["attrs"]
        lacks = [f"@{k}" for k in ("seeds", "evaluate_N") if k not in a]
        if lacks:
            raise ResultsError(f"{d.path}: /datasets/{env} has no {' or '.join(lacks)}: the file "
                               "`sirl dataset --profile P --out FILE` writes lists what `sirl "
                               "evaluate` asks for (a results file or a `sirl dataset --env` "
                               "file does not)")
        for seed in a["seeds"]:
            for N in a["evaluate_N"]:
                out[(env, seed, N)] = embedding_name(env, seed, N)
    return out


def embedding_name(env, seed, N) -> str:
    """Where `sirl evaluate` looks for the embedding of Ξ of (env, seed, N): "/grid/s0/N100"."""
    return f"/{env}/s{int(seed)}/N{int(N)}"


def write_embeddings(path, embeddings, method=None) -> None:
    """Writes the file `sirl evaluate` reads: {(env, seed, N): array [T, d]} (row i = φ(ξ_i), Ξ in
    the order of /datasets/<env>/inputs), each stored float32 at embedding_name(env, seed, N).
    Refuses NaN or ±Inf and arrays that are not 2-D, with one line naming the array."""
    arrays = {}
    for (env, seed, N), z in embeddings.items():
        a = np.asarray(z, dtype=np.float32)
        name = embedding_name(env, seed, N)
        if a.ndim != 2 or a.shape[1] < 1:
            raise ResultsError(f"{name}: an embedding is [T, d], got shape {a.shape}")
        if not np.isfinite(a).all():
            raise ResultsError(f"{name}: holds NaN or ±Inf")
        arrays[name] = a
    tmp = f"{path}.partial"
    with h5py.File(tmp, "w") as f:
        if method:
            f.attrs["method"] = method
        for name, a in arrays.items():
            f.create_dataset(name, data=a)
    os.replace(tmp, path)


def study_analysis(path) -> dict:
    """The user-study analysis, its arrays by name and "attrs": from `sirl study analyze --out`'s
    study_analysis.h5, or from a results file whose profile ran the study (its /tables/study, one
    row per value, rebuilt into the same arrays)."""
    with _open_h5(path) as f:
        if "study_analysis" in f:
            return Group(f["study_analysis"], "study_analysis", str(path), f).to_dict()
        if "tables" in f and "study" in f["tables"]:
            return _study_from_table(typed(pd.DataFrame(f["tables/study"][:])), str(path),
                                     as_stored(f.attrs.get("profile_name", "")))
    raise ResultsError(f"{path}: not a study analysis (no /study_analysis), nor a results file "
                       f"whose profile ran the study (no /tables/study; an engine before 0.14.0 "
                       f"wrote none: rerunning `sirl run` on its profile adds it, reusing the rest)")


def _study_from_table(t: pd.DataFrame, path: str, profile: str) -> dict:
    """The arrays of a study_analysis.h5 from /tables/study's rows (each (measure, method) in row
    order: seeds, participants, rewards)."""
    if len(t) == 0:
        raise ResultsError(f"{path}: /tables/study is empty (the profile has no [study], or its "
                           f"analysis task has not run)")
    d = {}
    for measure in ("fpe", "real", "heldout", "simulated"):
        for method in ("sirl", "random", "random_other"):
            rows = t[(t["measure"] == measure) & (t["method"] == method)]
            if measure == "fpe" and method == "random_other":
                continue
            d[f"{measure}_{method}"] = rows["value"].to_numpy(dtype=float)
    real = t[(t["measure"] == "real") & (t["method"] == "sirl")]
    d["participants"] = np.array(real["unit"].tolist(), dtype=object)
    d["both_features"] = real["both_features"].to_numpy(dtype=np.int32)
    first = t.iloc[0]
    d["attrs"] = {"env": first["env"], "random_mode": first["random_mode"],
                  "study_file": f"{path} (profile {profile}'s simulated cohort)"}
    for k in ("triplets", "seeds", "cv_splits", "sirl_epochs", "tpa_epochs"):
        d["attrs"][k] = int(first[k])
    return d


def open(path) -> Results:  # noqa: A001 (the package's entry point: sirl_bench.open)
    """Opens a results file; raises ResultsError with one clear line if it is not one."""
    return Results(path)


def _claims_frame(text, where) -> pd.DataFrame:
    try:
        rows = json.loads(text)
    except ValueError as e:
        raise ResultsError(f"{where}: not JSON ({e})") from None
    if not isinstance(rows, list) or not all(isinstance(r, dict) for r in rows):
        raise ResultsError(f"{where}: not the report's list of verdicts")
    return pd.DataFrame(rows)


def claims(source) -> pd.DataFrame:
    """The report's verdicts, one row per hypothesis × environment × TPA protocol (env, claim,
    protocol: "paper" or "linear" for a TPA claim, None for an FPE claim; verdict, including
    "not run" for a protocol the file lacks; comparisons, power, ...). `source` is a results file
    (the verdicts `sirl reproduce` stored in it: ResultsError if it holds none) or the folder
    `sirl reproduce --figures` (or report/plot_figures.py) wrote (its claims.json)."""
    import builtins
    import os
    if os.path.isdir(source):
        path = os.path.join(source, "claims.json")
        with builtins.open(path, encoding="utf-8") as fh:
            return _claims_frame(fh.read(), path)
    with Results(source) as r:
        v = r.verdicts()
    if v is None:
        raise ResultsError(f"{source}: no verdicts stored (`sirl reproduce` stores them after "
                           "the report; a later `sirl run` drops them): run the report, or pass "
                           "its figures folder")
    return v
