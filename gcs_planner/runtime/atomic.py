"""Atomic file writes: a file is either absent, the old one, or complete — never half-written.

Files are created with the permissions the user's umask gives a new file (``0o666 & ~umask``),
as ``open()`` would, not the 0600 of the temporary file they are written through. The checks
``check_output_file`` / ``check_output_dir`` let a command refuse an output path it could never
write *before* it spends minutes computing what to write there.
"""

from __future__ import annotations

import errno
import os
import shutil
import signal
import tempfile
import threading
from collections.abc import Iterable
from pathlib import Path

from gcs_planner.errors import InputError

_umask_lock = threading.Lock()


def current_umask() -> int:
    """The process umask. Linux publishes it in /proc; elsewhere it can only be read by setting
    it, which is done under a lock so two writers never see the temporary value."""
    try:
        with open("/proc/self/status", encoding="ascii") as f:
            for line in f:
                if line.startswith("Umask:"):
                    return int(line.split()[1], 8)
    except (OSError, ValueError, IndexError):
        pass
    with _umask_lock:
        mask = os.umask(0o022)
        os.umask(mask)
    return mask


def ignore_file_size_signal() -> None:
    """Past a file size limit (``ulimit -f``) the kernel sends SIGXFSZ, whose default action
    kills the process (with a core dump) in the middle of a write, leaving its temporary file
    behind. Ignored, the write fails with EFBIG instead, which the writers report as one line.
    Only the main thread may set a handler, and a handler someone else installed is kept."""
    sig = getattr(signal, "SIGXFSZ", None)
    if sig is None or threading.current_thread() is not threading.main_thread():
        return
    try:
        if signal.getsignal(sig) == signal.SIG_DFL:
            signal.signal(sig, signal.SIG_IGN)
    except (ValueError, OSError):
        pass


def write_error(exc: OSError, path: Path) -> InputError:
    """A failed write as the one-line error the command line prints (no traceback)."""
    reason = exc.strerror or str(exc)
    if exc.errno == errno.EFBIG:
        reason += " (a file size limit, ulimit -f?)"
    return InputError(f"cannot write: {reason}", file=str(path))


def _write_file(fd: int, data: str | bytes) -> None:
    mode = "wb" if isinstance(data, bytes) else "w"
    with os.fdopen(fd, mode, **({} if mode == "wb" else {"encoding": "utf-8", "newline": ""})) as f:
        f.write(data)
        f.flush()
        os.fsync(f.fileno())


def write_atomic(path: str | os.PathLike[str], data: str | bytes) -> Path:
    """Write ``data`` to ``path`` via a temporary file in the same folder and a rename. A
    failure (no space, a file size limit, a folder in the way) is :class:`InputError` naming
    ``path``, and leaves no temporary file."""
    path = Path(path)
    ignore_file_size_signal()
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".tmp", dir=path.parent)
    except OSError as exc:
        raise write_error(exc, path) from None
    try:
        os.fchmod(fd, 0o666 & ~current_umask())
        _write_file(fd, data)
        os.replace(tmp, path)
    except BaseException as exc:
        Path(tmp).unlink(missing_ok=True)
        if isinstance(exc, OSError):
            raise write_error(exc, path) from None
        raise
    return path


def write_folder_atomic(
    path: str | os.PathLike[str], files: Iterable[tuple[str, str | bytes]]
) -> list[Path]:
    """Write ``files`` (name, content) as the folder ``path``, all or nothing: into a temporary
    folder beside it, then renamed into place. An existing ``path`` is replaced only as a whole
    (it is renamed aside, the new one renamed in, the old one removed), so an interruption
    leaves either the previous folder or the complete new one, and no temporary folder.

    The caller checks beforehand (:func:`check_output_dir` with ``replaceable``) that an
    existing ``path`` holds nothing but files it may replace. Modes follow the umask, as
    ``mkdir`` and ``open`` would give them."""
    path = Path(os.path.abspath(path))
    parent = path.parent
    ignore_file_size_signal()
    umask = current_umask()
    try:
        parent.mkdir(parents=True, exist_ok=True)
        tmp = Path(tempfile.mkdtemp(prefix=f".{path.name}.", suffix=".tmp", dir=parent))
    except OSError as exc:
        raise write_error(exc, path) from None
    aside: Path | None = None
    current = path
    try:
        os.chmod(tmp, 0o777 & ~umask)
        names = []
        for name, data in files:
            current = path / name
            # A private, fresh folder: plain creation, the umask gives the mode.
            _write_file(os.open(tmp / name, os.O_WRONLY | os.O_CREAT | os.O_EXCL, 0o666), data)
            names.append(name)
        current = path
        _fsync_dir(tmp)
        if path.exists() or path.is_symlink():
            aside = tmp.with_suffix(".old")
            os.rename(path, aside)
        os.rename(tmp, path)
    except BaseException as exc:
        if aside is not None and not path.exists():
            os.rename(aside, path)  # the previous folder back in place
            aside = None
        shutil.rmtree(tmp, ignore_errors=True)
        if isinstance(exc, OSError):
            raise write_error(exc, current) from None
        raise
    if aside is not None:
        shutil.rmtree(aside, ignore_errors=True)
    _fsync_dir(parent)
    return [path / name for name in names]


