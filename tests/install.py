#!/usr/bin/python3
"""An installed sirl works without its source folder (ctest):

`cmake --install BUILD --prefix P`, then P is moved elsewhere and, with SIRL_INSTALLED_ONLY=1 (no
falling back to the build's source folder), from an unrelated working folder:
- `sirl run --help` lists the bundled profiles; `sirl reproduce --profile smoke` runs, draws the
  figures and writes the report, with the figure scripts run by the interpreter $SIRL_PYTHON
  names (a wrapper that records it was used); its task cache is a copy of the smoke fixture's
  (tests/make_smoke_fixture.py), so it trains nothing when the fixture is there;
- the installed reader imports from P/share/sirl-bench/python and opens the results file;
- every relative link of the installed README (docs, examples, CHANGELOG, ...) resolves inside
  P/share/sirl-bench, and so does every link between the installed docs pages;
- a missing data folder is one clear line.
"""
import os
import re
import shutil
import subprocess
import sys
import tempfile

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import sirl_testing  # noqa: E402

SIRL_BUILD = os.environ["SIRL_BUILD_DIR"]


fail = sirl_testing.make_fail("install")


def main():
    with tempfile.TemporaryDirectory() as tmp:
        prefix = os.path.join(tmp, "prefix")
        p = subprocess.run(["cmake", "--install", SIRL_BUILD, "--prefix", prefix],
                           capture_output=True, text=True)
        if p.returncode:
            fail(f"cmake --install: {p.stderr}")
        moved = os.path.join(tmp, "elsewhere", "sirl")
        os.makedirs(os.path.dirname(moved))
        shutil.move(prefix, moved)
        sirl = os.path.join(moved, "bin", "sirl")
        log = os.path.join(tmp, "python-used")
        wrapper = os.path.join(tmp, "python")
        open(wrapper, "w").write(f"#!/bin/sh\necho used >> {log}\nexec /usr/bin/python3 \"$@\"\n")
        os.chmod(wrapper, 0o755)
        env = dict(os.environ, SIRL_INSTALLED_ONLY="1", SIRL_PYTHON=wrapper)
        env.pop("SIRL_DATA_DIR", None)
        work = os.path.join(tmp, "work")
        os.makedirs(work)

        share = os.path.join(moved, "share", "sirl-bench")
        pages = [os.path.join(share, "README.md")] + [
            os.path.join(share, "docs", f) for f in sorted(os.listdir(os.path.join(share, "docs")))
            if f.endswith(".md")]
        checked, dead = 0, []
        for page in pages:
            # Links only: not code blocks or inline code (a C++ lambda reads like a link).
            text = re.sub(r"```.*?```", "", open(page).read(), flags=re.S)
            text = re.sub(r"`[^`\n]*`", "", text)
            for target in re.findall(r"\]\(([^)#\s]+)", text):
                if target.startswith(("http://", "https://", "mailto:")):
                    continue
                resolved = os.path.normpath(os.path.join(os.path.dirname(page), target))
                if page.endswith("README.md") or resolved.startswith(os.path.join(share, "docs")):
                    checked += 1
                    if not os.path.exists(resolved):
                        dead.append(f"{os.path.relpath(page, share)} -> {target}")
        if dead or checked < 30:
            fail(f"{len(dead)} of {checked} installed links are dead: {dead[:10]}")
        print(f"ok: all {checked} links of the installed README and between its docs resolve")

        h = subprocess.run([sirl, "run", "--help"], capture_output=True, text=True, env=env, cwd=work)
        if "quick" not in h.stdout or "smoke" not in h.stdout:
            fail(f"`sirl run --help` does not list the bundled profiles:\n{h.stdout[:800]}")
        out = os.path.join(work, "smoke.h5")
        # The smoke fixture's task cache as the run's (OUT.tasks): the installed binary plans,
        # writes the results file and draws from it without training again.
        sirl_testing.copy_fixture("smoke", out, with_file=False)
        r = subprocess.run([sirl, "reproduce", "--profile", "smoke", "--out", out, "--figures",
                            os.path.join(work, "figs"), "--no-study"],
                           capture_output=True, text=True, env=env, cwd=work, timeout=900)
        if r.returncode:
            fail(f"installed sirl reproduce: rc {r.returncode}\n{r.stderr[-2000:]}")
        for f in ("report.md", "fig4_fpe.png", "fig5_tpa.png"):
            if not os.path.exists(os.path.join(work, "figs", f)):
                fail(f"the installed run drew no {f}")
        if not os.path.exists(log):
            fail("the figure scripts did not run under $SIRL_PYTHON")
        print("ok: the installed, moved sirl ran smoke and drew its figures with $SIRL_PYTHON")

        code = (f"import sirl_bench; assert sirl_bench.__file__.startswith({moved!r}), "
                f"sirl_bench.__file__; print(len(sirl_bench.open({out!r}).tables['tpa']))")
        site = os.path.join(moved, "lib", "python%d.%d" % sys.version_info[:2], "dist-packages")
        for path in (os.path.join(moved, "share", "sirl-bench", "python"), site):
            # -s and an empty HOME: no user site-packages, no .pth file of a checkout.
            p = subprocess.run(["/usr/bin/python3", "-s", "-c", code], capture_output=True,
                               text=True, cwd=work,
                               env=dict(os.environ, PYTHONPATH=path, HOME=work))
            if p.returncode or int(p.stdout) < 1:
                fail(f"the installed reader from {path}: {p.stderr}")
        print("ok: the installed reader (PREFIX/lib/python3.X/dist-packages, and the share folder) "
              "opens the results file with nothing in the home folder")

        shutil.rmtree(os.path.join(moved, "share"))
        p = subprocess.run([sirl, "reproduce", "--profile", "smoke", "--out", out], capture_output=True,
                           text=True, env=env, cwd=work)
        if p.returncode == 0 or "SIRL_DATA_DIR" not in p.stderr or p.stderr.count("\n") != 1:
            fail(f"without its data folder: rc {p.returncode}, {p.stderr!r}")
        print("ok: without its data folder, one line saying what to set")
    print("install: OK")


if __name__ == "__main__":
    main()
