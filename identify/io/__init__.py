"""Files in and out: recordings (CSV/NPZ), raw controller logs and their column maps, motor-side files, drive-gain files.

Import from the modules of this package (or from `identify` for the public API)."""
