"""A file someone else wrote is untrusted input (a shard, a colleague's results, a file that came
with a paper). Before h5py reads a byte of it, this module checks what the engine checks:

- the checksum frame (the first 1024 bytes: "SIRLRESULTS2\\nxxh3-128 <digest of the rest>") and
  FILE.sum beside it (`xxh128sum -c` format);
- that a file an engine from 0.8.0 on wrote (schema 3) still has its frame;
- that no link leads to another file (an HDF5 external link pulls values no checksum covers);
- that reading its HDF5 structures does not crash the HDF5 library: a checksum proves only that
  nothing changed by accident (anyone can recompute XXH3 over crafted bytes), and crafted
  metadata crashes libhdf5 below anything h5py can check. So the structures are read first in a
  forked child; if it dies, the file is refused with one line.

Every failure is a ResultsError with one line. Debian's python3-h5py and python3-xxhash only."""
from __future__ import annotations

import os
import stat

from .errors import ResultsError

FRAME_BYTES = 1024
MAGIC = b"SIRLRESULTS2\nxxh3-128 "
HDF5_SIGNATURE = b"\x89HDF\r\n\x1a\n"


def _xxh3_128(path, offset=0):
    try:
        import xxhash
    except ImportError:
        raise ResultsError("python3-xxhash is missing (it verifies results files): "
                           "./scripts/setup.sh installs it") from None
    h = xxhash.xxh3_128()
    with open(path, "rb") as fh:
        fh.seek(offset)
        for block in iter(lambda: fh.read(1 << 20), b""):
            h.update(block)
    return h.hexdigest()


def verify(path) -> tuple[bool, bool]:
    """(framed, verified): checks the frame and FILE.sum as the engine does; raises ResultsError
    on any mismatch, a damaged frame, or a path that is not a regular file."""
    path = str(path)
    try:
        st = os.stat(path)
    except OSError as e:
        raise ResultsError(f"{path}: {e.strerror}") from None
    if not stat.S_ISREG(st.st_mode):
        raise ResultsError(f"{path}: not a regular file (a pipe, socket, device or folder)")
    with open(path, "rb") as fh:
        head = fh.read(FRAME_BYTES + len(HDF5_SIGNATURE))
    framed = not head.startswith(HDF5_SIGNATURE)
    if framed:
        if not head[FRAME_BYTES:].startswith(HDF5_SIGNATURE) and not head.startswith(b"SIRLRESULTS"):
            raise ResultsError(f"{path}: not an HDF5 file (neither a sirl results file nor a "
                               "dataset file)")
        frame = head[:FRAME_BYTES]
        want = frame[len(MAGIC):len(MAGIC) + 32]
        expect = MAGIC + want + b"\n"
        if (len(frame) != FRAME_BYTES or not frame.startswith(MAGIC) or len(want) != 32
                or frame != expect + b"\0" * (FRAME_BYTES - len(expect))):
            raise ResultsError(f"{path}: its checksum frame (the first {FRAME_BYTES} bytes) is "
                               "damaged (corrupted or truncated), or it is not a sirl results file")
        got = _xxh3_128(path, FRAME_BYTES)
        if got != want.decode("ascii", "replace"):
            raise ResultsError(f"{path}: checksum mismatch ({got}, recorded "
                               f"{want.decode('ascii', 'replace')}): the file changed after it "
                               "was written (corrupted?)")
    try:
        sum_st = os.stat(path + ".sum")
    except OSError:
        return framed, framed
    if not stat.S_ISREG(sum_st.st_mode):  # a FIFO would block the open forever
        raise ResultsError(f"{path}.sum: not a regular file (a pipe, socket, device or folder)")
    try:
        with open(path + ".sum") as fh:
            words = fh.read(4096).split()
    except (OSError, UnicodeDecodeError):
        return framed, framed
    want = words[0] if words else ""
    if len(want) == 32:
        got = _xxh3_128(path)
        if got != want:
            raise ResultsError(f"{path}: .sum checksum mismatch ({got}, recorded {want}): the "
                               "file changed after it was written (corrupted?)")
        return framed, True
    if len(want) == 16:  # an engine up to 0.7.0's checksum: the engine verifies those
        return framed, framed
    raise ResultsError(f"{path}.sum: not a checksum file")


