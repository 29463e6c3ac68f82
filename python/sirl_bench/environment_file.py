"""Writes an environment file: your own trajectories and true features, which a profile declares
as [environments.<name>] and sirl-bench then runs every method, metric and figure on
(docs/environment-files.md).

    xxh3 = sirl_bench.write_environment("mine.h5", inputs, features,
                                        names=["height", "speed"], name="mine")
    # profile:  envs = ["mine"]
    #           [environments.mine]
    #           file = "mine.h5"
    #           xxh3 = "<xxh3>"

The layout is the one `sirl dataset` exports (/datasets/<name>/inputs, features_raw with
@feature_names and @units, and optionally points), so an exported built-in environment is an
environment file too. The engine checks the file again when it reads it.
"""
import os
import re

import numpy as np

from .errors import ResultsError
from .untrusted import _xxh3_128

_NAME = re.compile(r"[a-z0-9_]{1,32}")


def write_environment(path, inputs, features, names, name="env", units=None, points=None,
                      description=None) -> str:
    """Writes `path` and returns its XXH3-128 (the `xxh3` a profile names it by).

    inputs   [T, D]: what the networks see of each trajectory (float32).
    features [T, F]: the true features in their own units; the engine normalises each to [0, 1]
             over the T trajectories, as it does its own, and the simulated humans answer from
             them.
    names    F feature names; units: F unit strings (optional).
    points   [T, L, 2 or 3] (optional): what a figure draws of each trajectory.
    Raises ResultsError (one line) for shapes that disagree, NaN or ±Inf, a feature that is the
    same for every trajectory, fewer than 3 trajectories or a malformed name."""
    if not _NAME.fullmatch(str(name)):
        raise ResultsError(f"name {name!r}: 1-32 characters of a-z, 0-9 or _")
    x = np.asarray(inputs, dtype=np.float32)
    phi = np.asarray(features, dtype=np.float32)
    if x.ndim != 2 or x.shape[1] < 1:
        raise ResultsError(f"inputs: [T, D] expected, got shape {x.shape}")
    if phi.ndim != 2 or phi.shape[1] < 1:
        raise ResultsError(f"features: [T, F] expected, got shape {phi.shape}")
    T, F = x.shape[0], phi.shape[1]
    if phi.shape[0] != T:
        raise ResultsError(f"features have {phi.shape[0]} rows, inputs {T}")
    if T < 3:
        raise ResultsError(f"{T} trajectories: a similarity query needs at least 3")
    names = [str(n) for n in names]
    if len(names) != F or len(set(names)) != F or not all(0 < len(n) <= 64 for n in names):
        raise ResultsError(f"names: {F} distinct names of 1-64 characters expected, got {names}")
    units = [""] * F if units is None else [str(u) for u in units]
    if len(units) != F:
        raise ResultsError(f"units: {F} expected, got {len(units)}")
    for what, a in (("inputs", x), ("features", phi)):
        if not np.isfinite(a).all():
            raise ResultsError(f"{what}: holds NaN or ±Inf (row {int(np.argwhere(~np.isfinite(a))[0][0])})")
    same = [names[k] for k in range(F) if phi[:, k].min() == phi[:, k].max()]
    if same:
        raise ResultsError(f"feature {same[0]!r} is the same for every trajectory: the simulated "
                           "humans could not tell any two apart by it")
    pts = None
    if points is not None:
        pts = np.asarray(points, dtype=np.float32)
        if pts.ndim != 3 or pts.shape[0] != T or pts.shape[2] not in (2, 3) or pts.shape[1] < 1:
            raise ResultsError(f"points: [T, L, 2 or 3] with T = {T} expected, got {pts.shape}")
        if not np.isfinite(pts).all():
            raise ResultsError("points: holds NaN or ±Inf")
    import h5py
    tmp = f"{path}.partial"
    g = f"datasets/{name}"
    with h5py.File(tmp, "w") as f:
        d = f.create_dataset(f"{g}/inputs", data=x)
        d.attrs["description"] = "inputs written by sirl_bench.write_environment"
        d = f.create_dataset(f"{g}/features_raw", data=phi)
        d.attrs["feature_names"] = names
        d.attrs["units"] = units
        if pts is not None:
            f.create_dataset(f"{g}/points", data=pts)
        if description:
            f[g].attrs["description"] = str(description)
    os.replace(tmp, path)
    return _xxh3_128(path)
