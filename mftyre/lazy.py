"""Imports paid for when first used, so that ``import mftyre`` and the command line start without pandas, lmfit,
scipy, matplotlib or CasADi (``benchmarks/bench_startup.py`` measures what each command costs to start).

* :class:`LazyModule`: ``pd = LazyModule("pandas")`` at the top of a module instead of ``import pandas as pd``;
  pandas is imported at the first attribute access (``pd.DataFrame``), i.e. when a function needs it.
* :func:`export_lazily`: a package's face (its ``__init__``'s names) imported from its submodules when first used
  (PEP 562), so that importing one light submodule (``mftyre.fit.command`` for ``mftyre fit --help``) does not
  import the heavy ones.
"""
from __future__ import annotations

import importlib
import sys
import types

__all__ = ["LazyModule", "export_lazily"]


class LazyModule:
    """Stands for the module ``name``; imports it at the first attribute access and keeps what was looked up."""

    def __init__(self, name: str):
        self._name = name

    def __getattr__(self, attribute: str):  # called only for names not yet kept
        value = getattr(importlib.import_module(self._name), attribute)
        setattr(self, attribute, value)
        return value

    def __repr__(self) -> str:
        return f"<module {self._name!r}, imported when first used>"


def export_lazily(package: str, exports: dict[str, str]) -> None:
    """Give the package ``package`` the names ``exports`` (name -> submodule it is defined in), each imported when
    first used (``mftyre.fit.fit_tir``, ``from mftyre.fit import fit_tir``).

    A name that is also its submodule's name (``mftyre.gaps.locate``, the function in ``mftyre/gaps/locate.py``)
    stays the function when the submodule is imported, as after an eager ``from .locate import locate``."""
    module = sys.modules[package]

    def load(name):
        return getattr(importlib.import_module(f"{package}.{exports[name]}"), name)

    def __getattr__(self, name):
        if name not in exports:
            raise AttributeError(f"module {package!r} has no attribute {name!r}")
        value = load(name)
        self.__dict__[name] = value
        return value

    namespace = {"__getattr__": __getattr__, "__dir__": lambda self: sorted(set(self.__dict__) | set(exports))}
    # the import system sets a package's attribute to each submodule it imports; for these names that is refused
    namespace.update({name: property(lambda self, name=name: load(name), lambda self, value: None)
                      for name, where in exports.items() if name == where})
    module.__class__ = type("LazyPackage", (types.ModuleType,), namespace)
