"""The identified model in a simulator: the MJCF ``rx90 export --mjcf`` writes, rolled out in MuJoCo from
the recorded state at the start of each window while the arm moves, under the recorded joint torques,
scored at the window's end beside the constant-velocity guess and the description's own bodies
(:mod:`identify.rollout.run`; docs/rollout.md). It comes before the fit in the data flow: a
:class:`identify.Fit` predicts with it (``Fit.predict(..., rollout=...)``) and hands it its own model
(:func:`identify.rollout.model.simulator_parameters`) and processing.

Import from the modules of this package (or from `identify` for the public API)."""
