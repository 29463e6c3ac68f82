#!/usr/bin/python3
"""README.md says only what is true (ctest):

- every repository path it names (links, `configs/…`, `scripts/…`, `python/`, `examples/…`, …)
  exists;
- every `sirl COMMAND …` it shows names a command that exists, and every `--option` of it is one
  that command's --help lists;
- its Python snippet runs on a results file the CLI writes (the smoke profile standing in for
  quick: the path is swapped, and N = 1000 for the smoke profile's largest N).
"""
import os
import re
import subprocess
import sys
import tempfile

SIRL = os.environ["SIRL"]
SRC = os.environ["SIRL_SOURCE_DIR"]
README = open(os.path.join(SRC, "README.md")).read()


def fail(msg):
    print("readme_commands: FAIL:", msg)
    sys.exit(1)


def help_text(*cmd):
    return subprocess.run([SIRL, *cmd, "--help"], capture_output=True, text=True, timeout=60).stdout


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
    known = set(re.findall(r"^\s{2}(\w+)\s", help_text().split("Subcommands:")[1], re.M))
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

    # The Python snippet, on the smoke profile's results file.
    snippets = re.findall(r"```python\n(.*?)```", README, re.S)
    if not snippets:
        fail("README has no Python snippet")
    with tempfile.TemporaryDirectory() as tmp:
        smoke = os.path.join(tmp, "smoke.h5")
        subprocess.run([SIRL, "run", "smoke", "--out", smoke, "--threads", "2", "--quiet"],
                       check=True)
        for code in snippets:
            code = code.replace("out/quick.h5", smoke).replace("N == 1000", "N == 200")
            p = subprocess.run(["/usr/bin/python3", "-c", "import matplotlib; matplotlib.use('Agg')\n"
                                + code], cwd=tmp, capture_output=True, text=True, timeout=300,
                               env=dict(os.environ, PYTHONPATH=os.path.join(SRC, "python")))
            if p.returncode:
                fail(f"README's Python snippet failed:\n{code}\n{p.stderr[-2000:]}")
        if not os.path.exists(os.path.join(tmp, "fig5.png")):
            fail("README's snippet did not write fig5.png")
    print(f"ok: README's {len(snippets)} Python snippet(s) run on the smoke file")
    print("readme_commands: OK")


if __name__ == "__main__":
    main()
