"""Drive gains (current to torque) identified with a payload of known mass.

Import from the modules of this package (or from `identify` for the public API)."""
