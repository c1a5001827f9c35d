"""The one fold rule of ftcal: :class:`FoldPlan`, the folds every held-out figure is judged on.

``auto``'s comparison, the save gate of ``ftcal fit`` and the calibration certificate all build their folds with
:meth:`FoldPlan.for_data`, so they always judge a model on the same rows and agree on its verdict.
"""

from __future__ import annotations

import hashlib
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray
from sklearn.model_selection import GroupKFold

from ..core._exceptions import CalibrationInputError
from ..core._wrench import WRENCH_LABELS
from ._selection import calibration_folds, check_groups, unseen_outputs

__all__ = ["FoldPlan"]


@dataclass(frozen=True, eq=False)
class FoldPlan:
    """The judging folds of a dataset, the unit of their standard errors and a sentence saying how they were made.

    Build it with :meth:`for_data` (the one fold rule); never by hand but in tests.

    Attributes
    ----------
    folds : tuple of (train, test) int arrays
        Empty when no folds can judge a model (``kind == "none"``).
    units : ndarray of shape (n_rows,) or None
        The standard-error unit of each row: its group label when the folds hold out whole groups, else the
        index of the fold that tests it. ``None`` without folds.
    kind : str
        ``"group"`` (whole groups held out), ``"kfold"`` (shuffled folds over the rows, repeated rows kept
        together), ``"ordered"`` (contiguous blocks of rows: a time series read by a load-history model),
        ``"replaced"`` (grouped folds that could not judge, replaced by folds over the rows) or ``"none"``.
    note : str
        One sentence for a report: what the folds are and why.
    cv : int
        Folds asked for (capped by the groups or the rows).
    seed : int
        Seed of the shuffled folds.
    n_rows : int

    Examples
    --------
    >>> X = np.arange(40.0).reshape(20, 2); y = np.column_stack([X[:, 0], X[:, 1] ** 2])
    >>> plan = FoldPlan.for_data(X, y, groups=np.repeat(np.arange(5), 4))
    >>> plan.kind, plan.n_splits, plan.units_name
    ('group', 5, 'group')
    >>> FoldPlan.for_data(X, y).kind
    'kfold'
    """

    folds: tuple
    units: NDArray | None
    kind: str
    note: str
    cv: int
    seed: int
    n_rows: int

    @property
    def n_splits(self) -> int:
        """Number of folds (0 when none can judge)."""
        return len(self.folds)

    @property
    def units_name(self) -> str:
        """What the standard errors are over: ``"group"`` or ``"fold"`` (``"row"`` for a plan without units)."""
        if self.units is None:
            return "row"
        return "group" if self.kind == "group" else "fold"

    def fingerprint(self) -> str:
        """SHA-256 (hex) of the folds' test rows: two plans with the same fingerprint judge on the same rows."""
        digest = hashlib.sha256(repr((self.kind, self.n_rows)).encode("ascii"))
        for _, test in self.folds:
            digest.update(np.ascontiguousarray(np.sort(np.asarray(test)), dtype=np.int64).tobytes() + b"|")
        return digest.hexdigest()

    def same_folds(self, other: "FoldPlan | dict | None") -> bool:
        """Whether ``other`` (a plan, or its :meth:`to_dict`) tests the very same rows in the same folds."""
        if other is None:
            return False
        theirs = other.to_dict() if isinstance(other, FoldPlan) else dict(other)
        return theirs.get("fingerprint") == self.fingerprint() and theirs.get("n_rows") == self.n_rows

    def to_dict(self) -> dict:
        """JSON-able facts of the plan (no arrays): kind, note, cv, seed, rows, folds, units and fingerprint."""
        return {"kind": self.kind, "note": self.note, "cv": int(self.cv), "seed": int(self.seed),
                "n_rows": int(self.n_rows), "n_splits": self.n_splits, "units_name": self.units_name,
                "n_units": None if self.units is None else int(np.unique(self.units).size),
                "fingerprint": self.fingerprint()}

    def with_seed(self, seed: int, X: ArrayLike, y: ArrayLike, groups: ArrayLike | None = None) -> "FoldPlan | None":
        """The same rule with another seed (grouped folds: the groups shuffled), or None when another seed gives
        the same folds (as many groups as folds, or contiguous blocks)."""
        if self.kind in ("none", "ordered"):
            return None
        if self.kind == "group":
            g = np.asarray(groups)
            if np.unique(g).size <= self.n_splits:
                return None
            splitter = GroupKFold(n_splits=min(int(self.cv), np.unique(g).size), shuffle=True, random_state=seed)
            folds = list(splitter.split(np.arange(self.n_rows), groups=g))  # the groups shuffled by ``seed``
            if unseen_outputs(np.asarray(y, dtype=float), folds):
                return None
            return FoldPlan(tuple(folds), self.units, "group", self.note, self.cv, int(seed), self.n_rows)
        plan = FoldPlan.for_data(X, y, None, cv=self.cv, seed=seed)
        return FoldPlan(plan.folds, plan.units, self.kind, self.note, self.cv, int(seed), self.n_rows)

    def to_state(self) -> dict:
        """:meth:`to_dict` plus the fold of each row and the units: what a model file keeps to rebuild the plan."""
        fold_of = np.full(self.n_rows, -1, dtype=np.int64)
        for i, (_, test) in enumerate(self.folds):
            fold_of[np.asarray(test)] = i
        units = None if self.units is None else np.asarray(self.units).tolist()
        return {**self.to_dict(), "fold_of_row": fold_of.tolist(), "units": units}

    @classmethod
    def from_state(cls, state: dict) -> "FoldPlan":
        """The plan :meth:`to_state` describes (its folds rebuilt from the fold of each row)."""
        fold_of = np.asarray(state["fold_of_row"], dtype=np.int64)
        rows = np.arange(fold_of.size)
        folds = tuple((rows[fold_of != i], rows[fold_of == i]) for i in range(int(state["n_splits"])))
        units = None if state.get("units") is None else np.asarray(state["units"])
        plan = cls(folds, units, str(state["kind"]), str(state["note"]), int(state["cv"]), int(state["seed"]),
                   int(state["n_rows"]))
        if state.get("fingerprint") not in (None, plan.fingerprint()):
            raise ValueError("the stored folds do not match their fingerprint")
        return plan

    @classmethod
    def for_data(cls, X: ArrayLike, y: ArrayLike, groups: ArrayLike | None = None, *, cv: int = 5, seed: int = 0,
                 ordered: bool = False) -> "FoldPlan":
        """THE fold rule of ftcal: the folds that can judge a model on these data.

        1. With ``groups`` (at least 2 labels): whole groups held out (:func:`calibration_folds`, ``GroupKFold``).
        2. If a grouped training fold leaves an output (nearly) unseen (:func:`unseen_outputs`: one group per
           loaded axis, so holding out the ``Fx`` group leaves no ``Fx`` load to learn), those folds cannot judge
           a model: folds over the rows replace them (``kind="replaced"``, said in ``note``); if even those
           cannot, ``kind="none"`` and no folds (a caller keeps the LTM unscored, or skips its held-out check).
        3. Without groups: shuffled k-fold over the rows with ``seed``, repeated rows (the same reading and
           wrench) kept in one fold (a copy on both sides of a split flatters every model that interpolates);
           ``ordered=True``: contiguous blocks of rows instead (a load-history model reads its rows in time order).

        The standard errors of every comparison on the plan are over its ``units``: the groups when whole groups
        are held out, else the folds.

        Parameters
        ----------
        X : array-like of shape (n, N)
        y : array-like of shape (n, k)
        groups : array-like of shape (n,) or None
        cv : int, default=5
            Folds (capped by the groups or the distinct rows).
        seed : int, default=0
        ordered : bool, default=False
            Rows are a time series: contiguous blocks, never shuffled.

        Returns
        -------
        FoldPlan

        Examples
        --------
        >>> y = np.repeat(np.eye(6)[:3] * 10, 5, axis=0) * np.tile(np.linspace(-1, 1, 5), 3)[:, None]
        >>> X = y[:, :3] + np.random.default_rng(0).normal(size=(15, 3))
        >>> plan = FoldPlan.for_data(X, y, np.repeat([0, 1, 2], 5))  # one group per loaded axis
        >>> plan.kind, plan.n_splits, plan.units_name
        ('replaced', 5, 'fold')
        """
        X = np.asarray(X, dtype=float)
        y = np.asarray(y, dtype=float).reshape(len(X), -1)
        n = len(y)
        seed = 0 if seed is None else int(seed)
        groups = check_groups(groups, n) if groups is not None and np.unique(np.asarray(groups)).size >= 2 else None
        names = WRENCH_LABELS if y.shape[1] == 6 else None
        cv_used = min(int(cv), n)
        if cv_used < 2:
            raise CalibrationInputError(f"cv must be an integer >= 2 and the data need at least 2 rows; got cv={cv!r} "
                                        f"and {n} rows.")
        unseen: list[str] = []
        if groups is not None:
            folds = calibration_folds(n, groups, cv_used, seed, shuffle=not ordered)
            unseen = unseen_outputs(y, folds, names)
            if not unseen:
                note = (f"group: whole groups held out, {len(folds)} folds over {np.unique(groups).size} groups; "
                        "standard errors over the groups")
                return cls(tuple(folds), np.asarray(groups), "group", note, int(cv), seed, n)
        copies = None
        if not ordered:
            _, copies = np.unique(np.column_stack([X, y]), axis=0, return_inverse=True)
            copies = copies.ravel() if np.unique(copies).size < n else None
        distinct = n if copies is None else int(np.unique(copies).size)
        if distinct < 2:
            raise CalibrationInputError(f"X and y hold {n} copies of one row; record different loads.")
        folds = calibration_folds(n, copies, min(cv_used, distinct), seed, shuffle=not ordered)
        units = np.empty(n, dtype=np.int64)
        for i, (_, test) in enumerate(folds):
            units[test] = i
        if ordered:
            kind, how = "ordered", f"ordered: {len(folds)} contiguous blocks of rows (a time series, never shuffled)"
        else:
            kind = "kfold"
            how = f"kfold: {len(folds)} shuffled folds over the rows (seed {seed})" if copies is None else \
                f"kfold: {len(folds)} shuffled folds over the {distinct} distinct rows (seed {seed}; repeated rows " \
                "kept together)"
        how += "; standard errors over the folds"
        if groups is None:
            return cls(tuple(folds), units, kind, how, int(cv), seed, n)
        what = f"{', '.join(unseen)} {'is' if len(unseen) == 1 else 'are'} missing from a training fold"
        if not unseen_outputs(y, folds, names):
            note = (f"replaced: the grouped folds cannot judge a model ({what}, e.g. one group per loaded axis); "
                    f"{how}")
            return cls(tuple(folds), units, "replaced", note, int(cv), seed, n)
        note = (f"none: no folds can judge a model ({what} even in folds over the rows); record each axis' loads in "
                "more than one group and more rows")
        return cls((), None, "none", note, int(cv), seed, n)
