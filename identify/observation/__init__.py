"""The observation matrix (eqs. 6-8), rest phases, spring columns.

Import from the modules of this package (or from `identify` for the public API)."""
