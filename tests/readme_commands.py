#!/usr/bin/python3
"""README.md says only what is true (ctest):

- every repository path it names (links, `configs/…`, `scripts/…`, `python/`, `examples/…`, …)
  exists;
- every `sirl COMMAND …` it shows names a command that exists, and every `--option` of it is one
  that command's --help lists;
(tests/docs_blocks.py runs its shell and Python blocks).
"""
import os
import re
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import sirl_testing  # noqa: E402
from sirl_testing import run_sirl  # noqa: E402

SRC = sirl_testing.source_dir()
README = open(os.path.join(SRC, "README.md")).read()
fail = sirl_testing.make_fail("readme_commands")


def help_text(*cmd):
    return run_sirl(*cmd, "--help", stdin=None, timeout=60).stdout


def main():
    # Paths: link targets, and words in backticks that look like repository paths.
    paths = set(re.findall(r"\]\(([^)#\s]+)", README))
    paths |= {p for p in re.findall(r"`([\w./-]+)`", README)
              if "/" in p and not p.startswith(("out/", "/", "http")) and "<" not in p
              and not p.startswith("build/")}
    missing = [p for p in sorted(paths) if not p.startswith("http")
               and not os.path.exists(os.path.join(SRC, p.rstrip("/")))]
    if missing:
        fail(f"README names paths that do not exist: {missing}")
    print(f"ok: {len(paths)} paths README names exist")

    # sirl commands and their options.
    commands = set(re.findall(r"`?sirl ([a-z]+)\b", README))
    known = set(re.findall(r"^ {2}([a-z]+) {2,}\S", help_text(), re.M))  # "  NAME  one line"
    checked = 0
    for line in re.findall(r"`(sirl [^`]+)`", README) + re.findall(r"^\s*(?:build/release/app/)?(sirl .+)$", README, re.M):
        words = line.split()
        cmd = words[1]
        if not re.fullmatch(r"[a-z]+", cmd):
            continue  # a placeholder: `sirl COMMAND --help`
        if cmd not in known:
            fail(f"README shows `{line}`, but `sirl {cmd}` is not a command ({sorted(known)})")
        sub = [cmd]
        if len(words) > 2 and not words[2].startswith("-") and re.fullmatch(r"[a-z]+", words[2]) \
                and words[2] in help_text(cmd).split("Subcommands:")[-1]:
            sub.append(words[2])
        h = help_text(*sub)
        for opt in re.findall(r"(--[a-z][a-z-]*)", line):
            if opt not in h:
                fail(f"README shows `{line}`: {opt} is not an option of `sirl {' '.join(sub)}`")
            checked += 1
    if not commands:
        fail("no sirl command found in README (the parsing broke)")
    print(f"ok: {len(commands)} sirl commands and {checked} of their options exist")

    # `sirl --version` (README's command table lists it): exit 0, one line, `sirl version`'s
    # version and commit.
    v = run_sirl("--version", stdin=None, timeout=60)
    full = run_sirl("version", stdin=None, timeout=120).stdout
    commit = re.search(r"^commit:\s+(\S+)", full, re.M).group(1)
    if v.returncode or v.stdout.count("\n") != 1 or not v.stdout.startswith(full.split("\n")[0]) \
            or commit not in v.stdout:
        fail(f"sirl --version: rc {v.returncode}, {v.stdout!r} {v.stderr!r} (sirl version: {full[:200]!r})")
    print(f"ok: sirl --version prints {v.stdout.strip()!r}")
    print("readme_commands: OK")


if __name__ == "__main__":
    main()
