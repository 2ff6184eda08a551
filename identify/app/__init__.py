"""The application on top of the method: the ``rx90`` command line, the demo and the HTML report.

It imports the method (``identify``, ``excitation``, ``rx90sym``); the method never imports it.
"""
from typing import Any

__all__ = ["build_parser", "main"]


def __getattr__(name: str) -> Any:
    # Imported on first use, so that ``python -m identify.app.cli`` runs the module once
    # (an eager import here makes runpy warn that the module is already in sys.modules).
    if name in __all__:
        from . import cli

        return getattr(cli, name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
