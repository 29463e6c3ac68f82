#!/usr/bin/python3
"""Numbers are decimal, everywhere (ctest): every integer and real option of every `sirl`
command, found from its --help, refuses "010", "0x10", "+3", " 3", "nan" (and integers also
"inf", "1e3", "30.0"; reals "inf" unless their help says inf means something) with exit code 2
and one line naming the option and the value; profile hyper-parameters refuse a value of the
wrong TOML type (30.0 or "30" for an integer key, also as a value of an axis: [30, 30.5];
"0.5", nan or inf for a real one), and a list of them is an axis ([30, 60]).
"""
import os
import re
import sys
import tempfile

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import sirl_testing  # noqa: E402

OPTION = re.compile(r"^\s+(?:-\w,)?(--[\w-]+)\s+(INT|UINT|FLOAT)\b(.*)$")
BAD_INT = ["010", "0x10", "+3", " 3", "nan", "inf", "1e3", "30.0", "-1"]
BAD_REAL = ["010", "0x10", "+3", " 3", "nan", "3.", ".5", "1e"]


def sirl(*args):
    return sirl_testing.run_sirl(*args, timeout=60)


def commands():
    """Every command path: `sirl X` and, for commands with their own subcommands, `sirl X Y`."""
    # The short help lists each command as "  NAME  one line", in groups.
    top = re.findall(r"^ {2}([a-z]+) {2,}\S", sirl("--help").stdout, re.M)
    paths = []
    for c in top:
        paths.append([c])
        h = sirl(c, "--help").stdout
        if "Subcommands:" in h:
            paths += [[c, s] for s in re.findall(r"^\s{2}(\w+)\s", h.split("Subcommands:")[1], re.M)]
    return paths


def main():
    failures, checked = [], 0
    for path in commands():
        for line in sirl(*path, "--help").stdout.splitlines():
            m = OPTION.match(line)
            if not m:
                continue
            opt, kind, rest = m.groups()
            bad = BAD_INT if kind in ("INT", "UINT") else BAD_REAL + ([] if "inf" in rest else ["inf"])
            for v in bad:
                p = sirl(*path, f"{opt}={v}")
                err = p.stderr.strip()
                checked += 1
                if p.returncode != 2 or opt not in err or v.strip() not in err or "\n" in err:
                    failures.append(f"sirl {' '.join(path)} {opt}={v!r}: rc {p.returncode}, {err[:200]!r}")
    if checked < 60:
        failures.append(f"only {checked} option values checked: the --help parsing broke")
    print(f"ok: {checked} bad values of the numeric options refused")

    # Accepted forms: a real option takes 1e3 and 0.5, an integer option plain digits.
    for args in (["plan", "smoke", "--tasks", "--node-bandwidth", "1e3"],
                 ["plan", "smoke", "--tasks", "--node-bandwidth", "0.5"],
                 ["plan", "smoke", "--tasks", "--threads", "3"]):
        p = sirl(*args)
        if p.returncode != 0:
            failures.append(f"sirl {' '.join(args)} refused: {p.stderr.strip()[:200]}")

    # "inf" where the help says it means something (a perfect teacher): validation passes and
    # the command stops at the next thing it lacks (no --out), not at --beta.
    for path in (["dataset"], ["study", "simulate"]):
        err = sirl(*path, "--beta", "inf").stderr
        if "--beta" in err:
            failures.append(f"sirl {' '.join(path)} --beta inf refused: {err.strip()[:200]}")

    # Profile hyper-parameters: the TOML type must be the key's.
    # (A list of values is an axis, each value checked as the key's: "[30, 60]" is good.)
    cases = {"sirl.epochs": (["30.0", '"30"', "[30, 30.5]", "true", "[[30]]"], "[30, 60]"),
             "tpa.stop_min_epochs": (["100.5", '[100, "200"]'], "100"),
             "sirl.lr": (['"0.5"', "nan", "inf", "[1, nan]"], "0.5"),
             "vae.standardize": (["1", '"true"', "[true, 1]"], "false"),
             "phi.hidden": (['"64,64"', "[64.0]", "[[64], [64.5]]"], "[64, 64]"),
             "tpa.stop": (["1", '["fixed", 1]'], '"converged"'),
             "tpa.stop_frozen_rel_tol": (['"0.001"', "true", "[0.001, nan]"], "0.001")}
    with tempfile.TemporaryDirectory() as tmp:
        prof = os.path.join(tmp, "p.toml")
        for key, (bad, good) in cases.items():
            for v in bad + [good]:
                open(prof, "w").write('name = "t"\nenvs = ["grid"]\nseeds = [0]\n[fpe]\n'
                                      'methods = ["sirl"]\nN = [10]\n[hyper.grid]\n'
                                      f'"{key}" = {v}\n')
                p = sirl("plan", prof, "--tasks")
                err = p.stderr.strip()
                if v == good:
                    if p.returncode != 0:
                        failures.append(f"profile {key} = {v} refused: {err[:200]}")
                elif p.returncode == 0 or key not in err or "p.toml:8" not in err:
                    failures.append(f"profile {key} = {v}: rc {p.returncode}, {err[:200]!r}")
                checked += 1
        # Of the right type but out of range: refused with the key, its range and the file (the
        # line cited is the [hyper.<env>] section's, where the whole set is validated).
        for key, v in (("tpa.stop_frozen_rel_tol", "0"), ("tpa.stop_frozen_rel_tol", "1.5"),
                       ("tpa.stop_rel_tol", "-0.1")):
            open(prof, "w").write('name = "t"\nenvs = ["grid"]\nseeds = [0]\n[fpe]\n'
                                  'methods = ["sirl"]\nN = [10]\n[hyper.grid]\n'
                                  f'"{key}" = {v}\n')
            p = sirl("plan", prof, "--tasks")
            err = p.stderr.strip()
            if p.returncode == 0 or f"{key} must be in (0, 1)" not in err or "p.toml:" not in err:
                failures.append(f"profile {key} = {v}: rc {p.returncode}, {err[:200]!r}")
            checked += 1
    if failures:
        print("cli_numbers: FAIL\n  " + "\n  ".join(failures))
        sys.exit(1)
    print("cli_numbers: OK")


if __name__ == "__main__":
    main()
