"""Hyperparameter search for the calibrators with scikit-learn's search tools.

:func:`search_calibrator` runs :class:`~sklearn.model_selection.GridSearchCV`
(every combination) or :class:`~sklearn.model_selection.RandomizedSearchCV`
(``n_iter`` draws) over a registry model's parameters, scored with the
thesis' metric (:func:`ftcal.neg_scaled_rmse`, eq. 18: the best model has the
lowest torque-scaled RMSE on the held-out folds). With groups (e.g. the load
configuration of each sample of a robot experiment) the folds are
:class:`~sklearn.model_selection.GroupKFold`, so a model is judged on loads
it never saw; otherwise shuffled :class:`~sklearn.model_selection.KFold`.

:data:`DEFAULT_SEARCH_SPACES` holds the documented search space per model:
width, depth, learning rate and epochs for the networks, the ridge penalty,
the polynomial degree and the hybrid's power-law exponents. Ensembles search
their members' parameters (``estimator__lr``, ...).

:func:`parse_search_space` reads the command line's form, ``KEY=VALUES``
with ``VALUES`` a JSON list (grid) or ``loguniform(a, b)``,
``uniform(a, b)``, ``randint(a, b)`` (distributions for the randomized
search); inner lists become tuples (``hidden_layer_sizes``, ``powers``).
"""

from __future__ import annotations

import json
import math
import re
from collections.abc import Iterable, Mapping
from typing import Any

import numpy as np
from numpy.typing import ArrayLike
from scipy import stats
from sklearn import config_context
from sklearn.model_selection import GridSearchCV, RandomizedSearchCV

from ..core._files import plain_json
from ..core._exceptions import CalibrationInputError, Placeholder
from ..core._metrics import neg_scaled_rmse
from ..model_selection._selection import calibration_folds, routed_groups
from ._registry import registered_search_spaces

__all__ = ["DEFAULT_SEARCH_SPACES", "search_calibrator", "parse_search_space", "search_summary"]

#: Search space of each registry model (a grid; also usable by the randomized search), as each registration
#: declares it (:func:`~ftcal.register_calibrator`'s ``search_space``): a snapshot taken at import, see
#: :func:`~ftcal.compose._registry.registered_search_spaces` for the live one.
DEFAULT_SEARCH_SPACES: dict[str, dict[str, list]] = registered_search_spaces()

#: Each distribution of the randomized search by name: the scipy distribution of its bounds (a, b), and what the
#: bounds must satisfy (scipy only fails when sampling, with "Domain error").
_DISTRIBUTIONS = {
    "loguniform": (stats.loguniform, lambda a, b: 0 < a < b, "0 < a < b"),
    "uniform": (lambda a, b: stats.uniform(a, b - a), lambda a, b: a < b, "a < b"),
    "randint": (lambda a, b: stats.randint(int(a), int(b) + 1),
                lambda a, b: a == int(a) and b == int(b) and a <= b, "integers a <= b"),
}
_DISTRIBUTION = re.compile(r"^\s*(\w+)\s*\(\s*([^,]+?)\s*,\s*([^,]+?)\s*\)\s*$")


def _bounds(name: str, low: str, high: str, where: str) -> tuple[float, float]:
    """The bounds ``low``, ``high`` of distribution ``name`` as floats, checked before any search starts.

    Examples
    --------
    >>> _bounds("loguniform", "1", "0", "lr")
    Traceback (most recent call last):
    ...
    ftcal.core._exceptions.CalibrationInputError: lr: loguniform(a, b) needs 0 < a < b; got a = 1, b = 0
    """
    try:
        a, b = float(low), float(high)
    except ValueError:
        raise CalibrationInputError(f"{where}: {name}(a, b) takes two numbers, e.g. {name}(1e-4, 1e-2)") from None
    if not (math.isfinite(a) and math.isfinite(b)):
        raise CalibrationInputError(f"{where}: {name}(a, b) needs finite bounds; got a = {low}, b = {high}")
    _, rule, text = _DISTRIBUTIONS[name]
    if not rule(a, b):
        raise CalibrationInputError(f"{where}: {name}(a, b) needs {text}; got a = {low}, b = {high}")
    return a, b


