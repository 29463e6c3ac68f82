"""The types of the HDF5 attributes the engine writes, declared in one place, and their reading.

The engine stores a number attribute as an HDF5 integer or float, a flag as the integer 0 or 1,
the seeds and N values of a `sirl dataset --profile` file as lists of decimal texts (@seeds =
["0", "1"]) and the hyper-parameters as "key = value" lines. The reader returns each as what it
means, by the tables below (never by guessing from a value's text):

  TEXT   str                     INT    int (a stored integer, or its decimal text)
  TEXTS  list[str]               INTS   list[int] (a list of integers or of their decimal texts)
  FLOAT  float ("inf" → inf)     FLAG   bool (stored 0 or 1)
  SEED   int: a 64-bit unsigned seed, which the engine stores in an int64 attribute (its bits), as
         `sirl inspect` prints it
  HYPER  Hyper, a dict {key: value} typed by HYPER_TYPES (its text as written: `.text`)

An attribute a table does not name (one a newer engine added) is returned as stored: texts as
str, numbers as int or float, text arrays as list[str]. A named attribute that is not of its type
(@seeds = ["x"], @in_claims = 2, a hyper line without " = ") is a ResultsError with one line
naming the file, the object and the attribute.
"""
from __future__ import annotations

import re

import numpy as np

from .errors import ResultsError

TEXT, TEXTS, INT, INTS, FLOAT, FLAG, SEED, HYPER = (
    "text", "texts", "int", "ints", "float", "flag", "seed", "hyper")

# {scope: {attribute: type}}. Scopes: "provenance", the root of a results file
# (results/results_file.cpp) or of a dataset file (app/cmd_dataset.cpp); "datasets", /datasets/<env>
# and every group and array under it, an array's attributes by their own name (results/
# dataset_store.cpp, app/cmd_dataset.cpp); "study_analysis", /study_analysis (app/cmd_study.cpp);
# "records", the texts of a task record in /runs (results/task_record.cpp).
ATTRIBUTE_TYPES = {
    "provenance": {
        "schema_version": INT, "profile_name": TEXT, "profile_text": TEXT,
        "engine_version": TEXT, "git_commit": TEXT, "host": TEXT, "cpu_class": TEXT,
        "libraries": TEXT, "kernel_paths": TEXT, "started": TEXT, "finished": TEXT,
        "shard": TEXT, "hyper_points": TEXT, "missing_tasks": TEXT, "unverified_inputs": TEXT,
        "threads": INT, "tasks_total": INT, "tasks_done": INT, "complete": FLAG,
        "wall_seconds": FLOAT, "roof_fp32_gflops_per_core": FLOAT,
        "roof_bf16_gflops_per_core": FLOAT, "stream_gbs_per_core": FLOAT,
    },
    "datasets": {
        # the environment's registration (datasets/environments.h)
        "env": TEXT, "title": TEXT, "description": TEXT, "view": TEXT, "model_mjcf": TEXT,
        "in_claims": FLAG,        # its cells decide the paper's claims H1/H2
        "vae_weak_claim": FLAG,   # the paper's "VAE severely underperforms" is checked on it
        "from_file": FLAG,        # read from an environment file a profile declared
        "beyond_paper": FLAG,     # not one of the paper's environments: its claims are marked so
        "fig3_rank": INT,         # > 0: Fig. 3 may be drawn on it; the highest rank present wins
        # provenance and the simulated teacher
        "engine_version": TEXT, "generator_seed": SEED, "query_seed": SEED, "trajectories": INT,
        "teacher_beta": FLOAT, "teacher_mistake": FLOAT, "teacher_skip": FLOAT,
        "teacher_equal": FLOAT, "teacher_features": TEXTS,
        # `sirl dataset --profile`: what `sirl evaluate` asks for, and the built-in methods' hyper
        "seeds": INTS, "evaluate_N": INTS, "hyper": HYPER,
        # seeds/s<seed>, queries/<set>, queries/tpa, and the arrays' own attributes
        "seed": INT, "skipped": INT, "train": INT,
        "feature_names": TEXTS, "units": TEXTS, "names": TEXTS,
    },
    "study_analysis": {
        "study_file": TEXT, "env": TEXT, "random_mode": TEXT, "hyper": HYPER,
        "triplets": INT, "seeds": INT, "cv_splits": INT, "sirl_epochs": INT, "tpa_epochs": INT,
    },
    # a task record's texts (Results.record): the hyper-parameters it read
    "records": {"hyper": HYPER},
}

