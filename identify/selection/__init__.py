"""Selection: the blocked cross-validation against the raw measured torques and what it chooses (the
processing, the torque offsets, the prior's weight λ).

Import from the modules of this package (or from `identify` for the public API)."""
