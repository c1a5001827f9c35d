"""Registry of calibrators by name, and the named training schedules.

Benchmarks and the CLI build every model through :func:`make_calibrator`, so
a new model only has to be registered with :func:`register_calibrator` to
appear everywhere. This is the one registry: the built-in calibrators are
listed at the end of this module by module and class *name*, and imported
only when one is built, so that listing the names (``ftcal --help``) does not
import torch.

Schedules (:func:`training_schedule`), counts in epochs:

=============  =========  ==============  ================  ===================
schedule        model      ``phase1_epochs``  ``plateau_epochs``  ``max_recover_epochs``
=============  =========  ==============  ================  ===================
``"thesis"``   directional  1700           100               500
``"thesis"``   comparative  3000           100               500
``"short"``    directional  150            30                50
``"short"``    comparative  250            30                50
=============  =========  ==============  ================  ===================

Both use Adam with ``lr = 1e-3``, ``batch_size = 32``, ``min_lr = 1e-5``,
``plateau_factor = 0.1``, ``recover_tolerance = 0.05`` and
``validation_fraction = 0.2``; the patience is 30 (thesis) or 10 (short).
The thesis stops phase 3 only by the 5 % rule; 500 is our hard cap. The
short schedule (at most 230 / 330 epochs) is for quick benchmark runs; it
keeps the comparative model's longer phase 1 in about the thesis' ratio.
The linear model has no schedule (``{}``).
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
import inspect
from typing import Any

from importlib import import_module

__all__ = ["CALIBRATOR_NAMES", "calibrator_parameters", "make_calibrator", "register_calibrator", "training_schedule",
           "SCHEDULE_NAMES", "registered_candidates", "registered_search_spaces"]

#: Names accepted by :func:`training_schedule` and ``make_calibrator(schedule=...)``.
SCHEDULE_NAMES: tuple[str, ...] = ("thesis", "short")

_COMMON = dict(lr=1e-3, batch_size=32, plateau_factor=0.1, min_lr=1e-5, recover_tolerance=0.05, validation_fraction=0.2)
_THESIS = dict(_COMMON, plateau_epochs=100, plateau_patience=30, max_recover_epochs=500)
_SHORT = dict(_COMMON, plateau_epochs=30, plateau_patience=10, max_recover_epochs=50)

_FACTORIES: dict[str, Callable[..., Any]] = {}


class _Lazy:
    """A factory named by module (dotted, inside ``ftcal``) and attribute, imported on first use.

    Keeps heavy imports (torch) out of listings such as ``ftcal fit --help``.
    """

    def __init__(self, module: str, attribute: str, ensemble_of: str | None = None):
        self.module, self.attribute, self.ensemble_of = module, attribute, ensemble_of

    def target(self) -> Any:
        """The attribute itself (a class), imported now."""
        return getattr(import_module(f"ftcal.{self.module}"), self.attribute)

    def resolve(self) -> Callable[..., Any]:
        target = self.target()
        if self.ensemble_of is not None:
            from ._ensemble import ensemble_factory

            return ensemble_factory(target)
        return target


def _factory(name: str) -> Callable[..., Any]:
    factory = _FACTORIES[name]
    if isinstance(factory, _Lazy):
        factory = _FACTORIES[name] = factory.resolve()
    return factory
_SCHEDULES: dict[str, dict[str, dict[str, Any]]] = {}
#: name -> ``[(complexity, label, params)]``: the candidates of ``auto`` each registration brings.
_CANDIDATES: dict[str, list[tuple[float, str, dict[str, Any]]]] = {}
#: name -> its search space (``ftcal tune``, :func:`~ftcal.compose.search_calibrator`).
_SEARCH_SPACES: dict[str, dict[str, list]] = {}


class _RegisteredNames(Sequence):
    """Tuple-like live view of the registered calibrator names (in registration order).

    It follows later :func:`register_calibrator` calls; ``tuple(CALIBRATOR_NAMES)`` is a snapshot.
    """

    def __getitem__(self, index):
        return tuple(_FACTORIES)[index]

    def __len__(self) -> int:
        return len(_FACTORIES)

    def __eq__(self, other) -> bool:
        return tuple(self) == (tuple(other) if isinstance(other, (tuple, _RegisteredNames)) else other)

    __hash__ = None

    def __repr__(self) -> str:
        return repr(tuple(_FACTORIES))


#: Names accepted by :func:`make_calibrator` (a live, tuple-like view).
CALIBRATOR_NAMES = _RegisteredNames()


def register_calibrator(
    name: str,
    factory: Callable[..., Any],
    *,
    schedules: Mapping[str, Mapping[str, Any]] | None = None,
    overwrite: bool = False,
    candidates: Sequence[tuple[float, str, Mapping[str, Any]]] = (),
    search_space: Mapping[str, Sequence] | None = None,
) -> None:
    """Make ``make_calibrator(name, ...)`` build ``factory(random_state=..., **params)``.

    This one line is all a new calibrator needs besides its module: the CLI's model lists, model files (a
    class), the ONNX export (its ``_emit_onnx``), ``auto``'s candidates (``candidates``), the search spaces
    (``search_space``) and the test suite's list of calibrators follow from the registry, and what the model can
    do from its tags (:class:`~ftcal.calibrators._base.CalibrationTags`).

    Parameters
    ----------
    name : str
        Registry name, e.g. ``"polynomial"``.
    factory : callable
        Usually the estimator class; it must accept ``random_state`` and the
        keyword parameters of the schedules.
    schedules : mapping or None
        ``{schedule_name: params}`` for :func:`training_schedule`; schedules
        not listed give ``{}`` (a model without a training schedule).
    overwrite : bool, default=False
        Replace an existing registration instead of raising ``ValueError``.
    candidates : sequence of (complexity, label, params)
        What :class:`~ftcal.AutoCalibrator` tries by default: ``make_calibrator(name, **params)`` named ``label``,
        placed by ``complexity`` (the LTM is 10, the polynomials 20-31, the hybrid 40, the GP 50, the networks
        60-70; lower is simpler). Params with ``group_offsets=True`` make a twin tried only on grouped data.
    search_space : mapping or None
        Its default grid for ``ftcal tune`` / :func:`~ftcal.compose.search_calibrator` (parameter -> values).

    Examples
    --------
    >>> from ftcal import LinearCalibrator
    >>> register_calibrator("ridge_ltm", lambda **p: LinearCalibrator(ridge=1e-3, **p))
    >>> "ridge_ltm" in CALIBRATOR_NAMES
    True
    >>> _ = _FACTORIES.pop("ridge_ltm")
    """
    if not isinstance(name, str) or not name:
        raise ValueError(f"calibrator name must be a non-empty string; got {name!r}.")
    if not callable(factory) and not isinstance(factory, _Lazy):
        raise ValueError(f"factory for {name!r} must be callable; got {factory!r}.")
    if name in _FACTORIES and not overwrite:
        raise ValueError(f"a calibrator named {name!r} is already registered; pass overwrite=True to replace it.")
    unknown = set(schedules or {}) - set(SCHEDULE_NAMES)
    if unknown:
        raise ValueError(f"unknown schedule name(s) {sorted(unknown)}; known: {SCHEDULE_NAMES}.")
    _FACTORIES[name] = factory
    _SCHEDULES[name] = {k: dict(v) for k, v in (schedules or {}).items()}
    _CANDIDATES[name] = [(float(c), str(label), dict(params)) for c, label, params in candidates]
    if search_space is not None:
        _SEARCH_SPACES[name] = {k: list(v) for k, v in search_space.items()}
    else:
        _SEARCH_SPACES.pop(name, None)


def registered_candidates(grouped: bool = False) -> list[tuple[str, str, dict[str, Any]]]:
    """``(registry name, label, params)`` of every registered ``auto`` candidate, simplest first (by complexity,
    then registration order); the twins with ``group_offsets=True`` only when ``grouped``.

    Examples
    --------
    >>> [label for _, label, _ in registered_candidates()][:2]
    ['linear', 'polynomial(degree=2, ridge=0.01)']
    """
    entries = [(c, i, name, label, params) for i, (name, listed) in enumerate(_CANDIDATES.items())
               for c, label, params in listed if grouped or not params.get("group_offsets")]
    return [(name, label, params) for *_, name, label, params in sorted(entries, key=lambda e: (e[0], e[1]))]


def registered_search_spaces() -> dict[str, dict[str, list]]:
    """Registry name -> default search space, for every registration that declares one (a fresh dict)."""
    return {name: {k: list(v) for k, v in space.items()} for name, space in _SEARCH_SPACES.items()}


def _check_name(model: str) -> None:
    if model not in _FACTORIES:
        raise ValueError(f"unknown calibrator {model!r}; choose one of {tuple(_FACTORIES)}.")


def training_schedule(name: str, model: str) -> dict[str, Any]:
    """Constructor parameters of the named schedule for the named model (a fresh dict).

    Examples
    --------
    >>> training_schedule("thesis", "comparative")["phase1_epochs"]
    3000
    >>> training_schedule("short", "linear")
    {}
    """
    if name not in SCHEDULE_NAMES:
        raise ValueError(f"unknown schedule {name!r}; choose one of {SCHEDULE_NAMES}.")
    _check_name(model)
    return dict(_SCHEDULES[model].get(name, {}))


def calibrator_parameters(name: str) -> tuple[str, ...]:
    """The keyword parameters ``make_calibrator(name, ...)`` accepts (besides ``schedule`` and ``random_state``).

    Examples
    --------
    >>> "phase1_epochs" in calibrator_parameters("directional_ensemble")
    True
    """
    _check_name(name)
    signature = inspect.signature(_factory(name))
    return tuple(p for p, v in signature.parameters.items()
                 if v.kind is not inspect.Parameter.VAR_KEYWORD and p != "random_state")


def make_calibrator(name: str, schedule: str = "thesis", random_state=None, **params) -> Any:
    """A new, unfitted calibrator by registry name with the named schedule.

    ``params`` override the schedule's values (e.g. ``hidden_layer_sizes``).

    Examples
    --------
    >>> make_calibrator("directional", schedule="short", random_state=0).phase1_epochs
    150
    >>> make_calibrator("linear", ridge=0.1)
    LinearCalibrator(ridge=0.1)
    """
    known = calibrator_parameters(name)
    unknown = sorted(set(params) - set(known))
    if unknown:
        raise ValueError(f"{name} has no parameter {unknown[0]!r}; its parameters are: {', '.join(sorted(known))}.")
    merged = {**training_schedule(schedule, name), **params}
    return _factory(name)(random_state=random_state, **merged)


_DIRECTIONAL = {"thesis": dict(_THESIS, phase1_epochs=1700), "short": dict(_SHORT, phase1_epochs=150)}
_COMPARATIVE = {"thesis": dict(_THESIS, phase1_epochs=3000), "short": dict(_SHORT, phase1_epochs=250)}
_NETWORK_SPACE = {
    "hidden_layer_sizes": [(32, 32), (64, 64), (64, 64, 64), (128, 128, 128)],
    "lr": [3e-4, 1e-3, 3e-3],
    "phase1_epochs": [150, 400, 1000],
}
_ENSEMBLE_SPACE = {f"estimator__{k}": v for k, v in _NETWORK_SPACE.items()}
register_calibrator("linear", _Lazy("calibrators._linear", "LinearCalibrator"), candidates=[(10, "linear", {})],
                    search_space={"ridge": [0.0, 1e-6, 1e-3, 1.0]})
register_calibrator("comparative", _Lazy("networks._comparative", "ComparativeCalibrator"), schedules=_COMPARATIVE,
                    candidates=[(70, "comparative", {"random_state": 0})], search_space=_NETWORK_SPACE)
register_calibrator("directional", _Lazy("networks._directional", "DirectionalCalibrator"), schedules=_DIRECTIONAL,
                    candidates=[(60, "directional", {"random_state": 0})], search_space=_NETWORK_SPACE)
register_calibrator("polynomial", _Lazy("calibrators._polynomial", "PolynomialCalibrator"), candidates=[
    # with groups, the LTM and the mildest quadratic are each followed by a twin with one offset per group
    (11, "linear(group offsets)", {"degree": 1, "group_offsets": True}),
    (20, "polynomial(degree=2, ridge=0.01)", {"degree": 2, "ridge": 1e-2}),
    (21, "polynomial(degree=2, ridge=0.01, group offsets)", {"degree": 2, "ridge": 1e-2, "group_offsets": True}),
    (22, "polynomial(degree=2, ridge=0.0001)", {"degree": 2, "ridge": 1e-4}),
    (30, "polynomial(degree=3, ridge=0.01)", {"degree": 3, "ridge": 1e-2}),
    (31, "polynomial(degree=3, ridge=0.0001)", {"degree": 3, "ridge": 1e-4}),
], search_space={"degree": [2, 3, 4, 5], "ridge": [1e-6, 1e-4, 1e-3, 1e-2]})
register_calibrator("axis_nonlinear", _Lazy("calibrators._axis_nonlinear", "AxisNonlinearCalibrator"),
                    candidates=[(40, "axis_nonlinear", {})],
                    search_space={"powers": [(), (1.0,), (1.5,), (2.0,), (1.0, 2.0)], "ridge": [1e-6, 1e-3, 1e-1]})
register_calibrator("gaussian_process", _Lazy("calibrators._gaussian_process", "GaussianProcessCalibrator"),
                    candidates=[(50, "gaussian_process", {"random_state": 0})])
# the stock scikit-learn baselines every table shows, as a model of their own: stock(baseline="sk_gp")
register_calibrator("stock", _Lazy("calibrators._baselines", "StockCalibrator"),  # its grid: every stock baseline
                    search_space={"baseline": ["sk_linear", "sk_poly2", "sk_poly3", "sk_kernel_ridge", "sk_gp"]})
# ensembles: the schedule and every other parameter go to the members, n_members and n_jobs to the ensemble
register_calibrator("directional_ensemble", _Lazy("networks._directional", "DirectionalCalibrator", ensemble_of="directional"),
                    schedules=_DIRECTIONAL, search_space=_ENSEMBLE_SPACE)
register_calibrator("comparative_ensemble", _Lazy("networks._comparative", "ComparativeCalibrator", ensemble_of="comparative"),
                    schedules=_COMPARATIVE, search_space=_ENSEMBLE_SPACE)
# "auto" chooses among the names above; its schedule goes to its network candidates
register_calibrator("auto", _Lazy("compose._auto", "AutoCalibrator"), schedules={n: {"schedule": n} for n in SCHEDULE_NAMES})


#: Meta-estimators that wrap registered calibrators without being registry names themselves.
_WRAPPERS: tuple[_Lazy, ...] = (
    _Lazy("compose._ensemble", "EnsembleCalibrator"),
    _Lazy("compose._temperature_compensation", "TemperatureCompensatedCalibrator"),
    _Lazy("compose._history", "HistoryCalibrator"),
    _Lazy("compose._auto", "StackedCalibrator"),
)


def model_class(name: str) -> type | None:
    """The class of :func:`model_classes` called ``name``, importing only its own module (``None`` if none is).

    Saving a linear model then never imports the networks' torch.

    Examples
    --------
    >>> model_class("LinearCalibrator").__name__, model_class("os")
    ('LinearCalibrator', None)
    """
    for attribute, load in _class_places():
        if attribute == name:
            return load()
    return None


def _class_places() -> list[tuple[str, Callable[[], Any]]]:
    """``(class name, loader)`` of every class :func:`model_classes` lists, wrappers first; nothing imported."""
    places = [(lazy.attribute, lazy.target) for lazy in _WRAPPERS]
    for factory in list(_FACTORIES.values()):
        if isinstance(factory, _Lazy):
            places.append((factory.attribute, factory.target))
        elif isinstance(factory, type):
            places.append((factory.__name__, lambda f=factory: f))
    return places


def model_classes() -> dict[str, type]:
    """The calibrator classes of the registry by class name: the only types model files may name.

    Model files (:func:`~ftcal.save_model`) and the ONNX export
    (:func:`~ftcal.export_onnx`) read the fitted state and the graph each class
    declares next to itself (``_fitted_state``, ``_emit_onnx``); this is the
    list of classes they trust, so a file never names code to run. A
    calibrator registered by class (or by a lazy module/class name) is in it;
    one registered by a function is not (save it by registering its class).

    Examples
    --------
    >>> sorted(model_classes())[:3]
    ['AutoCalibrator', 'AxisNonlinearCalibrator', 'ComparativeCalibrator']
    """
    classes: dict[str, type] = {}
    for _, load in _class_places():
        target = load()
        if isinstance(target, type):
            classes.setdefault(target.__name__, target)
    return classes