# The hyper-parameters' types (engine/hyperparams.cpp, for_each_field; `sirl plan P --set
# 'hyper.grid."KEY"=…'` names a key's type): INT, FLOAT, FLAG ("true"/"false"), INTS (widths,
# "128,128") or TEXT. A key not named here (a newer engine's) stays the text it was written as.
HYPER_TYPES = {
    "phi.hidden": INTS, "phi.embedding_dim": INT, "phi.relu_output": FLAG,
    **{f"{p}.{k}": t for p in ("sirl", "vae", "pref", "tpa")
       for k, t in (("epochs", INT), ("batch", INT), ("lr", FLOAT), ("lr_decay", FLOAT))},
    "sirl.margin": FLOAT, "vae.kl_weight": FLOAT, "vae.elbo": TEXT, "vae.standardize": FLAG,
    "pref.l2": FLOAT, "pref.stop": TEXT, "pref.stop_min_epochs": INT, "pref.stop_rel_tol": FLOAT,
    "tpa.hidden": INTS, "tpa.l2": FLOAT, "tpa.stop": TEXT,
    "tpa.stop_min_epochs": INT, "tpa.stop_rel_tol": FLOAT, "tpa.stop_frozen_rel_tol": FLOAT,
    "tpa.shadow_rel_tol": FLOAT,
    "precision": TEXT,
}

_INT_TEXT = re.compile(r"[+-]?[0-9]+")
_FLOAT_TEXT = re.compile(r"[+-]?(([0-9]+\.?[0-9]*|\.[0-9]+)([eE][+-]?[0-9]+)?|inf|infinity|nan)",
                         re.IGNORECASE)


class Hyper(dict):
    """Hyper-parameters as {key: typed value} ({"phi.hidden": [128, 128], "sirl.lr": 0.004,
    "phi.relu_output": False, "vae.elbo": "sum", ...}); `.text` is the "key = value" lines as the
    engine wrote them."""

    def __init__(self, values=(), text=""):
        super().__init__(values)
        self.text = text


class _Bad(Exception):
    pass


def _text(v):
    if isinstance(v, bytes):
        try:
            return v.decode("utf-8")
        except UnicodeDecodeError:
            raise _Bad("not UTF-8 text") from None
    return v


def _scalar(v):
    """A stored scalar as a Python value: bytes decoded, numpy scalars as int/float/bool."""
    v = _text(v)
    if isinstance(v, np.ndarray) and v.ndim == 0:
        v = _text(v[()])
    if isinstance(v, np.generic):
        v = v.item()
    return _text(v)


def _int(v):
    v = _scalar(v)
    if isinstance(v, bool) or not isinstance(v, (int, str)):
        raise _Bad("not an integer")
    if isinstance(v, str):
        if not _INT_TEXT.fullmatch(v.strip()):
            raise _Bad("not an integer")
        if len(v.strip()) > 40:  # far beyond 64 bits (and int()'s digit limit)
            raise _Bad("an integer out of range")
        v = int(v)
    return v


def _float(v):
    v = _scalar(v)
    if isinstance(v, bool) or not isinstance(v, (int, float, str)):
        raise _Bad("not a number")
    if isinstance(v, str) and not _FLOAT_TEXT.fullmatch(v.strip()):
        raise _Bad("not a number")
    return float(v)


def _flag(v):
    v = _scalar(v)
    if isinstance(v, bool):
        return v
    if isinstance(v, str) and v.strip() in ("0", "1"):
        return v.strip() == "1"
    if isinstance(v, int) and v in (0, 1):
        return bool(v)
    raise _Bad("not a flag (0 or 1)")


def _seed(v):
    x = _int(v)
    if not -(1 << 63) <= x < (1 << 64):
        raise _Bad("not a 64-bit seed")
    return x % (1 << 64)  # the int64 bits of the engine's uint64


def _str(v):
    v = _scalar(v)
    if not isinstance(v, str):
        raise _Bad("not a text")
    return v


