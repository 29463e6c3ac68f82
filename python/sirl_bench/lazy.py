"""/datasets of a sirl-bench file, read on demand: its attributes without its arrays.

A group reads like the nested dict the reader always returned ({"attrs": {...}, "inputs": Ξ,
"queries": {...}, ...}), but an array is read from the file the first time it is asked for
(then kept), so reading a few attributes of a 65 MB file reads none of its arrays. Iterating a
group, `len` and `in` read nothing; `values()`, `items()` and `to_dict()` read every array below.
The arrays are read from the open file: read them before the file is closed (Results.close(), or
the end of a `with sirl_bench.datasets(...)` block), or take `to_dict()` first.
"""
from __future__ import annotations

from collections.abc import Mapping

import h5py

from .attributes import typed_attrs
from .errors import ResultsError


class Group(Mapping):
    """One HDF5 group read on demand: "attrs" (the group's attributes plus each array's own as
    "<array>.<attribute>", e.g. "features.feature_names", typed by attributes.ATTRIBUTE_TYPES),
    each array as a numpy array, each subgroup as a Group."""

    def __init__(self, g, scope, path, file):
        self._g = g
        self._scope = scope
        self._path = path
        # The h5py.File, held so that the file stays open while this group is in use (and
        # nothing else: no reference cycle, so the file closes when the last group is dropped).
        self._file = file
        self._name = g.name
        self._names = list(g.keys())
        self._cache = {}

    def _check_open(self):
        if not self._g.id.valid:
            raise ResultsError(f"{self._path}: closed before {self._name} was read (read its "
                               "arrays while the file is open, or take .to_dict() first)")

    def _attrs(self):
        self._check_open()
        where = f"{self._path}: {self._name}"
        out = typed_attrs(self._scope, self._g.attrs, where)
        for name in self._names:
            o = self._g[name]
            if isinstance(o, h5py.Dataset):
                out.update(typed_attrs(self._scope, o.attrs, f"{self._path}: {o.name}",
                                       prefix=name + "."))
        return out

    def __getitem__(self, key):
        if key in self._cache:
            return self._cache[key]
        if key == "attrs":
            value = self._attrs()
        elif key in self._names:
            self._check_open()
            o = self._g[key]
            if isinstance(o, h5py.Group):
                value = Group(o, self._scope, self._path, self._file)
            else:
                try:
                    value = o[()]
                except (OSError, ValueError, TypeError) as e:
                    msg = str(e).replace("\n", " ")
                    raise ResultsError(f"{self._path}: cannot read {o.name} ({msg})") from None
        else:
            raise KeyError(key)
        self._cache[key] = value
        return value

    def __contains__(self, key):
        return key == "attrs" or key in self._names

    def __iter__(self):
        return iter(["attrs"] + self._names)

    def __len__(self):
        return 1 + len(self._names)

    def to_dict(self) -> dict:
        """The group and everything below it read now, as plain nested dicts."""
        return {k: v.to_dict() if isinstance(v, Group) else v for k, v in self.items()}

    def __repr__(self):
        read = [k for k in self._names if k in self._cache]
        return (f"<sirl_bench group {self._name} of {self._path}: attrs, "
                f"{', '.join(self._names)} ({len(read)} of {len(self._names)} read)>")


class Datasets(Mapping):
    """{env: Group} of a file's /datasets; `provenance` is the file's root attributes (typed).
    A context manager: the file closes at the end of the `with` block (or on close())."""

    def __init__(self, f, path, owns_file):
        self._f = f
        self.path = str(path)
        self._owns = owns_file
        self._envs = list(f["datasets"].keys()) if "datasets" in f else []
        self._cache = {}

    def __getitem__(self, env):
        if env not in self._cache:
            if env not in self._envs:
                raise KeyError(env)
            if not self._f.id.valid:
                raise ResultsError(f"{self.path}: closed before /datasets/{env} was read")
            self._cache[env] = Group(self._f["datasets/" + env], "datasets", self.path, self._f)
        return self._cache[env]

    def __contains__(self, env):
        return env in self._envs

    def __iter__(self):
        return iter(self._envs)

    def __len__(self):
        return len(self._envs)

    @property
    def provenance(self) -> dict:
        """The file's root attributes: engine_version, git_commit, and for `sirl dataset
        --profile` profile_name and profile_text."""
        return typed_attrs("provenance", self._f.attrs, f"{self.path}: /")

    def to_dict(self) -> dict:
        """Every environment read now, as plain nested dicts (what datasets() returned before it
        read on demand)."""
        return {env: self[env].to_dict() for env in self._envs}

    def close(self):
        if self._owns:
            self._f.close()

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()

    def __repr__(self):
        return f"<sirl_bench datasets of {self.path}: {', '.join(self._envs)}>"
