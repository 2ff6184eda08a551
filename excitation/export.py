"""Trajectory CSV export, written atomically through rx90sym.files (whole file or nothing)."""
from __future__ import annotations

import os
from pathlib import Path
from typing import TextIO

import numpy as np

from rx90sym.files import atomic_write


def write_csv(path: str | os.PathLike, header: list[str], rows: np.ndarray, fmt: str = "%.10g") -> Path:
    """CSV with one header line and ``rows`` (N, len(header)); refuses NaN/inf."""
    rows = np.asarray(rows, dtype=float)
    if rows.ndim != 2 or rows.shape[1] != len(header):
        raise ValueError(f"{path}: {rows.shape} data for {len(header)} columns")
    if not np.all(np.isfinite(rows)):
        raise ValueError(f"{path}: refusing to write non-finite values")

    def write(handle: TextIO) -> None:
        handle.write(",".join(header) + "\n")
        np.savetxt(handle, rows, fmt=fmt, delimiter=",")

    return atomic_write(path, write)
