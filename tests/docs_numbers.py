#!/usr/bin/python3
"""What the docs state about the engine's own plans and profiles, recomputed: the tasks an
external method adds to quick (docs/external-methods.md, from `sirl plan --tasks`), and the
profile table of docs/running.md against configs/. A change that makes a sentence stale fails
here, not in a reader's hands."""
import os
import re
import sys
import tempfile

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import sirl_testing  # noqa: E402

SRC = sirl_testing.source_dir()
PY = "/usr/bin/python3"


def tasks(profile):
    p = sirl_testing.run_sirl("plan", profile, "--tasks", timeout=300)
    if p.returncode != 0:
        sys.exit(f"FAIL: sirl plan {profile} --tasks: {p.stderr}")
    return [line.split()[0] for line in p.stdout.splitlines() if line.strip()]


def main():
    text = open(os.path.join(SRC, "docs", "external-methods.md")).read()
    m = re.search(r"on quick, its (\d+) tasks\s.*?instead of (\d+)\.", text, re.S)
    if not m:
        sys.exit("FAIL: docs/external-methods.md no longer states quick's external-method tasks")
    own, total = int(m.group(1)), int(m.group(2))
    with tempfile.TemporaryDirectory() as tmp:
        emb = os.path.join(tmp, "e.h5")
        with open(emb, "wb") as f:
            f.write(b"any bytes: planning reads only the digest")
        import xxhash
        digest = xxhash.xxh3_128_hexdigest(open(emb, "rb").read())
        prof = os.path.join(tmp, "p.toml")
        with open(prof, "w") as f:
            f.write(f'extends = "{os.path.join(SRC, "configs", "quick.toml")}"\n'
                    f'[external.mine]\nembeddings = "e.h5"\nxxh3 = "{digest}"\n')
        keys = tasks(prof)
    got_own = sum("/mine/" in k for k in keys)
    if (got_own, len(keys)) != (own, total):
        sys.exit(f"FAIL: docs/external-methods.md says {own} of {total} tasks; the plan has "
                 f"{got_own} of {len(keys)}")
    print(f"ok: an external method adds {own} of quick's {total} tasks, as the docs say")
    # docs/running.md's profile table lists every shipped profile.
    running = open(os.path.join(SRC, "docs", "running.md")).read()
    listed = set(re.findall(r"^\| `([\w-]+)\.toml` \|", running, re.M))
    shipped = {f[:-5] for f in os.listdir(os.path.join(SRC, "configs")) if f.endswith(".toml")}
    if listed != shipped:
        sys.exit(f"FAIL: docs/running.md's profile table lists {sorted(listed)}; configs/ has "
                 f"{sorted(shipped)}")
    print(f"ok: docs/running.md lists all {len(shipped)} profiles")
    # The BibTeX names the version CITATION.cff does.
    cff = re.search(r"^version: (\S+)", open(os.path.join(SRC, "CITATION.cff")).read(), re.M)[1]
    bib = re.search(r"version = \{([^}]+)\}", open(os.path.join(SRC, "docs", "citing.md")).read())[1]
    if bib != cff:
        sys.exit(f"FAIL: docs/citing.md cites version {bib}, CITATION.cff {cff}")
    print(f"ok: docs/citing.md cites version {bib}, as CITATION.cff")
    init = open(os.path.join(SRC, "python", "sirl_bench", "__init__.py")).read()
    reader = re.search(r'^__version__ = "([^"]+)"', init, re.M)[1]
    if reader != cff:
        sys.exit(f"FAIL: the reader says version {reader}, CITATION.cff {cff}")
    print(f"ok: the reader's version is {reader}")
    print("PASS")


if __name__ == "__main__":
    main()
