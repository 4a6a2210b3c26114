"""The files a user hands to mftyre and the files it writes: one rule for all of them.

Reading (:func:`open_user_file`, :func:`read_user_file`): only regular files are read (a FIFO, a device such as
``/dev/zero`` or a directory is refused before a byte is read), and only up to a size limit, so a wrong path can
neither block nor exhaust memory.

Sample files (:func:`sample_tir`): the .tir files of the repository's ``tir_files/`` folder, installed with the
package as ``mftyre.tir_files``.

Writing (:func:`check_outputs`, used by every command before it does any work): an output never replaces an input
(compared by resolved path, and by inode where both exist), two outputs are never the same file, and an existing
output is replaced only with ``--overwrite`` (``overwrite=True``), and never when it is a symbolic link or not a
regular file (a FIFO, a device). Every output is written by :func:`write_atomically` (figures by
:func:`write_figure`, tables by :func:`write_frame_csv`, rendered in memory first): a new file with a random name
in the target folder, created with O_EXCL|O_NOFOLLOW, fsynced and renamed into place, with the ordinary
permissions of a new file (0666 less the umask, e.g. 0644).
"""
from __future__ import annotations

import contextlib
import importlib.resources
import io
import os
import secrets
import stat
from pathlib import Path

from .errors import MFTyreError

__all__ = ["OutputError", "open_user_file", "read_user_file", "same_file", "check_outputs", "write_atomically",
           "write_figure", "write_frame_csv", "make_output_folder", "refuse_special_output", "sample_tir", "TIR_MAX_BYTES", "DATA_MAX_BYTES",
           "DATA_MAX_COLUMNS"]

#: Largest .tir file read (16 MiB; real files are tens of kB).
TIR_MAX_BYTES = 16 * 2**20
#: Largest measurement file read (CSV, TYDEX, TTC .dat/.mat, road profiles), and the most bytes the variables of a
#: compressed .mat file may expand to: 128 MiB (reading takes up to about 8x the file's size in memory, so at most
#: ~1.1 GB, and ~7 s of CPU; 6e5 rows of 17 channels written with 10 digits). docs/resource-limits.md.
DATA_MAX_BYTES = 128 * 2**20
#: Most columns (channels) a measurement file may have (TTC runs have about 25; each column costs Python work).
DATA_MAX_COLUMNS = 1_000


class OutputError(MFTyreError, FileExistsError):
    """An output file would replace an input or an existing file (without ``--overwrite``)."""


@contextlib.contextmanager
def open_user_file(path, *, max_bytes: int, what: str, error=MFTyreError):
    """Open the regular file ``path`` for binary reading (a context manager giving the file object); ``error``
    (an MFTyreError subclass) naming the path and ``what`` was expected when it is missing, not a regular file
    or larger than ``max_bytes``."""
    name = str(path)
    try:  # O_NONBLOCK: opening a FIFO with no writer must not block; it is refused below
        fd = os.open(name, os.O_RDONLY | getattr(os, "O_NONBLOCK", 0) | getattr(os, "O_BINARY", 0))
    except FileNotFoundError:
        raise error(f"{name}: file not found: expected an existing {what}") from None
    except IsADirectoryError:
        raise error(f"{name}: is a directory: expected a {what}") from None
    except ValueError:  # e.g. an embedded NUL character
        raise error(f"{name!r}: not a valid file name: expected the path of a {what}") from None
    except OSError as exc:
        raise error(f"{name}: cannot open: {exc.strerror}: expected a readable {what}") from None
    try:
        info = os.fstat(fd)
        if stat.S_ISDIR(info.st_mode):
            raise error(f"{name}: is a directory: expected a {what}")
        if not stat.S_ISREG(info.st_mode):
            raise error(f"{name}: not a regular file (a device, FIFO or socket): expected a {what}")
        if info.st_size > max_bytes:
            raise error(f"{name}: {info.st_size} bytes, more than the limit of {max_bytes} bytes for a {what}")
        with os.fdopen(fd, "rb", closefd=False) as fh:
            yield fh
    finally:
        os.close(fd)


