#!/usr/bin/python3
"""ctest: `sirl dataset` output loads with plain h5py exactly as docs/results-file.md shows."""
import os
import subprocess
import tempfile

import h5py
import numpy as np

with tempfile.TemporaryDirectory() as d:
    path = os.path.join(d, "grid.h5")
    subprocess.run([os.environ["SIRL"], "dataset", "--env", "grid", "--out", path], check=True)
    # --- the snippet of docs/results-file.md ---
    with h5py.File(path, "r") as f:
        g = f["datasets/grid"]
        X = g["inputs"][:]                 # [1960, 19] float32
        phi = g["features"][:]             # [1960, 4] normalised true features
        names = list(g["features"].attrs["feature_names"])
        trip = g["queries/similarity"][:]  # [N, 3] (positive 1, positive 2, negative)
    # ---
    assert X.shape == (1960, 19) and X.dtype == np.float32, (X.shape, X.dtype)
    assert phi.shape == (1960, 4) and abs(phi.min()) < 1e-7 and abs(phi.max() - 1) < 1e-7
    assert [str(n) for n in names] == ["obstacle1_distance", "obstacle2_distance", "laptop_distance", "abs_angle"], names
    # every stored answer is the perfect oracle's: the positives are the closest pair
    d12 = ((phi[trip[:, 0]] - phi[trip[:, 1]]) ** 2).sum(1)
    assert (d12 <= ((phi[trip[:, 0]] - phi[trip[:, 2]]) ** 2).sum(1) + 1e-6).all()
    assert (d12 <= ((phi[trip[:, 1]] - phi[trip[:, 2]]) ** 2).sum(1) + 1e-6).all()
print("ok")
