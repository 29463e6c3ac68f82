#!/usr/bin/python3
"""Every mutant of tests/mutants/mutants.py still applies: its original text occurs exactly once in
its file. A refactor that moves the code a mutant edits otherwise leaves the mutant silently
inapplicable, and the mutation check a step weaker, until someone runs it."""
import os
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
SRC = os.environ.get("SIRL_SOURCE_DIR", os.path.dirname(os.path.dirname(HERE)))
sys.path.insert(0, HERE)
from mutants import MUTANTS  # noqa: E402

bad = []
for n, m in enumerate(MUTANTS, 1):
    path, original = m[0], m[1]
    with open(os.path.join(SRC, path), encoding="utf-8") as f:
        count = f.read().count(original)
    if count != 1:
        bad.append(f"mutant {n} ({path}): its original text occurs {count} times: {original[:70]!r}")
print("\n".join(bad) if bad else f"all {len(MUTANTS)} mutants apply")
sys.exit(1 if bad else 0)
