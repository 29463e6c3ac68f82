#!/usr/bin/python3
"""A results file from someone else is untrusted input (issue 65). From the schema-1 fixture:

- crafted HDF5 metadata behind a valid frame (a global-heap object claiming 1 TB, the class that
  segfaulted `sirl export`/`merge`/`inspect` and h5py): a raw h5py read dies by a signal (the
  file is hostile), while `sirl export`, `sirl merge` and `sirl_bench.open` end with one line and
  a non-zero exit;
- a variable-length string whose reference claims 3.5 GiB (HDF5 allocates what it claims): one
  line from the engine and the reader, within the sandboxed read's memory bound;
- an HDF5 external link inside a framed file is refused by the engine and the reader;
- a schema-3 file without its frame (rewritten, or its frame cut off) is refused by both;
- `sirl merge` refuses an input no checksum verifies unless --accept-unverified, and records it;
- the Python reader checks the frame as the engine does (a flipped byte behind it is refused).
"""
import os
import shutil
import struct
import subprocess
import sys
import tempfile

import h5py
import numpy as np
import xxhash

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import sirl_testing  # noqa: E402

SRC = sirl_testing.source_dir()
FIXTURE = sirl_testing.data_path("results_v1.h5")
PY = "/usr/bin/python3"
READER = os.path.join(SRC, "python")
fail = sirl_testing.make_fail("untrusted_files")


def framed(body: bytes) -> bytes:
    """The engine's frame (results/results_file.cpp) in front of an HDF5 body."""
    head = b"SIRLRESULTS2\nxxh3-128 " + xxhash.xxh3_128(body).hexdigest().encode() + b"\n"
    return head + b"\0" * (1024 - len(head)) + body


def write(path, data):
    with open(path, "wb") as fh:
        fh.write(data)
    return path


def sirl(*args):
    return sirl_testing.run_sirl(*args, text=False, timeout=120)


def reader(path):
    """sirl_bench.open in a fresh interpreter: (returncode, stderr)."""
    code = ("import sys; sys.path.insert(0, sys.argv[1]); import sirl_bench\n"
            "try:\n    r = sirl_bench.open(sys.argv[2]); r.tables['fpe']; r.records; r.methods\n"
            "except sirl_bench.ResultsError as e:\n    print(e, file=sys.stderr); sys.exit(1)\n")
    p = subprocess.run([PY, "-c", code, READER, path], capture_output=True, timeout=120)
    return p.returncode, p.stderr


def one_line_refusal(what, rc, err, path):
    lines = err.decode("utf-8", "strict").strip().splitlines()
    if rc <= 0 or len(lines) != 1 or path not in lines[0]:
        fail(f"{what}: rc {rc}, stderr {err!r}")


