"""Lazy public namespaces (PEP 562): a package lists its public names and the private modules holding them,
and the names that moved elsewhere (each still answers, with a :class:`FutureWarning`, for one release)."""

from __future__ import annotations

import sys
import warnings
from collections.abc import Callable, Iterable, Mapping
from importlib import import_module

__all__ = ["lazy_namespace", "moved_name_warning"]


def moved_name_warning(old: str, new: str) -> FutureWarning:
    """The warning of a public name ``old`` (dotted) that now lives at ``new``.

    Examples
    --------
    >>> str(moved_name_warning("ftcal.icosphere", "ftcal.robot.icosphere"))[:53]
    'ftcal.icosphere moved to ftcal.robot.icosphere; the o'
    """
    return FutureWarning(f"{old} moved to {new}; the old name is a deprecated alias that will be removed in the "
                         f"next release: import it from {new.rsplit('.', 1)[0]}")


def lazy_namespace(package: str, names: Mapping[str, str], moved: Mapping[str, str] | None = None,
                   subpackages: Iterable[str] = ()) -> tuple[Callable[[str], object], Callable[[], list[str]]]:
    """``__getattr__`` and ``__dir__`` for ``package`` that import ``names[attr]`` (a submodule) on first use.

    Keeps ``import ftcal`` and ``import ftcal.<package>`` light: torch and pinocchio load only when a name
    that needs them is used. ``names`` values are module paths relative to ``package``. A resolved name is
    stored in the package, so later look-ups do not come here.

    ``moved`` maps a name that used to be public here to its public path now (absolute and dotted, e.g.
    ``"ftcal.robot.icosphere"``; the last part may be a new name): each access returns that object and warns
    with a :class:`FutureWarning` (never stored, so every access warns); ``__dir__`` does not list it.
    ``subpackages`` are imported on first access (``ftcal.robot`` after only ``import ftcal``).

    Examples
    --------
    >>> getattr_, dir_ = lazy_namespace("ftcal.core", {"mean_std": "_metrics"})
    >>> getattr_("mean_std").__name__
    'mean_std'
    """
    moved, subpackages = dict(moved or {}), frozenset(subpackages)

    def __getattr__(name: str):
        module = names.get(name)
        if name in subpackages:
            return import_module(f"{package}.{name}")  # the import binds it in the package
        if module is None:
            new = moved.get(name)
            if new is None:
                raise AttributeError(f"module {package!r} has no attribute {name!r}")
            warnings.warn(moved_name_warning(f"{package}.{name}", new), stacklevel=2)
            home, _, attribute = new.rpartition(".")
            return getattr(import_module(home), attribute)
        value = getattr(import_module(f"{package}.{module}"), name)
        setattr(sys.modules[package], name, value)  # later look-ups skip this function
        return value

    def __dir__() -> list[str]:
        return sorted(set(vars(sys.modules[package])) | set(names) | subpackages)

    return __getattr__, __dir__
