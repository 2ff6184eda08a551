"""The fit: one identification from recordings (:func:`identify.fit`), its file, prediction and validation, plausibility flags, fleets.

Import from the modules of this package (or from `identify` for the public API)."""
