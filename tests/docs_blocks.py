#!/usr/bin/python3
"""Every shell and Python block of README.md and docs/*.md runs (ctest).

The blocks (```sh and ```python fences) run in the order README.md, then docs/*.md by name, in one
scratch folder that looks like a checkout: configs/, examples/, bench/, python/, results/,
report/ and scripts/ link to the source, build/release to the build. `sirl` on PATH is an
installed copy (`cmake --install BUILD --prefix P`), so a block that says `sirl …` runs the
installed binary and one that says `build/release/app/sirl …` runs the build. Python blocks run
under /usr/bin/python3 with the installed reader on PYTHONPATH.

What the blocks show is run as written except for four rewrites, applied to every block:
- the `quick` profile (15 minutes and more) becomes `smoke` (seconds), everywhere in the block;
- a seed list `seeds=[0,1,…,n−1]` longer than quick's five seeds keeps its number of extra seeds
  on smoke's two (`seeds=[0,1,2,3,4,5]`, quick and one more seed, becomes `seeds=[0,1,2]`);
- an optional part of a synopsis, `[--threads N]`, is left out;
- `...` at the end of a line (more of the same) is left out.

A block that cannot run here says why on the line before its fence:
    <!-- docs-test: skip: needs a Slurm cluster -->
and one that needs a file made first names the command:
    <!-- docs-test: setup: sirl dataset --env grid --out grid.h5 -->
Skipped blocks are listed by file and line in the output; a skip without a reason fails.

The blocks are checked by their exit codes only, so the work folder starts with what the smoke
fixture holds (tests/make_smoke_fixture.py, $SIRL_SMOKE_FIXTURE): out/smoke.h5 with its .sum and
cache, and a copy of smoke's task cache wherever a block runs smoke into another output (SEEDED);
their runs reuse those tasks instead of training smoke again. Without the fixture (run by hand)
the folder starts empty and every block computes.
"""
import os
import re
import shutil
import subprocess
import sys
import tempfile
import time
import tomllib

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import sirl_testing  # noqa: E402

SIRL_BUILD = os.environ["SIRL_BUILD_DIR"]
SRC = os.environ["SIRL_SOURCE_DIR"]
LINKED = ["configs", "examples", "bench", "python", "results", "report", "scripts", "docs"]
# (results file or None, task cache) seeded from the smoke fixture, relative to the work folder:
# README's and docs/running.md's out/smoke.h5; the caches of README's out/q.h5 (docs/running.md's
# my-smoke run shares it), docs/running.md's out/quick.h5 (its `sirl run` and `sirl reproduce`),
# docs/cluster.md's shards, docs/running.md's setup shards, and README's
# `sirl evaluate … --name torch_sirl` (its default output out/smoke+torch_sirl.h5).
SEEDED = [("out/smoke.h5", "out/smoke.h5.tasks"), (None, "out/q.h5.tasks"),
          (None, "out/quick.h5.tasks"),
          (None, "out/c/tasks"), (None, "shard0.h5.tasks"), (None, "shard1.h5.tasks"),
          (None, "out/smoke+torch_sirl.h5.tasks")]
MARK = re.compile(r"<!--\s*docs-test:\s*(skip|setup):\s*(.*?)\s*-->\s*$")


def commands(lang, code):
    """A block's commands without its comments and spacing (a shell comment starts at a # outside
    quotes after a blank), so two blocks that differ only there run once."""
    if lang != "sh":
        return code
    out = []
    for line in code.split("\n"):
        quote, cut = None, len(line)
        for i, c in enumerate(line):
            if quote:
                quote = None if c == quote else quote
            elif c in "'\"":
                quote = c
            elif c == "#" and (i == 0 or line[i - 1] in " \t"):
                cut = i
                break
        line = " ".join(line[:cut].split())
        if line:
            out.append(line)
    return "\n".join(out)


fail = sirl_testing.make_fail("docs_blocks")


def blocks():
    """(page, line, language, code, marks) for every sh/python block, in run order."""
    pages = ["README.md"] + sorted(os.path.join("docs", f) for f in os.listdir(os.path.join(SRC, "docs"))
                                   if f.endswith(".md"))
    out = []
    for page in pages:
        lines = open(os.path.join(SRC, page)).read().split("\n")
        i = 0
        while i < len(lines):
            m = re.fullmatch(r"```(sh|python)\s*", lines[i])
            if not m:
                i += 1
                continue
            marks, j = [], i - 1
            while j >= 0 and MARK.search(lines[j]):
                marks.insert(0, MARK.search(lines[j]).groups())
                j -= 1
            end = lines.index("```", i + 1)
            out.append((page, i + 1, m.group(1), "\n".join(lines[i + 1:end]) + "\n", marks))
            i = end + 1
    return out


