#!/usr/bin/python3
"""`sirl reproduce` says what `sirl plan` predicts before a run of a profile with a budget
(budget_minutes), warns naming the smallest profile when the prediction is well over it, says
nothing of the kind for a profile without one, and draws its figures beside the results file
(--out DIR/x.h5 → DIR/x-figures/, not ./out/).
"""
import os
import re
import sys
import tempfile

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import sirl_testing  # noqa: E402
from sirl_testing import run_sirl  # noqa: E402

SRC = sirl_testing.source_dir()
SMOKE = os.path.join(SRC, "configs", "smoke.toml")
fail = sirl_testing.make_fail("reproduce_prediction")


def main():
    with tempfile.TemporaryDirectory() as tmp:
        tight = os.path.join(tmp, "tight.toml")
        with open(tight, "w") as f:  # smoke with a budget of 0.06 s: any machine is over it
            f.write(f'extends = "{SMOKE}"\nname = "tight"\nbudget_minutes = 0.001\n')
        out = os.path.join(tmp, "res", "tight.h5")
        p = run_sirl("reproduce", "--profile", tight, "--out", out, "--no-study", "--threads", "2",
                     cwd=tmp, timeout=900)
        if p.returncode != 0:
            fail(f"reproduce exited {p.returncode}:\n{p.stderr[-2000:]}")
        m = re.search(r"tight is predicted to take (\S+) on 2 thread\(s\) here", p.stderr)
        if not m:
            fail(f"no prediction before the run:\n{p.stderr[:2000]}")
        if "warning: that is" not in p.stderr or "--profile smoke" not in p.stderr:
            fail(f"no warning for a run far over its budget:\n{p.stderr[:2000]}")
        if p.stderr.index("predicted to take") > p.stderr.index("sirl run:"):
            fail("the prediction came after the run started")
        figs = os.path.join(tmp, "res", "tight-figures")
        if not os.path.exists(os.path.join(figs, "report.md")):
            fail(f"the figures are not beside the results file: {os.listdir(tmp)}")
        if os.path.exists(os.path.join(tmp, "out")):
            fail("reproduce --out wrote into ./out/")
        print(f"ok: predicted {m.group(1)}, warned (over a 0.06 s budget); figures beside --out")
        # The report's verdicts are kept in the results file: the reader gives the report's
        # claims.json row for row, and `sirl show` finds them with the figures folder gone.
        sys.path.insert(0, os.path.join(SRC, "python"))
        import json
        import sirl_bench
        with open(os.path.join(figs, "claims.json")) as fh:
            written = json.load(fh)
        stored = sirl_bench.claims(out)
        if stored[["env", "claim", "protocol", "verdict"]].to_dict("records") != [
                {k: h[k] for k in ("env", "claim", "protocol", "verdict")} for h in written]:
            fail(f"the stored verdicts differ from the report's:\n{stored}")
        os.rename(figs, figs + ".moved")
        shown = json.loads(run_sirl("show", out, "--json", stdin=None, check=True).stdout)
        if shown.get("verdicts_from") != out + " (/verdicts)" or [
                v["verdict"] for v in shown["verdicts"]] != [
                h["verdict"] for h in written if h["main"]]:
            fail(f"sirl show did not read the verdicts stored in the file: {shown}")
        print(f"ok: {len(written)} verdicts stored in the results file; the reader and sirl show "
              "read them without the figures folder")
        p = run_sirl("reproduce", "--profile", SMOKE, "--out", os.path.join(tmp, "smoke.h5"),
                     "--no-study", cwd=tmp, timeout=900)
        if p.returncode != 0 or "predicted to take" in p.stderr:
            fail(f"smoke (no budget): rc {p.returncode}, or it calibrated:\n{p.stderr[:1000]}")
        print("ok: a profile without a budget starts at once")
    print("reproduce_prediction: OK")


if __name__ == "__main__":
    main()