def _tuples(value):
    return tuple(_tuples(v) for v in value) if isinstance(value, list) else value


def parse_search_space(entries: Iterable[str]) -> dict[str, Any]:
    """Search space from ``KEY=VALUES`` strings (the CLI's ``--grid``).

    Examples
    --------
    >>> space = parse_search_space(["degree=[2, 3]", "hidden_layer_sizes=[[64, 64], [32]]"])
    >>> space
    {'degree': [2, 3], 'hidden_layer_sizes': [(64, 64), (32,)]}
    >>> [float(b) for b in parse_search_space(["lr=loguniform(1e-4, 1e-2)"])["lr"].support()]
    [0.0001, 0.01]
    """
    space: dict[str, Any] = {}
    for text in entries:
        key, sep, values = str(text).partition("=")
        key = key.strip()
        if not sep or not key.replace("__", "_").isidentifier():
            raise CalibrationInputError(f"search entry {text!r} is not KEY=VALUES, e.g. 'lr=[1e-4, 1e-3]'.")
        match = _DISTRIBUTION.match(values)
        if match:
            name, low, high = match.groups()
            if name not in _DISTRIBUTIONS:
                raise CalibrationInputError(
                    f"search entry {text!r}: unknown distribution {name!r}; use one of {sorted(_DISTRIBUTIONS)}."
                )
            space[key] = _DISTRIBUTIONS[name][0](*_bounds(name, low, high, f"search entry {text!r}"))
            continue
        try:
            parsed = json.loads(values)
        except json.JSONDecodeError:
            parsed = None
        if not isinstance(parsed, list) or not parsed:
            raise CalibrationInputError(
                f"search entry {text!r}: give a non-empty JSON list of values, e.g. '{key}=[1, 2]', or a "
                f"distribution such as '{key}=loguniform(1e-4, 1e-2)'."
            )
        space[key] = [_tuples(v) for v in parsed]
    return space


