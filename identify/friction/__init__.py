"""Friction: the forms of the moving rows (Coulomb, tanh, Stribeck) and their columns, the velocity
scales and presliding travels searched on a fit's rows, and the form chosen per joint by the blocked
cross-validation.

Import from the modules of this package (or from `identify` for the public API)."""