def read_user_file(path, *, max_bytes: int, what: str, error=MFTyreError) -> bytes:
    """The bytes of the regular file ``path`` (see :func:`open_user_file`)."""
    with open_user_file(path, max_bytes=max_bytes, what=what, error=error) as fh:
        size = os.fstat(fh.fileno()).st_size
        data = fh.read(size + 1)
    if len(data) != size:
        raise error(f"{path}: changed while being read: expected a {what} that is not being written to")
    return data


def same_file(a, b) -> bool:
    """True when ``a`` and ``b`` name the same file: by inode where both exist, else by resolved path."""
    a, b = Path(a), Path(b)
    try:
        if a.exists() and b.exists():
            return os.path.samefile(a, b)
    except OSError:
        pass
    return a.resolve() == b.resolve()


def check_outputs(outputs: dict, inputs: dict | None = None, *, folders: dict | None = None,
                  overwrite: bool = False, option: str = "--overwrite") -> None:
    """Refuse (:class:`OutputError`) to write before any work is done, when

    * an output file (``outputs``: label -> path, e.g. ``{"--csv": "out.csv"}``) or an output folder
      (``folders``: label -> folder the command writes its files into) is one of the ``inputs`` (label -> path),
    * two outputs are the same file,
    * an output file exists, or an output folder exists and is not empty, and ``overwrite`` is false.

    ``None`` paths are ignored; ``option`` is how the caller spells the permission (``--overwrite`` or
    ``overwrite=True``)."""
    files = {k: Path(v) for k, v in outputs.items() if v is not None}
    dirs = {k: Path(v) for k, v in (folders or {}).items() if v is not None}
    sources = {k: Path(v) for k, v in (inputs or {}).items() if v is not None}
    for label, out in (*files.items(), *dirs.items()):
        for source_label, source in sources.items():
            if same_file(out, source):
                raise OutputError(f"{label} {out}: is the input {source_label} ({source}); an input is never "
                                  "overwritten: choose another output path")
    labels = list(files)
    for i, label in enumerate(labels):
        for other in labels[i + 1:]:
            if same_file(files[label], files[other]):
                raise OutputError(f"{label} {files[label]}: is also the {other} output; choose different paths")
    for label, out in files.items():
        if out.is_dir():
            raise OutputError(f"{label} {out}: is a folder: expected a file path")
    for label, out in files.items():
        refuse_special_output(out, label)
    for label, folder in dirs.items():
        if folder.exists() and not folder.is_dir():
            raise OutputError(f"{label} {folder}: is a file: expected a folder (new, or existing)")
    existing = [f"{label} {out}" for label, out in files.items() if out.exists() or out.is_symlink()]
    existing += [f"{label} {folder} (a folder that is not empty)" for label, folder in dirs.items()
                 if folder.is_dir() and any(folder.iterdir())]
    if existing and not overwrite:
        raise OutputError(f"{'; '.join(existing)}: exist{'s' if len(existing) == 1 else ''}; pass {option} to "
                          "replace")


def refuse_special_output(path, label: str = "output") -> None:
    """Refuse (:class:`OutputError`) an output path that is a symbolic link (even a dangling one) or an existing
    file that is not a regular file (FIFO, device, socket): replacing it would write where the user did not ask,
    or block."""
    path = Path(path)
    try:
        info = os.lstat(path)
    except FileNotFoundError:
        return
    except ValueError:  # e.g. an embedded NUL character
        raise OutputError(f"{label} {str(path)!r}: not a valid file name") from None
    except OSError as exc:
        raise OutputError(f"{label} {path}: cannot inspect: {exc.strerror}") from None
    if stat.S_ISLNK(info.st_mode):
        raise OutputError(f"{label} {path}: is a symbolic link; outputs are never written through or over a link: "
                          "remove it or choose another path")
    if stat.S_ISDIR(info.st_mode):
        raise OutputError(f"{label} {path}: is a folder: expected a file path")
    if not stat.S_ISREG(info.st_mode):
        raise OutputError(f"{label} {path}: exists and is not a regular file (a FIFO, device or socket); "
                          "choose another path")


