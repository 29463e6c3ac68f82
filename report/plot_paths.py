"""The top-down view of an environment's trajectories, for the environments whose file stores what
a figure draws of each trajectory (/datasets/<env>/points, [T, L, 2]):

  fig_paths_<env>  one panel per true feature (the first four of features_raw), each showing the
                   same first 40 trajectories of Ξ as lines of their points, coloured by that
                   feature's raw value (its name and unit on the colour bar); equal aspect.

Environments without points (GridRobot, JacoRobot: drawn elsewhere) or with 3-D points draw
nothing here. Imported by plot_figures.py; what it drew goes to figures.json (fig_paths).
"""
import matplotlib.pyplot as plt
import numpy as np
from matplotlib.collections import LineCollection

import figures  # its save(); matplotlib set up as for every figure (Agg, labels as plain text)

SHOWN = 40   # trajectories drawn, the first of Ξ (all when it holds fewer)
PANELS = 4   # true features drawn at most, one panel each


def feature_label(names, units, k):
    """Feature k's name, with its unit in brackets when the file gives one."""
    name = names[k] if k < len(names) else f"feature {k}"
    unit = units[k].strip() if k < len(units) else ""
    return f"{name} [{unit}]" if unit else name


def drawable(g):
    """An environment's group has 2-D points ([T, L, 2], T > 0) and the raw features of the same
    T trajectories ([T, F], F > 0) to colour them."""
    if "points" not in g or "features_raw" not in g:
        return False
    p, f = np.shape(g["points"]), np.shape(g["features_raw"])
    return len(p) == 3 and p[2] == 2 and p[0] > 0 and len(f) == 2 and f[0] == p[0] and f[1] > 0


def plot_env(g, env, out):
    """fig_paths_<env>: the first SHOWN trajectories' points, one panel per true feature (at most
    PANELS), coloured by its raw value; returns what was drawn (figures.json's entry)."""
    a = g["attrs"]
    n = min(SHOWN, len(g["points"]))
    pts = np.asarray(g["points"][:n], dtype=float)
    raw = np.asarray(g["features_raw"][:n], dtype=float)
    names = list(a.get("features_raw.feature_names", []))
    units = list(a.get("features_raw.units", []))
    labels = [feature_label(names, units, k) for k in range(min(PANELS, raw.shape[1]))]
    xy = pts.reshape(-1, 2)
    xy = xy[np.isfinite(xy).all(axis=1)]
    span = np.ptp(xy, axis=0) if len(xy) else np.ones(2)
    tall = float(np.clip(span[1] / max(span[0], 1e-12), 0.25, 4.0))  # the data's height / width
    w, h = (4.5 / tall, 4.5) if tall >= 1 else (4.0, 4.0 * tall)  # a panel's plot, inches
    fig, axs = plt.subplots(1, len(labels), figsize=(len(labels) * (w + 1.3), h + 0.9),
                            squeeze=False, constrained_layout=True)
    for k, (ax, label) in enumerate(zip(axs[0], labels)):
        v = raw[:, k]
        order = np.argsort(v, kind="stable")  # the highest values drawn last, on top
        lines = LineCollection(pts[order], cmap="viridis", linewidths=1.1, alpha=0.9)
        lines.set_array(v[order])
        ax.add_collection(lines)
        bar = fig.colorbar(lines, ax=ax, shrink=0.85)
        bar.set_label(label, fontsize=8)
        bar.ax.tick_params(labelsize=7)
        ax.set_title(names[k] if k < len(names) else label, fontsize=10)
        ax.set_aspect("equal", adjustable="datalim")  # the panel filled, the scale 1:1
        ax.grid(alpha=0.3)
        ax.tick_params(labelsize=7)
        ax.autoscale_view()
    fig.suptitle(f"{a.get('title', env)} — {n} trajectories coloured by each true feature",
                 fontsize=11)
    figures.save(fig, out, f"fig_paths_{env}")
    return {"file": f"fig_paths_{env}", "trajectories": n, "features": labels}


def plot_paths(datasets, out, drawn):
    """fig_paths_<env>.{png,pdf} for every environment of `datasets` ({env: group}, as
    Results.datasets) whose points are 2-D, in drawn["fig_paths"]; returns those environments."""
    envs = [e for e in datasets if drawable(datasets[e])]
    for env in envs:
        drawn.setdefault("fig_paths", {})[env] = plot_env(datasets[env], env, out)
    return envs
