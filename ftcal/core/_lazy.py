"""Lazy public namespaces (PEP 562): a package lists its public names and the private modules holding them."""

from __future__ import annotations

import sys
from collections.abc import Callable, Iterable, Mapping
from importlib import import_module

__all__ = ["lazy_namespace"]


def lazy_namespace(package: str, names: Mapping[str, str],
                   subpackages: Iterable[str] = ()) -> tuple[Callable[[str], object], Callable[[], list[str]]]:
    """``__getattr__`` and ``__dir__`` for ``package`` that import ``names[attr]`` (a submodule) on first use.

    Keeps ``import ftcal`` and ``import ftcal.<package>`` light: torch and pinocchio load only when a name
    that needs them is used. ``names`` values are module paths relative to ``package``. A resolved name is
    stored in the package, so later look-ups do not come here. ``subpackages`` are imported on first access
    (``ftcal.robot`` after only ``import ftcal``).

    Examples
    --------
    >>> getattr_, dir_ = lazy_namespace("ftcal.core", {"mean_std": "_metrics"})
    >>> getattr_("mean_std").__name__
    'mean_std'
    """
    subpackages = frozenset(subpackages)

    def __getattr__(name: str):
        if name in subpackages:
            return import_module(f"{package}.{name}")  # the import binds it in the package
        module = names.get(name)
        if module is None:
            raise AttributeError(f"module {package!r} has no attribute {name!r}")
        value = getattr(import_module(f"{package}.{module}"), name)
        setattr(sys.modules[package], name, value)  # later look-ups skip this function
        return value

    def __dir__() -> list[str]:
        return sorted(set(vars(sys.modules[package])) | set(names) | subpackages)

    return __getattr__, __dir__
