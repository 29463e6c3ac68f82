#!/usr/bin/python3
"""bench/compare_kernels.py's check of the performance issue's targets, on hand-worked numbers:
each target's measured value as printed, whether it holds (at and above the threshold), and the
GFLOP/s it would take; bf16 and whole-cell targets only when those were measured."""
import os
import sys

sys.path.insert(0, os.path.join(os.environ["SIRL_SOURCE_DIR"], "bench"))
import compare_kernels as ck  # noqa: E402

roof = 200.0
one = {
    "sirl_step_grid": {"ours": 142.0, "torch": 20.0, "bf16": 150.0},  # 71 %; bf16 7.5× PyTorch
    "sirl_step_jaco": {"ours": 150.0, "torch": 75.0, "bf16": 270.0},  # 75 %; bf16 1.8×, 3.6×
    "tpa_heads_grid": {"ours": 100.0, "torch": 50.0},                 # 50 %; 2×
    "tpa_heads_jaco": {"ours": 110.0, "torch": 70.0},                 # 1.5714…×
    "tpa_unfrozen_jaco": {"ours": 100.0, "torch": 60.0},
}
cells = {"tpa_quick_cell_jaco_frozen": {"speedup": 1.6, "torch": 66.0}}
want = [  # (target, measured, holds, GFLOP/s it takes, whose roof applies)
    ("Grid SIRL step ≥ 70 % of the roof", "71 %", True, 140.0, "fp32"),
    ("Jaco SIRL step ≥ 80 % of the roof", "75 %", False, 160.0, "fp32"),
    ("20 Grid TPA heads ≥ 70 % of the roof", "50 %", False, 140.0, "fp32"),
    ("20 Grid TPA heads ≥ 4.5× the best PyTorch form", "2.00× PyTorch", False, 225.0, "fp32"),
    ("frozen Jaco TPA cell step ≥ 2.5× PyTorch", "1.57× PyTorch", False, 175.0, "fp32"),
    ("frozen Jaco TPA cell (whole, M = 100) ≥ 2.5× PyTorch", "1.60× PyTorch", False, 165.0, "fp32"),
    ("Jaco bf16 step ≥ 1.7× our fp32", "1.80× our fp32", True, 255.0, "bf16"),
    ("Jaco bf16 step ≥ 3.5× PyTorch", "3.60× PyTorch", True, 262.5, "bf16"),
    ("Grid bf16 step ≥ 7× PyTorch", "7.50× PyTorch", True, 140.0, "bf16"),
]
got = ck.target_rows(roof, one, cells)
assert len(got) == len(want), got
for g, w in zip(got, want):
    assert g[:3] == w[:3] and g[4] == w[4], (g, w)
    assert abs(g[3] - w[3]) < 1e-9, (g, w)

# Exactly at a threshold holds: 4.5× PyTorch's 50 is 225.
at = {k: dict(v) for k, v in one.items()}
at["tpa_heads_grid"]["ours"] = 225.0
row = [r for r in ck.target_rows(roof, at) if r[0].startswith("20 Grid TPA heads ≥ 4.5×")][0]
assert row[1:3] == ("4.50× PyTorch", True), row

# No bf16 measured and no whole cells: those targets are left out, not failed.
plain = {k: {"ours": v["ours"], "torch": v["torch"]} for k, v in one.items()}
names = [r[0] for r in ck.target_rows(roof, plain, None)]
assert names == [w[0] for w in want[:5]], names
print("compare_kernels targets: ok")
