"""Defaults of reading recordings and logs (standard library only: ``rx90 --help`` shows them
without importing the readers)."""
from __future__ import annotations

__all__ = ["DEFAULT_BLOCK", "DEFAULT_LOG_BLOCK", "DEFAULT_MAX_GAP"]

#: Default block: raw samples per block core of the block-wise fit (60 s at 1 kHz). Peak memory of
#: ``rx90 identify`` on a 7-joint arm with 69 parameters is then about 0.9-1.1 GB (docs/long-logs.md),
#: whatever the log's length.
DEFAULT_BLOCK = 60_000
#: Lines per block of :func:`identify.io.log_blocks.convert_log` (≈ 30 MB of text for a 15-column log).
DEFAULT_LOG_BLOCK = 200_000
#: Longest gap (s) bridged by interpolation; a longer one starts a new segment (identify.io.gaps).
DEFAULT_MAX_GAP = 0.05
