#!/usr/bin/python3
"""Draws a few JacoRobot end-effector paths over the table with the laptop and the human, from a
file written by `sirl dataset --env jaco` (or a results file): a sanity check for people.

    /usr/bin/python3 report/render_jaco.py FILE.h5 --out traj.png [--ids 0,1,2] [--env jaco]
"""
import argparse
import os
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

# The reader package: installed by scripts/setup.sh, or beside this folder in a checkout.
sys.path.insert(1, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "python"))
import sirl_bench  # noqa: E402
from safe_output import save_figure  # noqa: E402

ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
ap.add_argument("file")
ap.add_argument("--out", required=True)
ap.add_argument("--ids", default="0,1,2,3,4,5", help="comma-separated trajectory rows")
ap.add_argument("--env", default="jaco", help="an environment with an arm view (sirl render checks)")
a = ap.parse_args()

try:
    g = sirl_bench.datasets(a.file)[a.env]
except sirl_bench.ResultsError as e:
    sys.exit(f"render_jaco: {e}")
except KeyError:
    sys.exit(f"render_jaco: {a.file}: no /datasets/{a.env}")
X = g["inputs"]
T = X.shape[0]
try:
    ids = [int(i) for i in a.ids.split(",") if i.strip()]
except ValueError:
    sys.exit(f"render_jaco: --ids must be comma-separated integers, got {a.ids!r}")
bad = [i for i in ids if not 0 <= i < T]
if bad:
    sys.exit(f"render_jaco: --ids {bad} outside [0, {T})")
objects = g["objects"]
names = list(g["attrs"]["objects.names"])

fig = plt.figure(figsize=(11, 5))
ax = fig.add_subplot(1, 2, 1, projection="3d")
top = fig.add_subplot(1, 2, 2)
xx, yy = np.meshgrid(np.linspace(-1, 1, 2), np.linspace(-1.4, 0.6, 2))
ax.plot_surface(xx, yy, 0 * xx, color="tan", alpha=0.25)
colours = plt.cm.tab10(np.linspace(0, 1, 10))
for c, i in enumerate(ids):
    s = X[i].reshape(-1, 97)
    frames = s[:, 70:91].reshape(-1, 7, 3)
    ee = frames[:, 6]
    col = colours[c % 10]
    ax.plot(ee[:, 0], ee[:, 1], ee[:, 2], "-o", ms=2, color=col, label=f"ξ{i}")
    arm = np.vstack([[0, 0, 0], frames[0]])  # the arm at the start state
    ax.plot(arm[:, 0], arm[:, 1], arm[:, 2], "-", color=col, alpha=0.35, lw=3)
    top.plot(ee[:, 0], ee[:, 1], "-o", ms=2, color=col)
for (x, y, z), n in zip(objects, names):
    if n == "laptop":
        ax.scatter([x], [y], [z], marker="s", s=120, c="black")
        top.add_patch(plt.Circle((x, y), 0.3, color="black", alpha=0.15))
        top.scatter([x], [y], marker="s", c="black")
        top.annotate("laptop (0.3 m)", (x, y), fontsize=8)
    else:
        ax.plot([x, x], [y, y], [0, z + 0.2], color="peru", lw=8, alpha=0.7)
        top.add_patch(matplotlib.patches.Ellipse((x, y), 0.6, 1.8, color="peru", alpha=0.2))
        top.scatter([x], [y], marker="o", c="peru")
        top.annotate("human (proxemics)", (x, y), fontsize=8)
ax.scatter([0], [0], [0], marker="^", c="red", s=60)
ax.set_xlabel("x (m)")
ax.set_ylabel("y (m)")
ax.set_zlabel("z (m)")
ax.set_title("end-effector paths (arm drawn at the start)", fontsize=9)
ax.legend(fontsize=7, loc="upper left")
top.set_aspect("equal")
top.set_xlabel("x (m)")
top.set_ylabel("y (m)")
top.set_title("top view: laptop and human zones", fontsize=9)
top.grid(alpha=0.3)
fig.suptitle(f"JacoRobot ({a.env}): {len(ids)} of {T} trajectories from {a.file}", fontsize=10)
save_figure(fig, a.out, dpi=130, bbox_inches="tight")
print(f"render_jaco: wrote {a.out}")