def write_atomically(path, data: bytes | str) -> Path:
    """Write ``data`` (text as UTF-8) to ``path``: the one routine through which every output of mftyre is
    written. A new file with a random name in the target folder is created with O_CREAT|O_EXCL|O_NOFOLLOW (never
    an existing file or a planted link), written, fsynced and renamed onto ``path``; a ``path`` that is a
    symbolic link or an existing non-regular file (FIFO, device) is refused (:class:`OutputError`). The new file
    has the permissions of any new file (0666 less the umask). Returns the path."""
    path = Path(path)
    if isinstance(data, str):
        data = data.encode("utf-8")
    refuse_special_output(path)
    folder = path.parent
    flags = os.O_WRONLY | os.O_CREAT | os.O_EXCL | getattr(os, "O_NOFOLLOW", 0) | getattr(os, "O_BINARY", 0)
    tmp = folder / f".{path.name[:64]}.{secrets.token_hex(8)}.tmp"
    try:
        fd = os.open(tmp, flags, 0o666)
    except OSError as exc:
        raise OutputError(f"output {path}: cannot write in {folder}: {exc.strerror}") from None
    try:
        with os.fdopen(fd, "wb") as fh:
            fh.write(data)
            fh.flush()
            os.fsync(fh.fileno())
        refuse_special_output(path)  # a link or FIFO planted while writing is refused too (rename would replace it)
        os.replace(tmp, path)
    except BaseException as exc:
        try:
            os.unlink(tmp)
        except OSError:
            pass
        if isinstance(exc, OSError) and not isinstance(exc, MFTyreError):
            raise OutputError(f"output {path}: cannot write: {exc.strerror or exc}") from None
        raise
    return path


def write_figure(fig, path) -> Path:
    """Save the matplotlib Figure ``fig`` to ``path`` through :func:`write_atomically` (rendered in memory; the
    format from the suffix, PNG when the suffix is not one matplotlib writes)."""
    path = Path(path)
    suffix = path.suffix[1:].lower()
    fmt = suffix if suffix in fig.canvas.get_supported_filetypes() else "png"
    buffer = io.BytesIO()
    fig.savefig(buffer, format=fmt)
    return write_atomically(path, buffer.getvalue())


def write_frame_csv(frame, path, **to_csv) -> Path:
    """Write the pandas DataFrame ``frame`` as CSV to ``path`` through :func:`write_atomically`."""
    text = io.StringIO()
    frame.to_csv(text, **to_csv)
    return write_atomically(path, text.getvalue())


def make_output_folder(folder, label: str = "output folder") -> Path:
    """Create ``folder`` (and its parents) for outputs; :class:`OutputError` when that is impossible (no
    permission, a file in the way)."""
    folder = Path(folder)
    try:
        folder.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise OutputError(f"{label} {folder}: cannot create: {exc.strerror or exc}") from None
    return folder


def sample_tir(name: str) -> Path:
    """Path of a sample .tir file shipped with mftyre (``tir_files/`` of the repository), e.g.
    ``sample_tir("car_205_60R15_mf61.tir")``: package data ``mftyre.tir_files`` when installed (pip install . or a
    wheel), the repository's folder in a source checkout."""
    try:  # a folder without __init__.py: a namespace package, whose files() joins to real paths
        folder = importlib.resources.files("mftyre.tir_files")
    except ModuleNotFoundError:  # a source checkout on sys.path: the folder sits beside the package
        folder = Path(__file__).resolve().parents[1] / "tir_files"
    path = folder.joinpath(name)
    if not path.is_file():
        available = sorted(p.name for p in folder.iterdir() if p.name.endswith(".tir")) if folder.is_dir() else []
        raise FileNotFoundError(f"no sample file {name!r} among the samples shipped with mftyre: "
                                f"{', '.join(available) or 'none'}")
    return Path(str(path))