def _list(v, each):
    v = _text(v)
    if not (isinstance(v, (np.ndarray, list, tuple)) and np.ndim(v) == 1):
        raise _Bad("not a list")
    out = []
    for x in v:
        try:
            out.append(each(x))
        except _Bad as e:
            raise _Bad(f"holds {_show(x)}, {e}") from None
    return out


_HYPER_WORDS = {"true": True, "false": False}


def _hyper_value(key, value):
    t = HYPER_TYPES.get(key, TEXT)
    if t == FLAG:
        if value not in _HYPER_WORDS:
            raise _Bad(f"{key} = {value!r} is not true or false")
        return _HYPER_WORDS[value]
    if t == INTS:
        try:
            return [_int(p) for p in value.split(",")]
        except _Bad:
            raise _Bad(f"{key} = {value!r} is not a list of widths") from None
    try:
        return CONVERT[t](value)
    except _Bad:
        raise _Bad(f"{key} = {value!r} is {'not an integer' if t == INT else 'not a number'}") \
            from None


def parse_hyper(text) -> Hyper:
    """The engine's "key = value" lines (engine/hyperparams.h, describe()) as a Hyper; raises
    ValueError (in a reader, one line of ResultsError) on a line without " = ", a key twice, or
    a value not of its key's type."""
    try:
        return _hyper(text)
    except _Bad as e:
        raise ValueError(str(e)) from None


def _hyper(v):
    text = _str(v)
    out = Hyper(text=text)
    for n, line in enumerate(text.splitlines(), 1):
        if not line.strip():
            continue
        key, sep, value = line.partition(" = ")
        key, value = key.strip(), value.strip()
        if not sep or not key:
            raise _Bad(f"line {n} is not 'key = value': {line[:60]!r}")
        if key in out:
            raise _Bad(f"{key} is given twice")
        out[key] = _hyper_value(key, value)
    return out


CONVERT = {TEXT: _str, INT: _int, FLOAT: _float, FLAG: _flag, SEED: _seed, HYPER: _hyper,
           TEXTS: lambda v: _list(v, _str), INTS: lambda v: _list(v, _int)}


def as_stored(v):
    """An attribute no table names: texts as str, numpy scalars as int/float, text arrays as
    list[str] (what the reader always returned)."""
    v = _text(v)
    if isinstance(v, np.ndarray) and v.dtype == object:
        return [_text(x) for x in v]
    if isinstance(v, np.generic):
        return v.item()
    return v


def typed(scope, name, value, where):
    """Attribute `name` of the object `where` ("FILE: /datasets/grid") as its declared type in
    `scope`; raises ResultsError (one line) if it is not of that type."""
    t = ATTRIBUTE_TYPES[scope].get(name)
    try:
        return as_stored(value) if t is None else CONVERT[t](value)
    except _Bad as e:
        what = "" if t is None else f" ({_show(value)}; the engine writes {_NAMES[t]})"
        raise ResultsError(_one_line(f"{where}@{name}: {e}{what}")) from None


def typed_attrs(scope, attrs, where, prefix="") -> dict:
    """Every attribute of an h5py AttributeManager, typed: {prefix + name: value}."""
    out = {}
    for k in attrs.keys():
        try:
            v = attrs[k]
        except (OSError, TypeError, ValueError) as e:  # a type h5py cannot read
            raise ResultsError(_one_line(f"{where}@{k}: unreadable ({type(e).__name__}: {e})")) \
                from None
        out[prefix + k] = typed(scope, k, v, where)
    return out


_NAMES = {TEXT: "a text", TEXTS: "a list of texts", INT: "an integer", FLOAT: "a number",
          FLAG: "0 or 1", SEED: "a 64-bit seed", INTS: "a list of integers",
          HYPER: "'key = value' lines"}


def _show(v):
    """A short one-line rendering of a stored value for an error message."""
    if isinstance(v, np.ndarray) and v.dtype == object:
        v = [_text(x) if isinstance(x, bytes) else x for x in v.tolist()]
    elif isinstance(v, np.generic):
        v = v.item()
    s = repr(v).replace("\n", "\\n")
    return s if len(s) <= 60 else s[:57] + "..."


def _one_line(s):
    return s.replace("\r", "\\r").replace("\n", "\\n")
