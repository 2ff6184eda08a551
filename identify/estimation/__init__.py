"""Estimation: QR compression, (weighted) least squares with statistics (eqs. 9-15), essential parameters, bootstrap, physical consistency.

Import from the modules of this package (or from `identify` for the public API)."""
