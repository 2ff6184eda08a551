"""The identified model at work on a stream or a log: payload monitoring (the paper's conclusion).

Import from the modules of this package (or from `identify` for the public API)."""