def _walk(f, visit):
    """Every object of file f by path, links examined without being followed: `visit(name,
    obj)` for groups and datasets. The engine writes a tree: each object under one name, no
    links. Raises ResultsError at a link to another file, a link within it (a soft link makes one
    table read as another), and an object reached under two names (hard links; a group linked
    into itself would make the walk endless)."""
    import h5py
    stack = [("", f)]
    seen = {h5py.h5o.get_info(f.id).addr}
    while stack:
        prefix, g = stack.pop()
        for k in g.keys():
            name = f"{prefix}/{k}"
            link = g.get(k, getlink=True)
            if isinstance(link, h5py.ExternalLink) or not isinstance(link, (h5py.HardLink,
                                                                            h5py.SoftLink)):
                raise ResultsError(f"{f.filename}: {name} is a link to another file (an HDF5 "
                                   "external link), which no checksum of this file covers; "
                                   "sirl-bench reads no such file")
            if isinstance(link, h5py.SoftLink):
                raise ResultsError(f"{f.filename}: {name} is a link within the file (an HDF5 "
                                   "soft link), which the engine never writes")
            obj = g[k]
            addr = h5py.h5o.get_info(obj.id).addr
            if addr in seen:
                raise ResultsError(f"{f.filename}: {name} is an object the file also holds under "
                                   "another name (an HDF5 hard link), which the engine never "
                                   "writes")
            seen.add(addr)
            if len(seen) > 2_000_000:
                raise ResultsError(f"{f.filename}: more than 2,000,000 objects")
            visit(name, obj)
            if isinstance(obj, h5py.Group):
                stack.append((name, obj))


def _read_structures(path):
    """Reads what a reader of the file will touch: every attribute, every string or compound
    dataset whole, and one element of every other dataset (its metadata, filters and storage)."""
    import h5py
    import numpy as np
    with h5py.File(path, "r") as f:
        def touch(obj):
            for k in obj.attrs.keys():
                obj.attrs[k]
        touch(f)

        def visit(name, obj):
            touch(obj)
            if isinstance(obj, h5py.Dataset):
                if obj.is_virtual or obj.external:
                    raise ResultsError(f"{path}: {name} keeps its values outside the file "
                                       "(external or virtual storage), which no checksum covers")
                if obj.dtype.kind in "OSUV" or obj.dtype.names:
                    obj[()]
                elif obj.size:
                    obj[tuple(np.zeros(obj.ndim, dtype=int))] if obj.ndim else obj[()]
        _walk(f, visit)


def _die_with_parent():
    """The forked reader is killed when its parent dies (Linux PR_SET_PDEATHSIG): a reader killed
    by `timeout` or Ctrl-C leaves no child reading on."""
    try:
        import ctypes
        import signal
        libc = ctypes.CDLL(None, use_errno=True)
        libc.prctl(1, int(signal.SIGKILL), 0, 0, 0)  # PR_SET_PDEATHSIG = 1
        if os.getppid() == 1:  # the parent died before the request: do not read on
            os._exit(3)
    except (OSError, AttributeError):
        pass  # not Linux: the child still ends when its reading does


# What the sandboxed read of a file may use, as the engine bounds its own (results/
# isolated_read.cpp): memory of 256 MiB plus 64 times the file, CPU time of 30 s plus 1 s per
# 8 MiB. Every value is stored in the file and deflate expands at most 1032-fold, but crafted
# metadata claims more than it stores (a variable-length string's 32-bit length, which HDF5
# allocates and clears before it finds the heap object shorter; a dataspace of never-written
# storage), and without a bound one small file takes the machine's memory or hangs the reader.
_OVER_MEMORY = 5


def _read_budget(path) -> tuple[int, int]:
    try:
        size = max(os.stat(path).st_size, 0)
    except OSError:
        size = 0
    size = min(size, 1 << 39)
    return (256 << 20) + 64 * size, 30 + size // (8 << 20)


