"""Atomic file writes: a file is either absent, the old one, or complete — never half-written.

Files are created with the permissions the user's umask gives a new file (``0o666 & ~umask``),
as ``open()`` would, not the 0600 of the temporary file they are written through. The checks
``check_output_file`` / ``check_output_dir`` let a command refuse an output path it could never
write *before* it spends minutes computing what to write there.
"""

from __future__ import annotations

import os
import tempfile
import threading
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


def write_atomic(path: str | os.PathLike[str], data: str | bytes) -> Path:
    """Write ``data`` to ``path`` via a temporary file in the same folder and a rename."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    mode = "wb" if isinstance(data, bytes) else "w"
    fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".tmp", dir=path.parent)
    try:
        os.fchmod(fd, 0o666 & ~current_umask())
        with os.fdopen(
            fd, mode, **({} if mode == "wb" else {"encoding": "utf-8", "newline": ""})
        ) as f:
            f.write(data)
            f.flush()
            os.fsync(f.fileno())
        os.replace(tmp, path)
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise
    return path


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
    """``path`` as a file to be written later: not a folder, and in a folder we can write in
    (or can create). Raises :class:`InputError` otherwise."""
    path = Path(path)
    if path.is_dir():
        raise InputError("is a folder, expected a file name", file=str(path), field=flag)
    _probe_folder(_existing_ancestor(path.parent), flag, path)
    return path


def check_output_dir(path: str | os.PathLike[str], flag: str = "--out") -> Path:
    """``path`` as a folder to write files into later: a folder (or creatable as one) that we
    can write in. Raises :class:`InputError` otherwise."""
    path = Path(path)
    if path.exists() and not path.is_dir():
        raise InputError("is a file, expected a folder", file=str(path), field=flag)
    _probe_folder(_existing_ancestor(path), flag, path)
    return path
