"""Writing the figures folder's files without following what someone else put there.

A figure or report is written to a fresh temporary file beside its final name (created with
O_EXCL, so never an existing file or link) and renamed over that name: a symbolic link planted at
a figure's name is replaced, its target never written, and a reader never sees half a file.
"""
import os
import tempfile


def replace_file(path, write):
    """Calls write(tmp) to produce the file at a new temporary name beside `path`, then renames
    it to `path` (replacing a file or a link there, never writing through one)."""
    folder = os.path.dirname(path) or "."
    if os.path.isdir(path) and not os.path.islink(path):
        raise IsADirectoryError(f"{path}: is a folder, not a file this script writes")
    fd, tmp = tempfile.mkstemp(dir=folder, prefix="." + os.path.basename(path) + ".",
                               suffix=".tmp")
    os.close(fd)
    try:
        write(tmp)
        os.chmod(tmp, 0o644 & ~_umask())
        os.replace(tmp, path)
    except BaseException:
        try:
            os.unlink(tmp)
        except OSError:
            pass
        raise


def _umask():
    mask = os.umask(0)
    os.umask(mask)
    return mask


def write_text(path, text):
    """`text` (str) as the UTF-8 file `path`."""
    def write(tmp):
        with open(tmp, "w", encoding="utf-8") as fh:
            fh.write(text)
    replace_file(path, write)


def save_figure(fig, path, **kw):
    """fig.savefig to `path`, its format from path's extension."""
    fmt = os.path.splitext(path)[1].lstrip(".")
    replace_file(path, lambda tmp: fig.savefig(tmp, format=fmt, **kw))