def _limit_child(memory: int, cpu_seconds: int):
    """In the forked child: an address-space limit of what it maps now plus `memory`, and a CPU
    time limit (SIGXCPU at it, SIGKILL a second later)."""
    import resource
    try:
        with open("/proc/self/statm") as fh:
            mapped = int(fh.read().split()[0]) * os.sysconf("SC_PAGE_SIZE")
        resource.setrlimit(resource.RLIMIT_AS, (mapped + memory, mapped + memory))
    except (OSError, ValueError):
        pass  # no /proc: the CPU limit still ends a runaway read
    try:
        resource.setrlimit(resource.RLIMIT_CPU, (cpu_seconds, cpu_seconds + 1))
    except (OSError, ValueError):
        pass


# Files this process has checked, by what identifies their bytes (device, inode, size and both
# times: a rewrite changes ctime, which no user can set back) -> check()'s result. A report opens
# one file several times (the tables, the study, the ledger); the sandboxed read of every object
# is seconds on a big file and need not run twice on the same bytes.
_CHECKED: dict[tuple, tuple[bool, bool]] = {}


def _identity(path):
    try:
        st = os.stat(path)
    except OSError:
        return None  # verify() reports it
    return (st.st_dev, st.st_ino, st.st_size, st.st_mtime_ns, st.st_ctime_ns)


def check(path) -> tuple[bool, bool]:
    """verify(path), then the file's structures read in a forked child (a crash there is one
    ResultsError here). Returns (framed, verified). A file already checked by this process, not
    changed since, is not read again."""
    before = _identity(path)
    if before is not None and before in _CHECKED:
        return _CHECKED[before]
    result = _check(path)
    if before is not None and _identity(path) == before:
        _CHECKED[before] = result
    return result


def _check(path) -> tuple[bool, bool]:
    framed, verified = verify(path)
    memory, cpu_seconds = _read_budget(path)
    r, w = os.pipe()
    pid = os.fork()
    if pid == 0:  # the child: read, report, and leave without running the parent's handlers
        os.close(r)
        _die_with_parent()
        try:
            fd = os.open(os.devnull, os.O_WRONLY)
            os.dup2(fd, 2)
            _limit_child(memory, cpu_seconds)
            _read_structures(str(path))
            code = 0
        except MemoryError:
            code = _OVER_MEMORY
        except ResultsError as e:
            os.write(w, str(e).encode("utf-8", "replace")[:4000])
            code = 3
        except BaseException as e:  # noqa: BLE001 (h5py's and numpy's errors: all malformed)
            os.write(w, f"{path}: malformed HDF5 ({type(e).__name__}: {e})".encode(
                "utf-8", "replace")[:4000])
            code = 3
        os._exit(code)
    os.close(w)
    chunks = []
    while True:
        b = os.read(r, 4096)
        if not b:
            break
        chunks.append(b)
    os.close(r)
    _, status, usage = os.wait4(pid, 0)
    msg = b"".join(chunks).decode("utf-8", "replace").splitlines()
    if os.WIFEXITED(status) and os.WEXITSTATUS(status) == 0:
        return framed, verified
    if os.WIFEXITED(status) and os.WEXITSTATUS(status) == 3:
        raise ResultsError(msg[0] if msg else f"{path}: malformed HDF5")
    if os.WIFEXITED(status) and os.WEXITSTATUS(status) == _OVER_MEMORY:
        raise ResultsError(f"{path}: its HDF5 structures claim more data than the file can hold "
                           f"(reading them needed more than {memory >> 20} MiB in a sandboxed "
                           "read); the file was damaged or crafted after its checksum was "
                           "computed, and cannot be read")
    import signal
    if os.WIFSIGNALED(status) and (
            os.WTERMSIG(status) == signal.SIGXCPU or
            (os.WTERMSIG(status) == signal.SIGKILL and
             usage.ru_utime + usage.ru_stime >= cpu_seconds)):
        raise ResultsError(f"{path}: reading its HDF5 structures did not end within "
                           f"{cpu_seconds} s of CPU time in a sandboxed read, far more than a "
                           "file of its size needs; the file was damaged or crafted after its "
                           "checksum was computed, and cannot be read")
    how = (f"signal {os.WTERMSIG(status)}" if os.WIFSIGNALED(status)
           else f"exit {os.WEXITSTATUS(status)}")
    raise ResultsError(f"{path}: its HDF5 structures are malformed (reading them crashed the HDF5 "
                       f"library in a sandboxed read: {how}); the file was damaged or crafted "
                       "after its checksum was computed, and cannot be read")
