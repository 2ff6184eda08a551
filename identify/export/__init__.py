"""A fit's identified model out: URDF and MJCF with actuator terms.

Import from the modules of this package (or from `identify` for the public API)."""