def seed_count(profile):
    """How many seeds configs/PROFILE.toml's top-level `seeds` lists."""
    with open(os.path.join(SRC, "configs", profile + ".toml"), "rb") as f:
        return len(tomllib.load(f)["seeds"])


QUICK_SEEDS, SMOKE_SEEDS = seed_count("quick"), seed_count("smoke")


def fewer_seeds(m):
    """`seeds=[0,…,n−1]` with n > QUICK_SEEDS: the same number of seeds beyond smoke's."""
    seeds = [int(x) for x in m.group(1).split(",")]
    n = len(seeds)
    if seeds != list(range(n)) or n <= QUICK_SEEDS:
        return m.group(0)
    return "seeds=[" + ",".join(str(i) for i in range(n - QUICK_SEEDS + SMOKE_SEEDS)) + "]"


def rewrite(code):
    if re.search(r"\bquick\b", code):
        code = re.sub(r"\bseeds=\[([0-9]+(?:,[0-9]+)*)\]", fewer_seeds, code)
    code = re.sub(r"\bquick\b", "smoke", code)
    code = re.sub(r" ?\[[^\]\n]*--[^\]\n]*\]", "", code)       # [--option VALUE …]
    code = re.sub(r" \.\.\.[ \t]*(#.*)?$", r" \1", code, flags=re.M)
    return code


def main():
    found = blocks()
    if len(found) < 10:
        fail(f"only {len(found)} blocks found (the parsing broke)")
    with tempfile.TemporaryDirectory() as tmp:
        prefix = os.path.join(tmp, "prefix")
        p = subprocess.run(["cmake", "--install", SIRL_BUILD, "--prefix", prefix],
                           capture_output=True, text=True)
        if p.returncode:
            fail(f"cmake --install: {p.stderr}")
        work = os.path.join(tmp, "work")
        os.makedirs(os.path.join(work, "build"))
        os.symlink(SIRL_BUILD, os.path.join(work, "build", "release"))
        for d in LINKED:
            os.symlink(os.path.join(SRC, d), os.path.join(work, d))
        if os.environ.get("SIRL_SMOKE_FIXTURE"):  # without it, every block computes
            os.makedirs(os.path.join(work, "out"))
            for h5, cache in SEEDED:
                sirl_testing.copy_fixture("smoke", h5 and os.path.join(work, h5),
                                          with_file=bool(h5), cache_dest=os.path.join(work, cache))
        env = dict(os.environ, PATH=os.path.join(prefix, "bin") + ":" + os.environ["PATH"],
                   PYTHONPATH=os.path.join(prefix, "share", "sirl-bench", "python"),
                   MPLBACKEND="Agg", SIRL_PYTHON="/usr/bin/python3")
        ran, skipped, seen = 0, [], set()
        for page, line, lang, code, marks in found:
            where = f"{page}:{line}"
            skip = [reason for kind, reason in marks if kind == "skip"]
            if skip:
                if not skip[0]:
                    fail(f"{where}: a skip mark must say why")
                skipped.append(f"{where} ({skip[0]})")
                continue
            code = rewrite(code)
            if (lang, commands(lang, code)) in seen:
                print(f"ok: {where}: the same commands as a block above (comments aside)")
                continue
            seen.add((lang, commands(lang, code)))
            for kind, cmd in marks:
                if kind == "setup":
                    s = subprocess.run(["bash", "-euo", "pipefail", "-c", rewrite(cmd)], cwd=work,
                                       env=env, capture_output=True, text=True, timeout=600)
                    if s.returncode:
                        fail(f"{where}: its setup `{cmd}` failed:\n{s.stderr[-1500:]}")
            t0 = time.time()
            argv = (["bash", "-euo", "pipefail", "-c", code] if lang == "sh"
                    else ["/usr/bin/python3", "-c", code])
            r = subprocess.run(argv, cwd=work, env=env, capture_output=True, text=True, timeout=900)
            if r.returncode:
                fail(f"{where}: the {lang} block failed (rc {r.returncode}), as run:\n{code}\n"
                     f"stdout: {r.stdout[-1500:]}\nstderr: {r.stderr[-2500:]}")
            ran += 1
            print(f"ok: {where} ({lang}, {time.time() - t0:.0f} s)")
        print(f"skipped {len(skipped)} block(s), each with its reason:")
        for s in skipped:
            print("  " + s)
        print(f"docs_blocks: OK ({ran} blocks ran)")


if __name__ == "__main__":
    main()