def search_calibrator(model: str, X: ArrayLike, y: ArrayLike, *, space: Mapping[str, Any] | None = None,
                      n_iter: int | None = None, cv: int = 3, groups: ArrayLike | None = None, schedule: str = "short",
                      random_state: int | None = 0, n_jobs: int | None = None, **params):
    """Search a registry model's hyperparameters; returns the fitted scikit-learn search object.

    Parameters
    ----------
    model : str
        Registry name (:data:`~ftcal.compose.CALIBRATOR_NAMES`).
    X : array-like of shape (n, N)
        Raw readings.
    y : array-like of shape (n, 6)
        Wrenches [N] / [N·m].
    space : mapping or None
        ``{param: list of values}`` (or scipy distributions with ``n_iter``);
        ``None`` uses :data:`DEFAULT_SEARCH_SPACES` of ``model``.
    n_iter : int or None
        ``None``: grid search over every combination; an int: randomized
        search with that many draws.
    cv : int, default=3
        Number of folds.
    groups : array-like of shape (n,) or None
        Group of each sample (e.g. load configuration); folds keep groups
        whole, and each fold's training groups reach the calibrators that
        request them (metadata routing: the hybrid's ``ridge="auto"``,
        ``auto``, wrappers of them).
    schedule : {"short", "thesis"}, default="short"
        Training schedule the networks start from (a searched parameter
        overrides it).
    random_state : int or None, default=0
        Seed of the folds, the randomized draws and the models.
    n_jobs : int or None
        joblib workers of the search.
    **params
        Fixed parameters of the model (e.g. ``alpha``, ``zero_reading``).

    Returns
    -------
    GridSearchCV or RandomizedSearchCV
        Refitted on all data: ``best_params_``, ``best_score_`` (minus the RMSE
        [N]), ``best_estimator_``, ``cv_results_``.

    Examples
    --------
    >>> import numpy as np
    >>> rng = np.random.default_rng(0)
    >>> raw = rng.uniform(-1, 1, size=(120, 6))
    >>> wrench = 100 * (raw + 0.2 * raw**3)
    >>> search = search_calibrator("polynomial", raw, wrench, space={"degree": [1, 3]}, cv=3)
    >>> search.best_params_
    {'degree': 3}
    """
    from ._registry import make_calibrator

    estimator = make_calibrator(model, schedule=schedule, random_state=random_state, **params)
    if space is None:
        spaces = registered_search_spaces()
        if model not in spaces:
            raise CalibrationInputError(f"no default search space for {model!r}.", parameter="space",
                                        fix="pass {space}",
                                        settings={"space": Placeholder("{param: values}")})
        space = spaces[model]
    space = dict(space)
    if not space:
        raise CalibrationInputError("the search space is empty; give at least one parameter and its values.")
    valid = estimator.get_params(deep=True)
    unknown = sorted(set(space) - set(valid))
    if unknown:
        raise CalibrationInputError(
            f"{type(estimator).__name__} has no parameter(s) {unknown}; searchable: "
            f"{sorted(k for k in valid if not k.endswith('random_state'))}."
        )
    if isinstance(cv, bool) or not isinstance(cv, (int, np.integer)) or cv < 2:
        raise CalibrationInputError(f"cv must be an integer >= 2 (number of folds); got {cv!r}.")
    if groups is not None:
        groups = np.asarray(groups)
        n_groups = np.unique(groups).size
        if n_groups < cv:
            raise CalibrationInputError(f"groups has {n_groups} distinct values; {{cv}} {cv} folds need at least {cv}.",
                                        parameter="cv", value=cv, fix=f"ask for at most {n_groups} folds ({{cv}}) or "
                                        "record more groups", settings={"cv": int(n_groups)})
    # the folds of every model choice in ftcal: whole groups held out, else shuffled k-fold
    folds = calibration_folds(len(X), groups, int(cv), random_state)
    common = dict(scoring=neg_scaled_rmse, cv=folds, n_jobs=n_jobs, refit=True, error_score="raise")
    if n_iter is None:
        bad = [k for k, v in space.items() if not isinstance(v, (list, tuple))]
        if bad:
            raise CalibrationInputError(f"grid search needs lists of values; {bad} are distributions: give n_iter.")
        search = GridSearchCV(estimator, space, **common)
    else:
        if isinstance(n_iter, bool) or not isinstance(n_iter, (int, np.integer)) or n_iter < 1:
            raise CalibrationInputError(f"n_iter must be an integer >= 1; got {n_iter!r}.")
        search = RandomizedSearchCV(estimator, space, n_iter=int(n_iter), random_state=random_state, **common)
    # the groups already shaped the folds above (whole groups held out), whatever the calibrator requests; through
    # scikit-learn's metadata routing they also reach the calibrator when it requests them (the hybrid's and auto's
    # own cross-validation inside each fit then hold out whole groups too), and only then: the precomputed folds
    # consume nothing, so passing groups nobody requests would be refused by the routing
    fit_params = routed_groups(estimator, groups)
    with config_context(enable_metadata_routing=True if fit_params else None):  # None: the user's setting stays
        return search.fit(X, y, **fit_params)


def search_summary(search) -> dict[str, Any]:
    """Plain-JSON summary of a fitted search: best parameters and RMSE, every candidate ranked.

    ``rmse_mean`` / ``rmse_std`` are over the folds, in [N] (torque-scaled, eq. 18).
    """
    res = search.cv_results_
    order = np.argsort(res["rank_test_score"], kind="stable")
    candidates = [
        {
            "rank": int(res["rank_test_score"][i]),
            "params": {k: plain_json(v) for k, v in res["params"][i].items()},
            "rmse_mean": float(-res["mean_test_score"][i]),
            "rmse_std": float(res["std_test_score"][i]),
            "fit_seconds_mean": float(res["mean_fit_time"][i]),
        }
        for i in order
    ]
    return {
        "best_params": {k: plain_json(v) for k, v in search.best_params_.items()},
        "best_rmse": float(-search.best_score_),
        "n_candidates": len(candidates),
        "n_folds": int(search.n_splits_),
        "candidates": candidates,
    }
