"""Lazy public namespaces (PEP 562): a package lists its public names and the private modules holding them."""

from __future__ import annotations

from collections.abc import Callable
from importlib import import_module

__all__ = ["lazy_namespace"]


def lazy_namespace(package: str, names: dict[str, str]) -> tuple[Callable[[str], object], Callable[[], list[str]]]:
    """``__getattr__`` and ``__dir__`` for ``package`` that import ``names[attr]`` (a submodule) on first use.

    Keeps ``import ftcal.<package>`` as light as its docstring: torch and pinocchio load only when a name
    that needs them is used.

    Examples
    --------
    >>> getattr_, dir_ = lazy_namespace("ftcal.core", {"mean_std": "_metrics"})
    >>> getattr_("mean_std").__name__
    'mean_std'
    """

    def __getattr__(name: str):
        module = names.get(name)
        if module is None:
            raise AttributeError(f"module {package!r} has no attribute {name!r}")
        return getattr(import_module(f"{package}.{module}"), name)

    def __dir__() -> list[str]:
        return sorted(names)

    return __getattr__, __dir__
