"""Atomic file writing: the target gets the whole content or is left as it was.

Every writer of the project (recordings, trajectories, JSON results, reports) goes through
``atomic_write``: a temporary file in the target's folder (same file system, so ``os.replace``
is atomic), flushed to disk, then renamed over the target; on any error it is removed.
"""
from __future__ import annotations

import hashlib
import json
import os
import tempfile
from pathlib import Path
from typing import IO, Any, Callable


def atomic_write(path: str | os.PathLike, write: Callable[[IO], None], binary: bool = False) -> Path:
    """Call ``write(handle)`` on a temporary file, then rename it to ``path``."""
    target = Path(path)
    if not target.parent.is_dir():
        raise ValueError(f"cannot write {target}: folder {target.parent} does not exist")
    fd, tmp = tempfile.mkstemp(prefix=f".{target.name}.", suffix=".tmp", dir=target.parent)
    try:
        # mkstemp creates the file private (0600); give the result ordinary data-file permissions.
        os.chmod(tmp, (target.stat().st_mode & 0o777) if target.exists() else 0o644)
        with os.fdopen(fd, "wb" if binary else "w", encoding=None if binary else "utf-8",
                       newline=None if binary else "\n") as handle:
            write(handle)
            handle.flush()
            os.fsync(handle.fileno())
        os.replace(tmp, target)
    except BaseException:
        try:
            os.unlink(tmp)
        except FileNotFoundError:
            pass
        raise
    return target


def write_json(path: str | os.PathLike, content: Any) -> Path:
    """Indented JSON, atomically; NaN/inf are refused (turn them into null first)."""
    text = json.dumps(content, indent=1, allow_nan=False)
    return atomic_write(path, lambda handle: handle.write(text + "\n"))


def read_json(path: str | os.PathLike) -> Any:
    """The JSON content of ``path``; ValueError naming the file (and the line and column)."""
    try:
        with open(path, encoding="utf-8") as fh:
            return json.load(fh)
    except json.JSONDecodeError as exc:
        raise ValueError(f"{path}: not valid JSON (line {exc.lineno}, column {exc.colno}: {exc.msg})") from None
    except OSError as exc:
        raise ValueError(f"{path}: cannot read ({exc.strerror or exc})") from None


def file_sha256(path: str | os.PathLike) -> str | None:
    """SHA-256 (hex) of a file's bytes; None when it is not a readable file (a recording built in memory)."""
    p = Path(path)
    try:
        return hashlib.sha256(p.read_bytes()).hexdigest() if p.is_file() else None
    except OSError:
        return None