def _fsync_dir(folder: Path) -> None:
    """Make a rename in ``folder`` durable (where the platform lets a folder be opened)."""
    try:
        fd = os.open(folder, os.O_RDONLY)
    except OSError:
        return
    try:
        os.fsync(fd)
    except OSError:
        pass
    finally:
        os.close(fd)


def _probe_folder(folder: Path, flag: str, shown: Path) -> None:
    """Refuse unless a file can be created in ``folder`` (the nearest existing ancestor of the
    output). A real attempt, not ``os.access``: root passes ``access`` on read-only mounts."""
    if not folder.is_dir():
        raise InputError(f"{folder} is not a folder", file=str(shown), field=flag)
    try:
        with tempfile.TemporaryFile(dir=folder):
            pass
    except OSError as exc:
        reason = exc.strerror or str(exc)
        message = f"cannot write in {folder}: {reason}"
        raise InputError(message, file=str(shown), field=flag) from None


def _existing_ancestor(path: Path) -> Path:
    p = path.absolute()
    while not p.exists():
        if p.parent == p:
            break
        p = p.parent
    return p


def check_output_file(path: str | os.PathLike[str], flag: str = "--out") -> Path:
    """``path`` as a file to be written later: not a folder, and in an existing folder we can
    write in (a file name is not asked to create folders: a mistyped folder would otherwise
    appear silently). Raises :class:`InputError` otherwise."""
    path = Path(path)
    if path.is_dir():
        raise InputError("is a folder, expected a file name", file=str(path), field=flag)
    folder = path.parent
    _probe_folder(_existing_ancestor(folder), flag, path)
    if not folder.is_dir():
        raise InputError(
            f"folder {folder} does not exist (create it first; a file name creates no folders)",
            file=str(path),
            field=flag,
        )
    return path


def check_output_dir(
    path: str | os.PathLike[str],
    flag: str = "--out",
    replaceable: Iterable[str] | None = None,
) -> Path:
    """``path`` as a folder to write files into later: a folder (or creatable as one) that we
    can write in. Raises :class:`InputError` otherwise.

    With ``replaceable`` (the names of the files the command writes) the folder is to be
    written whole by :func:`write_folder_atomic`, which replaces an existing one: it must then
    be absent, empty, or hold only regular files of those names (an earlier run's output), so
    that nothing else of the user's is ever removed with it."""
    path = Path(path)
    if path.exists() and not path.is_dir():
        raise InputError("is a file, expected a folder", file=str(path), field=flag)
    if replaceable is None:
        _probe_folder(_existing_ancestor(path), flag, path)
        return path
    full = Path(os.path.abspath(path))
    if full.parent == full:
        raise InputError("cannot replace the root folder", file=str(path), field=flag)
    try:
        holds_cwd = full.exists() and Path.cwd().resolve().is_relative_to(full.resolve())
    except OSError:
        holds_cwd = False
    if holds_cwd:
        raise InputError(
            "is the current folder (or holds it): name a folder for the outputs",
            file=str(path),
            field=flag,
        )
    if full.is_dir():
        allowed = set(replaceable)
        try:
            entries = sorted(os.scandir(full), key=lambda e: e.name)
        except OSError as exc:
            raise InputError(
                f"cannot read the folder: {exc.strerror or exc}", file=str(path), field=flag
            ) from None
        for entry in entries:
            if entry.name not in allowed or not entry.is_file(follow_symlinks=False):
                what = "a folder" if entry.is_dir(follow_symlinks=False) else "an entry"
                raise InputError(
                    f"holds {what} {entry.name!r} that gcs-planner does not write; the "
                    "output folder is replaced as a whole, so name a new or empty folder (or "
                    "one an earlier `plan --out` wrote)",
                    file=str(path),
                    field=flag,
                )
    _probe_folder(_existing_ancestor(full.parent), flag, path)
    return path
