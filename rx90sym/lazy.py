"""Lazy public names of a package: a name is imported from its module on first use.

A command that only prints its help must not pay for CasADi, SciPy or cvxpy (seconds on a small
machine): each package's ``__init__`` lists where its public names live and calls
:func:`lazy_package`; ``import package`` then costs nothing until a name is used.
"""
from __future__ import annotations

import importlib
import sys
import types
from typing import Mapping

__all__ = ["lazy_package"]


def lazy_package(name: str, exports: Mapping[str, str], submodules: tuple[str, ...] = ()) -> None:
    """Give package ``name`` the attributes ``exports`` (public name -> module it is defined in,
    or "module:attribute" when the public name is an alias) and ``submodules`` (imported on first
    use), resolved when first read."""
    package = sys.modules[name]
    table = dict(exports)

    class LazyPackage(types.ModuleType):
        def __getattr__(self, attr: str):
            if attr in submodules:
                return importlib.import_module(f"{name}.{attr}")
            source = table.get(attr)
            if source is None:
                raise AttributeError(f"module {name!r} has no attribute {attr!r}")
            module, _, original = source.partition(":")
            value = getattr(importlib.import_module(module), original or attr)
            types.ModuleType.__setattr__(self, attr, value)
            return value

        def __setattr__(self, attr: str, value) -> None:
            # Importing submodule X.f binds it as attribute f of X: where f is also a public name
            # (identify.payload the function, identify/payload.py the module), the name wins.
            if attr in table and isinstance(value, types.ModuleType) and value.__name__ == f"{name}.{attr}":
                return
            types.ModuleType.__setattr__(self, attr, value)

        def __dir__(self) -> list[str]:
            return sorted(set(self.__dict__) | set(table) | set(submodules))

    package.__class__ = LazyPackage