def main():
    body = open(FIXTURE, "rb").read()
    with tempfile.TemporaryDirectory() as tmp:
        good = write(os.path.join(tmp, "good.h5"), framed(body))
        p = sirl("export", good, "--csv", os.path.join(tmp, "csv_good"))
        if p.returncode != 0:
            fail(f"the framed fixture: {p.stderr!r}")
        rc, err = reader(good)
        if rc != 0:
            fail(f"the reader on the framed fixture: {err!r}")

        # Crafted metadata: the first global heap's first object claims 1 TB.
        heap = body.index(b"GCOL")
        b = bytearray(body)
        struct.pack_into("<Q", b, heap + 24, 1 << 40)
        bad = write(os.path.join(tmp, "crafted.h5"), framed(bytes(b)))
        raw = subprocess.run([PY, "-c", "import h5py, sys\nf = h5py.File(sys.argv[1], 'r')\n"
                              "[f.attrs[k] for k in f.attrs]\n"
                              "f.visititems(lambda n, o: [o.attrs[k] for k in o.attrs] and None or "
                              "(o[()] if isinstance(o, h5py.Dataset) else None))", bad],
                             capture_output=True, timeout=120)
        if raw.returncode >= 0:
            fail(f"the crafted file does not crash a raw h5py read (rc {raw.returncode}): "
                 "the fixture no longer tests the class")
        for args in (["export", bad, "--csv", os.path.join(tmp, "csv_bad")],
                     ["merge", "--partial", os.path.join(tmp, "m.h5"), bad, good]):
            p = sirl(*args)
            one_line_refusal(f"sirl {args[0]} on crafted metadata", p.returncode, p.stderr, bad)
        one_line_refusal("the reader on crafted metadata", *reader(bad), bad)
        print("ok: crafted HDF5 metadata behind a valid frame: one line, never a signal "
              f"(a raw h5py read died with rc {raw.returncode})")

        # Crafted lengths: the first string of runs_index (a variable-length string dataset)
        # claims 3.5 GiB through its heap reference's 32-bit length, which HDF5 allocates and
        # clears before it finds the heap object shorter. Unbounded, every read of this 200 KB
        # file takes 3.5 GiB and seconds (a few such strings take the machine's memory); the
        # sandboxed reads bound what a file of its size may need, so it is one line.
        with h5py.File(FIXTURE, "r") as f:
            at = f["runs_index"].id.get_offset()
        b = bytearray(body)
        struct.pack_into("<I", b, at, 0xE0000000)
        long_string = write(os.path.join(tmp, "long_string.h5"), framed(bytes(b)))
        for args in (["export", long_string, "--csv", os.path.join(tmp, "csv_long")],
                     ["merge", "--partial", os.path.join(tmp, "m2.h5"), long_string, good]):
            p = sirl(*args)
            one_line_refusal(f"sirl {args[0]} on a string claiming 3.5 GiB", p.returncode,
                             p.stderr, long_string)
        one_line_refusal("the reader on a string claiming 3.5 GiB", *reader(long_string),
                         long_string)
        print("ok: a string whose reference claims 3.5 GiB in a 200 KB file: one line, within "
              "the sandboxed read's memory bound")

        # An external link inside a framed file.
        plain = shutil.copy(FIXTURE, os.path.join(tmp, "plain.h5"))
        with h5py.File(plain, "r+") as f:
            f["runs/elsewhere"] = h5py.ExternalLink(os.path.join(tmp, "other.h5"), "/x")
        linked = write(os.path.join(tmp, "linked.h5"), framed(open(plain, "rb").read()))
        p = sirl("export", linked, "--csv", os.path.join(tmp, "csv_link"))
        one_line_refusal("sirl export with an external link", p.returncode, p.stderr, linked)
        if b"link to another file" not in p.stderr:
            fail(f"external link: {p.stderr!r}")
        rc, err = reader(linked)
        one_line_refusal("the reader with an external link", rc, err, linked)
        print("ok: an external link is refused by the engine and the reader")

        # Links within the file, which the engine never writes: a group linked into itself (a
        # walk that follows it never ends) and a table soft-linked to another (issue 65: the
        # reader hung on the first and the figures gave a traceback on the second).
        for name, make in (("cycle", lambda f: f.__setitem__("runs/loop", f["runs"])),
                           ("soft", lambda f: f.__setitem__("runs/alias", h5py.SoftLink("/runs")))):
            plain = shutil.copy(FIXTURE, os.path.join(tmp, name + "_plain.h5"))
            with h5py.File(plain, "r+") as f:
                make(f)
            linked = write(os.path.join(tmp, name + ".h5"), framed(open(plain, "rb").read()))
            one_line_refusal(f"the reader on a {name} link", *reader(linked), linked)
        print("ok: a hard-link cycle and a soft link are refused by the reader, promptly")

        # A record that names a field it lacks (a flipped byte in a heap string does this): the
        # reader refuses it in one line (issue 65: a KeyError traceback in records and figures).
        named = shutil.copy(FIXTURE, os.path.join(tmp, "named_plain.h5"))
        with h5py.File(named, "r+") as f:
            groups = []
            f["runs"].visititems(lambda n, o: groups.append(o) if "record_numbers" in o.attrs
                                 else None)
            g = groups[0]
            names = [n.decode() if isinstance(n, bytes) else str(n)
                     for n in g.attrs["record_numbers"]] + ["flopsrged"]
            g.attrs["record_numbers"] = np.array(names, dtype=h5py.string_dtype())
        named_f = write(os.path.join(tmp, "named.h5"), framed(open(named, "rb").read()))
        code = ("import sys; sys.path.insert(0, sys.argv[2]); import sirl_bench\n"
                "sirl_bench.open(sys.argv[1]).records")
        p = subprocess.run([PY, "-c", code, named_f, os.path.join(SRC, "python")],
                           capture_output=True, timeout=120)
        lines = p.stderr.decode().strip().splitlines()
        if p.returncode == 0 or "ResultsError" not in lines[-1] or "not a record" not in lines[-1]:
            fail(f"the reader on a record naming a missing field: {p.stderr[-600:]!r}")
        print("ok: a record naming a field it lacks is one ResultsError")

        # A schema-3 file without its frame: laundered through h5py.
        laundered = shutil.copy(FIXTURE, os.path.join(tmp, "laundered.h5"))
        with h5py.File(laundered, "r+") as f:
            f.attrs["schema_version"] = 3
        p = sirl("export", laundered, "--csv", os.path.join(tmp, "csv_l"))
        one_line_refusal("sirl export of an unframed schema-3 file", p.returncode, p.stderr, laundered)
        if b"frame" not in p.stderr:
            fail(f"unframed schema 3: {p.stderr!r}")
        one_line_refusal("the reader on an unframed schema-3 file", *reader(laundered), laundered)
        print("ok: a schema-3 file without its frame is refused")

        # merge takes unverified inputs only when told, and says so in its output.
        a, c = (shutil.copy(FIXTURE, os.path.join(tmp, n)) for n in ("a.h5", "c.h5"))
        out = os.path.join(tmp, "merged.h5")
        p = sirl("merge", "--partial", out, a, c)
        if p.returncode != 2 or b"--accept-unverified" not in p.stderr or os.path.exists(out):
            fail(f"merge of unverified inputs: rc {p.returncode}, {p.stderr!r}")
        p = sirl("merge", "--partial", "--accept-unverified", out, a, c)
        if p.returncode != 0:
            fail(f"merge --accept-unverified: {p.stderr!r}")
        with h5py.File(out, "r") as f:  # our own output, framed: h5py reads it at offset 1024
            listed = f.attrs["unverified_inputs"]
            listed = listed.decode() if isinstance(listed, bytes) else listed
        if a not in listed or c not in listed:
            fail(f"the merged file does not list its unverified inputs: {listed!r}")
        print("ok: merge refuses unverified inputs unless --accept-unverified, and records them")

        # A hostile /methods group (what the figures draw): refused with one line by the reader.
        styled = shutil.copy(FIXTURE, os.path.join(tmp, "styled.h5"))
        with h5py.File(styled, "r+") as f:
            g = f.create_group("methods/sirl")
            g.attrs["label"] = "$\\frac{SIRL"
            g.attrs["colour"] = "not a colour"
            g.attrs["figure_order"] = 1e400
        styled_f = write(os.path.join(tmp, "styled_f.h5"), framed(open(styled, "rb").read()))
        rc, err = reader(styled_f)
        one_line_refusal("the reader on a hostile /methods", rc, err, styled_f)
        print("ok: a hostile /methods group is one ResultsError")

        # The reader checks the frame: one flipped byte behind it.
        flipped = bytearray(open(good, "rb").read())
        flipped[-100] ^= 0x01
        flip = write(os.path.join(tmp, "flipped.h5"), bytes(flipped))
        rc, err = reader(flip)
        one_line_refusal("the reader on a flipped byte", rc, err, flip)
        if b"checksum mismatch" not in err:
            fail(f"flipped byte: {err!r}")
        print("ok: the reader verifies the frame")

        # A file is checked once per process while its bytes stay (the report opens one file
        # several times); the same path rewritten, here with that flipped byte, is checked again.
        again = os.path.join(tmp, "again.h5")
        shutil.copy(good, again)
        code = ("import os, shutil, sys; sys.path.insert(0, sys.argv[1]); import sirl_bench\n"
                "forks = []; real = os.fork\n"
                "os.fork = lambda: (forks.append(1), real())[1]\n"
                "sirl_bench.open(sys.argv[2]).close(); sirl_bench.open(sys.argv[2]).close()\n"
                "print(len(forks))\n"
                "shutil.copyfile(sys.argv[3], sys.argv[2])\n"
                "try:\n    sirl_bench.open(sys.argv[2])\n"
                "except sirl_bench.ResultsError as e:\n    print(len(forks), e)\n")
        p = subprocess.run([PY, "-c", code, READER, again, flip], capture_output=True, text=True,
                           timeout=120)
        out = p.stdout.splitlines()
        if p.returncode != 0 or len(out) != 2 or out[0] != "1" or "checksum mismatch" not in out[1]:
            fail(f"checked once per unchanged file, again when rewritten: rc {p.returncode}, "
                 f"{p.stdout!r} {p.stderr[-2000:]!r}")
        print("ok: an unchanged file is checked once per process; a rewritten one again")


main()
