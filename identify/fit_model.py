"""Deprecated address: the fit file's records live in :mod:`identify.fit_file`."""
from identify.fit_file import FitModel, robot_file_hash, toolkit_version  # noqa: F401

__all__ = ["FitModel", "robot_file_hash", "toolkit_version"]
