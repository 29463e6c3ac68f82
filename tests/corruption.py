#!/usr/bin/python3
"""Every corruption of a results file is caught (ctest):

- a seeded sample of single bit flips anywhere in a smoke results file, and of paired flips of
  bit 0x80 at two offsets ≡ 7 (mod 8) (the pattern the old word-wise checksum missed), each with
  and without the .sum sidecar: `sirl export` refuses every one (exit code 1, one line naming the
  file) and writes no CSV;
- the untouched file verifies without its sidecar (its digest is inside it) and `xxh128sum -c`
  accepts its sidecar;
- a file of an older engine without its .sum (the schema-1 fixture) is read with one line saying
  it cannot be verified.
"""
import os
import random
import shutil
import subprocess
import sys
import tempfile

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import sirl_testing  # noqa: E402

SIRL = sirl_testing.sirl_binary()
SINGLE, PAIRS = 120, 60
fail = sirl_testing.make_fail("corruption")


def export(path, out):
    return sirl_testing.run_sirl("export", path, "--csv", out, stdin=None, timeout=120)


def flipped(src, dst, flips):
    data = bytearray(open(src, "rb").read())
    for offset, bit in flips:
        data[offset] ^= bit
    open(dst, "wb").write(data)


def main():
    rng = random.Random(20261203)
    with tempfile.TemporaryDirectory() as tmp:
        good = os.path.join(tmp, "smoke.h5")
        if not sirl_testing.copy_fixture("smoke", good, with_cache=False):
            subprocess.run([SIRL, "run", "smoke", "--out", good, "--threads", "2", "--quiet"],
                           check=True)
        size = os.path.getsize(good)
        cases = [[(rng.randrange(size), 1 << rng.randrange(8))] for _ in range(SINGLE)]
        sevens = range(7, size, 8)
        cases += [[(a, 0x80), (b, 0x80)] for a, b in
                  (rng.sample(sevens, 2) for _ in range(PAIRS))]
        bad = os.path.join(tmp, "bad.h5")
        refused = 0
        for flips in cases:
            flipped(good, bad, flips)
            for sidecar in (True, False):
                if sidecar:
                    shutil.copy(good + ".sum", bad + ".sum")
                elif os.path.exists(bad + ".sum"):
                    os.remove(bad + ".sum")
                out = os.path.join(tmp, "csv")
                shutil.rmtree(out, ignore_errors=True)
                p = export(bad, out)
                err = p.stderr.strip()
                if p.returncode != 1 or bad not in err or "\n" in err or os.path.exists(out):
                    fail(f"flips {flips} (sidecar {sidecar}) not refused: rc {p.returncode}, "
                         f"{err[:300]!r}")
                refused += 1
        print(f"ok: {refused} corrupted copies ({SINGLE} single, {PAIRS} paired flips; with and "
              "without the sidecar) refused")
        # `inspect` reads a results file's datasets: the last corrupted copy is refused there too.
        flipped(good, bad, cases[0])
        p = sirl_testing.run_sirl("inspect", bad, stdin=None, timeout=60)
        if p.returncode == 0 or "checksum" not in p.stderr:
            fail(f"inspect read a corrupted results file: rc {p.returncode}, {p.stderr!r}")

        copy = os.path.join(tmp, "copied.h5")
        shutil.copy(good, copy)  # the .h5 alone, as a user copies it
        p = export(copy, os.path.join(tmp, "csv2"))
        if p.returncode != 0 or "cannot be verified" in p.stderr:
            fail(f"a copied file without its sidecar: rc {p.returncode}, {p.stderr!r}")
        if shutil.which("xxh128sum"):
            p = subprocess.run(["xxh128sum", "-c", "smoke.h5.sum"], cwd=tmp, capture_output=True,
                               text=True)
            if p.returncode != 0:
                fail(f"xxh128sum -c smoke.h5.sum: {p.stdout}{p.stderr}")
        print("ok: a copied .h5 verifies by its own digest; xxh128sum -c accepts the sidecar")

        old = os.path.join(tmp, "v1.h5")
        shutil.copy(sirl_testing.data_path("results_v1.h5"), old)
        p = export(old, os.path.join(tmp, "csv3"))
        if p.returncode != 0 or p.stderr.count("cannot be verified") != 1:
            fail(f"an old file without a checksum: rc {p.returncode}, {p.stderr!r}")
        print("ok: an old file without a checksum is read with one line saying so")
    print("corruption: OK")


if __name__ == "__main__":
    main()
