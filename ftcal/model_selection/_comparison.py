"""The one comparison engine of ftcal: any regressors scored on one :class:`FoldPlan`, as a typed
:class:`Comparison` with paired differences in symmetric words.

``compare`` scores the cheap models (closed forms, kernel models on few rows: their tags' ``cost``) on every
fold first, then races the costly ones (networks, kernel models on many rows, models of unknown cost): each is
fitted on the first fold and stopped when it cannot come within one standard error of the best; the survivors are
scored on every fold. ``AutoCalibrator`` is ``compare`` plus the one-standard-error rule; ``ftcal benchmark``
prints the same rows and words.
"""

from __future__ import annotations

import enum
import logging
import time
import warnings
from dataclasses import dataclass, field
from typing import Any, Callable, Sequence

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..core._exceptions import CalibrationInputError
from ..core._wrench import scale_torques
from ._plan import FoldPlan
from ._selection import (MIN_SE_GROUPS, TIE_TOLERANCE, degenerate_reason, fold_predictions, mean_and_se, paired_excess,
                         rmse_and_se, simplest_within_one_se, tie_margin, choice_beats_simplest)

__all__ = ["RowStatus", "ComparisonRow", "Comparison", "PairedDifference", "ChoiceStability", "compare",
           "choice_stability", "model_cost", "race_stop", "LIGHT_KERNEL_ROWS", "COST_TIERS", "TIER_STEP"]

LOGGER = logging.getLogger("ftcal")

#: Training rows up to which a kernel model's fit is light work (scored with the closed forms, never raced).
LIGHT_KERNEL_ROWS = 200
#: Complexity tier of each cost (the one-SE rule's order): a closed form before a kernel model before a model of
#: unknown cost before a network, whatever their names.
COST_TIERS = {"closed_form": 0, "kernel": 1, "heavy": 2, "network": 3}
#: Complexity step of one tier: positions within a tier never reach the next tier.
TIER_STEP = 1000.0
#: Standard errors of a raced candidate's excess on its first fold that must lie beyond the stopping margin.
RACE_SIGMAS = 2.0


class RowStatus(enum.Enum):
    """What became of a row of a comparison."""

    #: Scored on every fold.
    SCORED = "scored"
    #: Not fitted: could not be judged (too few training rows, over the memory or work budget).
    SKIPPED = "skipped"
    #: Its fit or predict raised.
    FAILED = "failed"
    #: Raced out early: on its first fold it could not come within one standard error of the best.
    STOPPED = "stopped"


@dataclass(eq=False)  # rows hold arrays: compare their to_dict() figures, not the objects
class ComparisonRow:
    """One model of a :class:`Comparison`.

    ``rmse`` is the torque-scaled whole-wrench RMSE (eq. 18) [N] of its out-of-fold predictions, ``rmse_se`` its
    standard error over the plan's units; ``complexity`` orders the one-SE rule (lower is simpler: the cost tier,
    then the position). ``eligible`` is False for a row that is reported only (a baseline) or refused (degenerate
    held-out predictions, said in ``reason``). ``verdict``, ``excess_mse`` and ``excess_se`` are set by
    :meth:`Comparison.choose`.
    """

    name: str
    kind: str
    status: RowStatus
    reason: str | None = None
    rmse: float | None = None
    rmse_se: float | None = None
    axis_rmse: NDArray | None = None
    predictions: NDArray | None = field(default=None, repr=False)
    seconds: float = 0.0
    complexity: float = 0.0
    eligible: bool = True
    row_errors: NDArray | None = field(default=None, repr=False)
    verdict: str = ""
    excess_mse: float | None = None
    excess_se: float | None = None
    #: this row against the chosen one in symmetric words (:meth:`PairedDifference.words`), set by ``choose``
    against: str = ""

    @property
    def status_text(self) -> str:
        """``scored``, or the status and its reason (``skipped: ...``, ``stopped: ...``, ``refused: ...``)."""
        if self.status is RowStatus.SCORED:
            return self.reason if self.reason else "scored"
        return f"{self.status.value}: {self.reason}" if self.reason else self.status.value


@dataclass(frozen=True)
class PairedDifference:
    """Two rows of one comparison compared on the same folds, ``a`` relative to ``b``.

    ``difference = rmse_a - rmse_b`` [N]; ``paired_se`` the standard error of that difference from the per-unit
    differences of their squared errors (groups, or folds; delta method: the MSE difference over
    ``rmse_a + rmse_b``); ``combined_se`` the unpaired ``sqrt(se_a² + se_b²)`` beside it. The rule (symmetric):
    ``noise = max(t · paired_se, TIE_TOLERANCE / 4 · (rmse_a + rmse_b))`` with ``t`` the two-sided 95 % quantile of
    Student's t on (units - 1) degrees of freedom (a direction is named only at 95 % confidence: at one SE, a third
    of true ties would get one), and 0.5 % of the mean RMSE (a gain that small is a tie even when consistent); ``"better"`` when ``difference < -noise``, ``"worse"`` when
    ``difference > noise``, else ``"equivalent"``. Swapping ``a`` and ``b`` negates the difference and mirrors
    the verdict and the words exactly.
    """

    a: str
    b: str
    rmse_a: float
    rmse_b: float
    difference: float
    paired_se: float
    combined_se: float
    verdict: str

    @property
    def percent(self) -> float:
        """``|difference|`` in % of the larger of the two RMSEs (the same number in both orders)."""
        larger = max(self.rmse_a, self.rmse_b)
        return 100.0 * abs(self.difference) / larger if larger > 0 else 0.0

    def words(self) -> str:
        """One sentence, the same facts whichever side is ``a``.

        Examples
        --------
        >>> d = PairedDifference("A", "B", 0.47, 0.51, -0.04, 0.01, 0.05, "better")
        >>> d.words()
        'A is 7.8 % better than B (0.47 vs 0.51 N, paired SE 0.01 N)'
        """
        figures = f"({self.rmse_a:.4g} vs {self.rmse_b:.4g} N, paired SE {self.paired_se:.2g} N)"
        if self.verdict == "equivalent":
            return f"{self.a} and {self.b} are equivalent within noise {figures}"
        return f"{self.a} is {self.percent:.1f} % {self.verdict} than {self.b} {figures}"


def _t95(dof: int) -> float:
    """The two-sided 95 % quantile of Student's t on ``dof`` degrees of freedom (1.96 for many).

    >>> round(_t95(4), 3), round(_t95(10**6), 3)
    (2.776, 1.96)
    """
    from scipy.stats import t

    return float(t.ppf(0.975, max(int(dof), 1)))


@dataclass(frozen=True)
class ChoiceStability:
    """How often the same choice is made on folds with other seeds: ``chosen`` in ``count`` of ``repeats``."""

    chosen: str
    count: int
    repeats: int
    seeds: tuple
    choices: tuple

    def words(self) -> str:
        """E.g. ``"chosen in 4 of 5 repeats (fold seeds 0, 1, 2, 3, 4)"``."""
        return (f"chosen in {self.count} of {self.repeats} repeats (fold seeds "
                f"{', '.join(str(s) for s in self.seeds)})")

    def to_dict(self) -> dict:
        return {"chosen": self.chosen, "count": self.count, "repeats": self.repeats, "seeds": list(self.seeds),
                "choices": list(self.choices), "words": self.words()}


def _short(words: str) -> str:
    """The verdict part of :meth:`PairedDifference.words` for a table cell: ``"2.1 % worse"``, ``"equivalent
    within noise"`` (empty for none)."""
    if "equivalent within noise" in words:
        return "equivalent within noise"
    head = words.split(" (")[0]
    return head.split(" is ")[-1].split(" than ")[0] if " % better than " in head or " % worse than " in head else head


def _number(value) -> float | None:
    return None if value is None else float(value)


@dataclass(eq=False)  # compare to_dict() (what a model file keeps), not the arrays
class Comparison:
    """Rows scored on one :class:`FoldPlan`, the one-SE choice among them and why.

    Attributes
    ----------
    rows : list of ComparisonRow
    plan : FoldPlan or None
        ``None`` for a comparison read back from a model file (its facts are in ``plan_facts``).
    alpha : float
        Torque scale [1/m] of every RMSE.
    chosen, best : str or None
        The one-SE choice and the row of lowest error (:meth:`choose`).
    why : str
        One sentence: why the choice won.
    stability : ChoiceStability or None
    stack_members, stack_weights : list
        A stack row's members and weights, when one was scored.
    training_sha256 : str or None
        Identity of the rows scored (arrays and groups).
    """

    rows: list
    plan: FoldPlan | None
    alpha: float = 1.0
    chosen: str | None = None
    best_name: str | None = None
    why: str = ""
    stability: ChoiceStability | None = None
    stack_members: list = field(default_factory=list)
    stack_weights: list = field(default_factory=list)
    training_sha256: str | None = None
    plan_facts: dict = field(default_factory=dict)
    tie_mse: float | None = None
    min_training_rows: int | None = None
    #: name -> the structure a model that chooses one chose on the first fold's training rows, with which its other
    #: folds were scored (a refit on all rows keeps it; not saved)
    structures: dict = field(default_factory=dict, repr=False)

    # ------------------------------------------------------------------ reading
    def row(self, name: str) -> ComparisonRow:
        """The row called ``name`` (a :class:`KeyError` naming the rows otherwise)."""
        for r in self.rows:
            if r.name == name:
                return r
        raise KeyError(f"no row {name!r} in the comparison; rows: {[r.name for r in self.rows]}")

    def scored(self) -> list[ComparisonRow]:
        """The rows scored on every fold."""
        return [r for r in self.rows if r.status is RowStatus.SCORED]

    def best(self) -> ComparisonRow | None:
        """The eligible scored row of lowest held-out RMSE (None when none is)."""
        return min((r for r in self.scored() if r.eligible and r.rmse is not None), key=lambda r: r.rmse, default=None)

    @property
    def facts(self) -> dict:
        """The plan's :meth:`FoldPlan.to_dict` (kept in model files when the plan's arrays are not)."""
        return self.plan.to_dict() if self.plan is not None else dict(self.plan_facts)

    @property
    def se_units(self) -> str:
        """What the standard errors are over, in words: ``"groups"``, ``"folds"``, ``"rows"``, or with fewer than
        :data:`~ftcal.model_selection._selection.MIN_SE_GROUPS` units ``"rows or groups, the larger (fewer than 5
        groups)"`` (:func:`mean_and_se`)."""
        facts = self.facts
        if facts.get("se_units"):  # an earlier file's words
            return str(facts["se_units"])
        name, count = facts.get("units_name", "row"), facts.get("n_units")
        if name == "row" or count is None or count >= MIN_SE_GROUPS:
            return name + "s"
        return f"rows or {name}s, the larger (fewer than {MIN_SE_GROUPS} {name}s)"

    def _units(self) -> NDArray | None:
        return None if self.plan is None else self.plan.units

    def paired(self, a: str, b: str) -> PairedDifference:
        """``a`` against ``b`` on the same folds (:class:`PairedDifference`); both must be scored.

        Examples
        --------
        >>> from sklearn.linear_model import LinearRegression, Ridge
        >>> rng = np.random.default_rng(0); X = rng.normal(size=(60, 3)); y = X @ rng.normal(size=(3, 2))
        >>> c = compare([("ols", LinearRegression()), ("ridge", Ridge(alpha=30.0))], X, y, FoldPlan.for_data(X, y),
        ...             min_rows=lambda est, n: 5)
        >>> c.paired("ols", "ridge").verdict, c.paired("ridge", "ols").verdict
        ('better', 'worse')
        """
        ra, rb = self.row(a), self.row(b)
        for r in (ra, rb):
            if r.row_errors is None or r.rmse is None:
                raise CalibrationInputError(
                    f"row {r.name!r} has no held-out errors to pair ({r.status_text}); a comparison read from a "
                    "model file keeps its figures, not its errors per row.")
        units = self._units()
        d_mse, se_mse = mean_and_se(ra.row_errors - rb.row_errors, units)
        total = ra.rmse + rb.rmse
        difference = ra.rmse - rb.rmse
        paired_se = se_mse / total if total > 0 else 0.0
        combined = float(np.hypot(ra.rmse_se or 0.0, rb.rmse_se or 0.0))
        n_units = ra.row_errors.size if units is None else np.unique(units).size
        noise = max(_t95(n_units - 1) * paired_se, TIE_TOLERANCE / 4.0 * total)
        verdict = "better" if difference < -noise else "worse" if difference > noise else "equivalent"
        return PairedDifference(a, b, float(ra.rmse), float(rb.rmse), float(difference), float(paired_se), combined,
                                verdict)

    def add_scored(self, name: str, kind: str, predictions: ArrayLike, y: ArrayLike, *, complexity: float,
                   axes=None, index: int | None = None, seconds: float = 0.0) -> ComparisonRow:
        """Add a row made from out-of-fold ``predictions`` on this plan (e.g. a stack of the other rows), scored
        and checked like :func:`compare`'s rows; inserted at ``index`` (default: last)."""
        y = np.asarray(y, dtype=float).reshape(self.plan.n_rows, -1)
        pred = np.asarray(predictions, dtype=float).reshape(y.shape)
        row = ComparisonRow(name=name, kind=kind, status=RowStatus.SCORED, seconds=float(seconds),
                            complexity=float(complexity), eligible=kind != "baseline", predictions=pred)
        _score_row(row, pred, y, self.alpha, axes, self.plan.units)
        self.rows.insert(len(self.rows) if index is None else index, row)
        return row

    # ------------------------------------------------------------------ the one-SE rule
    def choose(self) -> str:
        """Apply the one-standard-error rule (:func:`simplest_within_one_se`) over the eligible scored rows, by
        ``complexity``, cross-validated against the simplest row (:func:`choice_beats_simplest`: a more complex
        choice that does not beat it on the folds it was not chosen on gives way to it); set ``chosen``,
        ``best_name``, every row's ``verdict``, ``excess_mse``, ``excess_se`` and ``why``. Returns the chosen name."""
        rows = self.rows
        n = self.plan.n_rows if self.plan is not None else 0
        errors = np.vstack([r.row_errors if r.status is RowStatus.SCORED and r.row_errors is not None
                            else np.full(n, np.nan) for r in rows])
        eligible = [r.eligible and r.status is RowStatus.SCORED for r in rows]
        if not any(eligible):
            raise CalibrationInputError("no row could be scored and chosen; see each row's reason.")
        units = self._units()
        ranks = np.array([r.complexity for r in rows], dtype=float)
        chosen = simplest_within_one_se(errors, units, complexity=ranks, eligible=eligible)
        overruled = None  # a more complex choice is kept only if choosing by the rule beats the simplest
        if ranks[chosen] > ranks[eligible].min() and self.plan is not None and self.plan.n_splits > 1:
            beats, simplest, gain, gain_se = choice_beats_simplest(errors, units, self.plan.folds, complexity=ranks,
                                                                   eligible=eligible)
            overruled, chosen = (None, chosen) if beats else ((chosen, gain, gain_se), simplest)
        best = int(np.nanargmin([np.mean(errors[k]) if eligible[k] else np.nan for k in range(len(rows))]))
        excess, excess_se, tie = paired_excess(errors, best, units)
        self.tie_mse = float(tie)
        for k, r in enumerate(rows):
            r.excess_mse, r.excess_se = (None, None) if np.isnan(excess[k]) else (float(excess[k]),
                                                                                     float(excess_se[k]))
            if k == chosen:
                r.verdict = "chosen"
            elif overruled and k == overruled[0]:
                r.verdict = "not kept: choosing it did not beat the simplest on the folds it was not chosen on"
            elif not eligible[k]:
                r.verdict = r.status_text if r.status is not RowStatus.SCORED else (r.reason or "reported only")
            elif k == best or excess[k] <= max(excess_se[k], tie):
                r.verdict = ("within one SE, as simple (the lower or earlier wins)" if r.complexity == ranks[chosen]
                             else "within one SE, more complex")
            else:
                r.verdict = "beyond one SE"
        self.chosen, self.best_name = rows[chosen].name, rows[best].name
        for r in rows:
            r.against = self.paired(r.name, self.chosen).words() if r is not rows[chosen] and \
                r.row_errors is not None and r.rmse is not None and r.status is RowStatus.SCORED else ""
        self.why = self._why(chosen, best, int(sum(1 for r in rows if r.verdict.startswith("within")) + 1)) \
            if not overruled else (f"{rows[chosen].name} won, the simplest model: the one-SE rule's choice, "
                                   f"{rows[overruled[0]].name}, is not better than it beyond one paired SE when the "
                                   f"choice is cross-validated (made again without each fold and scored on it: "
                                   f"{rows[chosen].name}'s excess mean squared error over that choice "
                                   f"{overruled[1]:.3g} ± {overruled[2]:.2g} N², SE over the {self.se_units}).")
        return self.chosen

    def _why(self, chosen: int, best: int, n_within: int) -> str:
        rows, unit = self.rows, self.se_units
        c, b = rows[chosen], rows[best]
        if chosen == best:
            why = (f"{c.name} won: the best held-out RMSE ({c.rmse:.4g} ± {c.rmse_se:.2g} N), and no simpler model "
                   f"within one standard error of it (standard errors over the {unit})")
        else:
            why = (f"{c.name} won: the simplest of the {n_within} models within one standard error of the best, "
                   f"{b.name} ({b.rmse:.4g} ± {b.rmse_se:.2g} N; {c.name} {c.rmse:.4g} N; standard errors over "
                   f"the {unit})")
        s = min((r for r in self.scored() if r.kind in ("stock", "baseline") and r.rmse is not None),
                key=lambda r: r.rmse, default=None)
        if s is c:
            why += f". It is the best stock model itself ({s.name})"
        elif s is not None and c.row_errors is not None and s.row_errors is not None:
            why += f"; against the best stock model: {self.paired(c.name, s.name).words()}"
        return why + "."

    # ------------------------------------------------------------------ output
    def to_dict(self) -> dict:
        """JSON-able columns (one list per field, no predictions), close to the comparison dicts of earlier
        versions (``name``, ``kind``, ``status``, ``eligible``, ``rmse``, ``rmse_se``, ``axis_rmse``,
        ``fit_seconds``, ``verdict``, ``chosen``, ``why``, ...), plus ``plan`` and ``stability``."""
        rows = self.rows
        out = {
            "name": [r.name for r in rows], "kind": [r.kind for r in rows],
            "status": [r.status_text for r in rows], "row_status": [r.status.value for r in rows],
            "reason": [r.reason for r in rows], "eligible": [bool(r.eligible) for r in rows],
            "rmse": [_number(r.rmse) for r in rows], "rmse_se": [_number(r.rmse_se) for r in rows],
            "axis_rmse": [None if r.axis_rmse is None else np.asarray(r.axis_rmse, dtype=float).tolist()
                          for r in rows],
            "fit_seconds": [_number(r.seconds) for r in rows], "complexity": [float(r.complexity) for r in rows],
            "verdict": [r.verdict for r in rows], "excess_mse": [r.excess_mse for r in rows],
            "excess_se": [r.excess_se for r in rows], "against": [r.against for r in rows],
            "chosen": self.chosen, "best": self.best_name, "why": self.why, "alpha": float(self.alpha),
            "plan": self.facts, "folds": self._folds_word(), "n_splits": self.facts.get("n_splits", 0),
            "se_units": self.se_units, "tie_mse": self.tie_mse,
            "min_training_rows": self.min_training_rows,
            "stability": None if self.stability is None else self.stability.to_dict(),
            "training_sha256": self.training_sha256,
        }
        if self.stack_members:
            out.update(stack_members=list(self.stack_members), stack_weights=[float(w) for w in self.stack_weights])
        if self.tie_mse is not None and self.best_name is not None:
            out["rule"] = {"best": self.best_name, "tie_mse": self.tie_mse, "units": out["se_units"]}
        return out

    def _folds_word(self) -> str:
        """The ``folds`` column of earlier versions: ``"group"`` or ``"kfold"`` for plain folds, else the note
        (replaced folds, repeated rows kept together, ordered blocks, none)."""
        kind, note = self.facts.get("kind", "none"), str(self.facts.get("note") or "")
        if kind == "group" or (kind == "kfold" and "distinct rows" not in note):
            return kind
        return note or kind

    def to_state(self) -> dict:
        """What a model file keeps: :meth:`to_dict` (read back by :meth:`from_dict`)."""
        return self.to_dict()

    @classmethod
    def from_dict(cls, data: dict) -> "Comparison":
        """A comparison from :meth:`to_dict`, or from the comparison dict of an earlier model file (its
        ``status`` texts read back into :class:`RowStatus`); the plan's arrays and the per-row errors are not
        kept, so :meth:`paired` answers only for a comparison made in this process."""
        names = list(data.get("name") or [])
        get = lambda key, i, default=None: (data.get(key) or [default] * len(names))[i]  # noqa: E731
        rows = []
        for i, name in enumerate(names):
            status_text = str(get("status", i, "scored") or "scored")
            raw = get("row_status", i)
            if raw is None:  # an earlier file: the state was a prefix of the status text
                head, _, rest = status_text.partition(": ")
                status = RowStatus(head) if head in ("skipped", "failed", "stopped") else RowStatus.SCORED
                reason = rest if status is not RowStatus.SCORED else (None if status_text == "scored"
                                                                      else status_text)
            else:
                status, reason = RowStatus(raw), get("reason", i)
            axis = get("axis_rmse", i)
            rows.append(ComparisonRow(
                name=str(name), kind=str(get("kind", i, "candidate")), status=status, reason=reason,
                rmse=_number(get("rmse", i)), rmse_se=_number(get("rmse_se", i)),
                axis_rmse=None if axis is None else np.asarray(axis, dtype=float),
                seconds=float(get("fit_seconds", i) or 0.0), complexity=float(get("complexity", i, i) or 0.0),
                eligible=bool(get("eligible", i, True)), verdict=str(get("verdict", i, "") or ""),
                excess_mse=_number(get("excess_mse", i)), excess_se=_number(get("excess_se", i)),
                against=str(get("against", i, "") or "")))
        plan = data.get("plan") if isinstance(data.get("plan"), dict) else \
            {"kind": str(data.get("folds", "none")).split(":")[0], "n_splits": data.get("n_splits", 0),
             "units_name": "group" if "group" in str(data.get("se_units", "")) else "row",
             "note": str(data.get("folds", "")), "se_units": data.get("se_units")}
        stab = data.get("stability")
        stability = None if not isinstance(stab, dict) else ChoiceStability(
            stab["chosen"], int(stab["count"]), int(stab["repeats"]), tuple(stab.get("seeds", ())),
            tuple(stab.get("choices", ())))
        rule = data.get("rule") if isinstance(data.get("rule"), dict) else {}
        return cls(rows=rows, plan=None, alpha=float(data.get("alpha", 1.0) or 1.0), chosen=data.get("chosen"),
                   best_name=data.get("best") or rule.get("best"), why=str(data.get("why") or ""),
                   stability=stability, stack_members=list(data.get("stack_members") or []),
                   stack_weights=list(data.get("stack_weights") or []), training_sha256=data.get("training_sha256"),
                   plan_facts=plan, tie_mse=_number(data.get("tie_mse", rule.get("tie_mse"))),
                   min_training_rows=data.get("min_training_rows"))

    def __getitem__(self, key: str):
        """Read access to a column of :meth:`to_dict` (``comparison_["rmse"]``), as the dicts of earlier versions."""
        return self.to_dict()[key]

    def get(self, key: str, default=None):
        """``to_dict().get(key, default)``."""
        return self.to_dict().get(key, default)

    def table(self) -> str:
        """The comparison as a markdown table: held-out RMSE ± SE, against the chosen row in symmetric words
        (paired SE on the same folds), seconds, status (stopped rows with why), then why the choice won and how
        stable it is."""
        head = ("| model | kind | held-out RMSE (eq. 18) [N] | ± SE | / best stock model | fit [s] | "
                "excess MSE over best [N²] | ± paired SE [N²] | against the choice | status |")
        lines = [head, "|---" * 10 + "|"]
        best_stock = min((r.rmse for r in self.rows if r.kind in ("stock", "baseline") and r.rmse is not None),
                         default=None)
        num = lambda v, form: "" if v is None else format(v, form)  # noqa: E731
        for r in self.rows:
            mark = " **(chosen)**" if r.name == self.chosen else ""
            ratio = None if r.rmse is None or not best_stock else r.rmse / best_stock
            cells = [num(r.rmse, ".4g"), num(r.rmse_se, ".2g"), num(ratio, ".3f"), num(r.seconds, ".1f"), num(r.excess_mse, ".3g"),
                     num(r.excess_se, ".2g"), _short(r.against), r.verdict or r.status_text]
            lines.append(f"| {r.name}{mark} | {r.kind} | " + " | ".join(cells) + " |")
        units = self.se_units
        if self.tie_mse is not None and self.best_name:
            lines += ["", f"One-SE rule: a row is within one SE of the best ({self.best_name}) when its excess mean "
                          f"squared error over the best is at most its paired SE (the spread of the differences from "
                          f"the best over the {units}, not the row's own ± SE) or the tie margin {self.tie_mse:.3g} "
                          f"N² ({100 * TIE_TOLERANCE:g} % of the best's). 'Against the choice' says better or worse "
                          "only beyond the paired SE of the RMSE difference."]
        stopped = [r for r in self.rows if r.status is RowStatus.STOPPED]
        if stopped:
            lines += ["", "Stopped early (raced out): " + "; ".join(f"{r.name}: {r.reason}" for r in stopped) + "."]
        if self.facts.get("note"):
            lines += ["", f"Folds: {self.facts['note']}."]
        if self.stability is not None:
            lines += ["", f"Stability: {self.stability.chosen} {self.stability.words()}."]
        if self.why:
            lines += ["", self.why]
        return "\n".join(lines)


# ---------------------------------------------------------------------- the engine
def _ftcal_tags(estimator) -> Any:
    try:
        tags = estimator.__sklearn_tags__() if hasattr(estimator, "__sklearn_tags__") else None
    except Exception:  # a regressor whose tags need fitted state: unknown capabilities
        tags = None
    return getattr(tags, "ftcal", None)


def model_cost(estimator, training_rows: int | None = None) -> str:
    """What a fit of ``estimator`` costs, from its tags (``cost``): ``"closed_form"``, ``"kernel"``,
    ``"network"`` or ``"heavy"`` (unknown: any regressor without ftcal's tags); with ``training_rows``, a kernel
    model on at most :data:`LIGHT_KERNEL_ROWS` rows counts as ``"closed_form"`` (light work).

    Examples
    --------
    >>> from sklearn.linear_model import LinearRegression
    >>> model_cost(LinearRegression())
    'heavy'
    """
    cost = getattr(_ftcal_tags(estimator), "cost", "heavy")
    if cost == "kernel" and training_rows is not None and training_rows <= LIGHT_KERNEL_ROWS:
        return "closed_form"
    return cost if cost in COST_TIERS else "heavy"


def _min_rows(estimator, n_channels: int) -> int:
    rule = getattr(_ftcal_tags(estimator), "min_training_rows", None)
    return int(rule(n_channels)) if callable(rule) else 25 * int(n_channels)


def _chooses_structure(estimator) -> bool:
    tags = _ftcal_tags(estimator)
    return bool(getattr(tags, "chooses_structure", False)) and not getattr(tags, "network", False) \
        and hasattr(estimator, "structure_params")


def _stacked(estimator) -> bool:
    """A network that trains its folds as one stacked fit (its tags: ``network`` and ``stackable``)."""
    tags = _ftcal_tags(estimator)
    return bool(getattr(tags, "network", False) and getattr(tags, "stackable", False))


def _row_errors(pred: NDArray, y: NDArray, alpha: float, axes=None) -> NDArray:
    """Per-row mean of the squared torque-scaled errors: their mean is eq. 18's MSE."""
    return np.mean((scale_torques(pred, alpha, axes) - scale_torques(y, alpha, axes)) ** 2, axis=1)


def _score_row(row: ComparisonRow, pred: NDArray, y: NDArray, alpha: float, axes, units, refuse: bool = True
               ) -> None:
    """Fill ``row``'s errors, RMSE ± SE and per-axis RMSE from its out-of-fold ``pred``; a degenerate one is kept
    but made ineligible, the reason said."""
    row.row_errors = _row_errors(pred, y, alpha, axes)
    row.rmse, row.rmse_se = rmse_and_se(row.row_errors, units)
    row.axis_rmse = np.sqrt(np.mean((pred - y) ** 2, axis=0))
    bad = degenerate_reason(y, pred, alpha=alpha, axes=axes) if refuse and row.eligible else None
    if bad is not None:
        row.eligible, row.reason = False, f"refused: {bad}"


def _default_out_of_fold(estimator, X, y, folds, groups):
    return fold_predictions(estimator, X, y, folds, groups=groups)


def _score_job(estimator, X, y, folds, groups, out_of_fold, structure) -> tuple:
    """One job: ``folds`` scored with ``out_of_fold``; with ``structure`` (a model that chooses its structure), the
    first fold's model is instead a clone of ``estimator`` that chooses it on that fold's training rows alone, and
    the rest use that structure (a subsample of the rows, and inside the race: a model stopped after its first fold
    has cost one fit). Returns ``(structure parameters or None, [(test, pred)], error text or None, seconds)``."""
    from sklearn.base import clone

    from ..core._threads import limit_threads_here

    t0 = time.perf_counter()
    try:
        # BLAS on one thread, scoped to this job: the matrices are small and the jobs share the cores
        with warnings.catch_warnings(), limit_threads_here(1, openmp=True):
            warnings.simplefilter("ignore", UserWarning)
            chosen, pieces = None, []
            if structure and folds:
                from ._selection import routed_groups

                train, test = (np.asarray(a) for a in folds[0])
                def rows(a, index):  # a table (pandas) by position, anything else as an array
                    return a.iloc[index] if hasattr(a, "iloc") else np.asarray(a)[index]

                fitted = clone(estimator).fit(rows(X, train), rows(y, train), **routed_groups(
                    estimator, None if groups is None else np.asarray(groups)[train]))
                chosen = dict(fitted.structure_params())
                pieces = [(test, fitted.predict(rows(X, test)))]
                estimator, folds = clone(estimator).set_params(**chosen), folds[1:]
            if folds:
                pieces += out_of_fold(estimator, X, y, list(folds), groups)
        return chosen, [(t, np.asarray(p, dtype=float)) for t, p, *_ in pieces], None, time.perf_counter() - t0
    except Exception as exc:  # a model that cannot fit these data is a FAILED row, not fatal
        return None, None, f"{type(exc).__name__}: {' '.join(str(exc).split())[:200]}", time.perf_counter() - t0


@dataclass
class _Work:
    index: int
    name: str
    estimator: Any
    kind: str
    cost: str
    pieces: list = field(default_factory=list)
    seconds: float = 0.0
    error: str | None = None
    structured: Any = None
    structure: dict | None = None
    stopped: str | None = None


def _runner(n_jobs, jobs: list):
    """Run ``jobs`` (callables) in this process (one job or ``n_jobs`` 1: joblib runs them in order, each as it is
    asked for), else in joblib's processes; yields ``(position, result)`` as each finishes."""
    import os

    from joblib import effective_n_jobs
    from sklearn.utils.parallel import Parallel, delayed

    workers = min(effective_n_jobs(n_jobs), os.cpu_count() or 1, len(jobs)) if jobs else 1

    def tagged(i, job):
        return i, job()

    yield from Parallel(n_jobs=workers, return_as="generator_unordered")(delayed(tagged)(i, j)
                                                                          for i, j in enumerate(jobs))


def compare(models: Sequence[tuple[str, Any]], X: ArrayLike, y: ArrayLike, plan: FoldPlan, *, alpha: float = 1.0,
            groups: ArrayLike | None = None, n_jobs: int | None = None, race: bool = True, race_ties: bool = False,
            kinds: dict | None = None, progress: Callable[[ComparisonRow], None] | None = None, axes=None,
            complexity: Sequence[float] | None = None, out_of_fold: Callable | None = None,
            min_rows: Callable | None = None, refuse_degenerate: bool = True) -> Comparison:
    """Score ``models`` on ``plan``'s folds: the one comparison engine of ftcal.

    Any scikit-learn regressor may be a model; ftcal's tags (``cost``, ``min_training_rows``,
    ``chooses_structure``), when it has them, say what a fit costs and how many training rows it needs
    (without them: a model of unknown cost needing ``25 N`` rows). Never its name.

    1. A model whose smallest training fold holds fewer distinct rows than it needs is SKIPPED (not a baseline:
       reported only, never chosen).
    2. The cheap models (closed forms, kernel models on at most :data:`LIGHT_KERNEL_ROWS` training rows) are
       scored on every fold, in this process.
    3. The costly ones (networks, kernel models on more rows, unknown cost) are raced (``race=True`` and a
       cheap row scored): each is first fitted on the plan's first fold (a model that chooses its structure
       chooses it there, on that fold's training rows, and its other folds keep it), and STOPPED when, on that
       fold's rows, its excess mean squared error over the best cheap row exceeds :data:`RACE_SIGMAS` paired
       standard errors of that excess plus one paired SE (or the tie margin, the larger): it cannot come within
       one SE of the best (:func:`race_stop`). The rest are scored on every fold. ``n_jobs`` costly jobs run at
       once (joblib processes); the figures do not depend on it.
    4. A row whose held-out predictions are degenerate (:func:`degenerate_reason`) stays SCORED but is not
       eligible (``reason`` says why); ``kinds[name] == "baseline"`` rows are never eligible.

    Parameters
    ----------
    models : list of (name, regressor)
        Distinct names.
    X : array-like of shape (n, N)
    y : array-like of shape (n, k), or a table of named axes (each fit gets its rows)
    plan : FoldPlan
    alpha : float, default=1.0
        Torque scale [1/m] of the RMSE (eq. 18).
    groups : array-like of shape (n,) or None
        Routed to the models that request them (their own inner choices).
    n_jobs : int or None
    race : bool, default=True
    race_ties : bool, default=False
        Also stop a raced model that cannot come better than the best cheap row beyond one SE on its first fold
        (:func:`race_stop`'s ``ties``: ``auto`` on large data, where a costly fold is dear).
    kinds : dict name -> kind, optional
        ``"candidate"`` (default), ``"stock"``, ``"baseline"`` (reported only), ``"calibration"``.
    progress : callable, optional
        Called with each :class:`ComparisonRow` as it is finished (the CLI prints it).
    axes : tuple of str, optional
        Names of ``y``'s columns (their torques are scaled).
    complexity : sequence of float, optional
        Complexity of each model for the one-SE rule; default its cost tier (closed form, kernel, unknown,
        network) times :data:`TIER_STEP` plus its position.
    out_of_fold : callable, optional
        ``(estimator, X, y, folds, groups) -> [(test, pred), ...]``; default :func:`fold_predictions` (``auto``
        passes one that trains network folds as one stacked fit).
    min_rows : callable, optional
        ``(estimator, n_channels) -> rows``; default from the tags.
    refuse_degenerate : bool, default=True

    Returns
    -------
    Comparison
        Rows in the order of ``models``; :meth:`Comparison.choose` applies the one-SE rule.

    Examples
    --------
    >>> from sklearn.linear_model import LinearRegression
    >>> from sklearn.neighbors import KNeighborsRegressor
    >>> rng = np.random.default_rng(0); X = rng.normal(size=(80, 3)); y = X @ rng.normal(size=(3, 2))
    >>> c = compare([("ols", LinearRegression()), ("knn", KNeighborsRegressor())], X, y, FoldPlan.for_data(X, y),
    ...             min_rows=lambda est, n: 5)
    >>> c.choose(), [r.status.name for r in c.rows]
    ('ols', ['SCORED', 'SCORED'])
    """
    X = np.asarray(X, dtype=float)
    _check_models(models, X, plan)
    y_arr = np.asarray(y, dtype=float).reshape(len(X), -1)
    folds = list(plan.folds)
    smallest = min(len(np.unique(np.column_stack([X[tr], y_arr[tr]]), axis=0)) for tr, _ in folds) if folds else 0
    work = [_Work(i, name, est, (kinds or {}).get(name, "candidate"), model_cost(est, smallest))
            for i, (name, est) in enumerate(models)]
    ranks = list(complexity) if complexity is not None else \
        [COST_TIERS[w.cost if w.cost in COST_TIERS else "heavy"] * TIER_STEP + w.index for w in work]
    comparison = Comparison(rows=[None] * len(work), plan=plan, alpha=float(alpha), min_training_rows=smallest)
    LOGGER.info("compare: %d models on %d rows, %s", len(work), len(X), plan.note)
    race_ = _Race(comparison, X, y, y_arr, folds, None if groups is None else np.asarray(groups), ranks, axes,
                  out_of_fold or _default_out_of_fold, progress, refuse_degenerate, n_jobs)
    pending = race_.skip_too_few_rows(work, min_rows or _min_rows, smallest)
    cheap = [w for w in pending if w.cost == "closed_form"]
    for w in cheap:  # light work: in this process, one after another, each row said as it finishes
        race_.run([w], True, lambda w: None, workers=1)
        race_.run([w], False, race_.scored_or_failed, workers=1)
    reference = min((comparison.rows[w.index] for w in cheap
                     if comparison.rows[w.index].eligible and comparison.rows[w.index].rmse is not None),
                    key=lambda r: r.rmse, default=None)
    costly = sorted((w for w in pending if w.cost != "closed_form"), key=lambda w: -COST_TIERS[w.cost])
    race_.race_costly(costly, reference if race and len(folds) > 1 else None, race_ties)
    comparison.structures = {w.name: w.structure for w in work if w.structure is not None}
    return comparison


def _check_models(models, X: NDArray, plan: FoldPlan) -> None:
    """Distinct non-empty names, regressors, and a plan of ``X``'s rows (else :class:`CalibrationInputError`)."""
    names = [name for name, _ in models]
    if len(set(names)) != len(names) or not all(isinstance(n, str) and n for n in names):
        raise CalibrationInputError(f"compare needs distinct non-empty names; got {names!r:.200}.")
    for name, est in models:
        if not (hasattr(est, "fit") and hasattr(est, "predict")):
            raise CalibrationInputError(f"model {name!r} is not a regressor (no fit/predict): {est!r:.80}.")
    if plan.n_rows != len(X):
        raise CalibrationInputError(f"the fold plan is of {plan.n_rows} rows but X has {len(X)}; build the plan "
                                    "with FoldPlan.for_data on these data.")


@dataclass
class _Race:
    """The steps of one :func:`compare`: skip, run jobs on the first or the other folds, race, finish rows."""

    comparison: Comparison
    X: NDArray
    y_fit: Any  # y as given (a table of named axes stays one for the fits)
    y: NDArray
    folds: list
    groups: NDArray | None
    ranks: list
    axes: Any
    out_of_fold: Callable
    progress: Callable | None
    refuse_degenerate: bool
    n_jobs: int | None

    def finish(self, w: _Work, status: RowStatus, reason: str | None = None) -> ComparisonRow:
        """``w``'s row, scored from its pieces (SCORED) or not; said to the log and ``progress``."""
        row = ComparisonRow(name=w.name, kind=w.kind, status=status, reason=reason, seconds=float(w.seconds),
                            complexity=float(self.ranks[w.index]),
                            eligible=w.kind != "baseline" and status is RowStatus.SCORED)
        plan = self.comparison.plan
        if status is RowStatus.SCORED:
            pred = np.full(self.y.shape, np.nan)
            for test, values in w.pieces:
                pred[test] = values.reshape(len(test), -1)
            row.predictions = pred
            _score_row(row, pred, self.y, self.comparison.alpha, self.axes, plan.units, self.refuse_degenerate)
        self.comparison.rows[w.index] = row
        LOGGER.info("compare: %s %s%s (%.1f s)", w.name, status.value,
                    f", RMSE {row.rmse:.4g} ± {row.rmse_se:.2g} N" if row.rmse is not None else
                    f": {reason}" if reason else "", row.seconds)
        if self.progress is not None:
            self.progress(row)
        return row

    def skip_too_few_rows(self, work: list, need: Callable, smallest: int) -> list:
        """SKIPPED rows for the models no fold can judge (none, or too few training rows); the others."""
        pending, n_channels = [], self.X.shape[1]
        for w in work:
            needed = need(w.estimator, n_channels)
            if not self.folds:
                self.finish(w, RowStatus.SKIPPED, "no folds can judge a model")
            elif smallest < needed and w.kind != "baseline":  # (a baseline is reported only, never chosen)
                self.finish(w, RowStatus.SKIPPED, f"training folds of {smallest} rows < the {needed} it needs")
            else:
                pending.append(w)
        return pending

    def run(self, batch: list, first: bool, done: Callable, workers=None) -> None:
        """``batch`` on the first fold (``first``; a model that chooses its structure chooses it there) or on the
        other folds: a job per fold, a network's folds one job (one stacked fit); ``done(w)`` as each model's
        last job returns."""
        from sklearn.base import clone

        folds, jobs, owner = self.folds, [], []
        for w in batch:
            structure = first and _chooses_structure(w.estimator)
            idx = [0] if first else list(range(1, len(folds)))
            parts = [idx] if _stacked(w.estimator) or structure or not idx else [[i] for i in idx]
            for part in parts:
                jobs.append(lambda w=w, part=part, structure=structure: _score_job(
                    w.structured if w.structured is not None else w.estimator, self.X, self.y_fit,
                    [folds[i] for i in part], self.groups, self.out_of_fold, structure))
                owner.append(w)
        left = {w.index: sum(o is w for o in owner) for w in batch}
        for w in batch:
            if not left[w.index]:
                done(w)
        for pos, (chosen, pieces, error, seconds) in _runner(self.n_jobs if workers is None else workers, jobs):
            w = owner[pos]
            w.seconds += seconds
            if chosen is not None:
                w.structure, w.structured = chosen, clone(w.estimator).set_params(**chosen)
            if error is not None:
                w.error = w.error or error
            else:
                w.pieces.extend(pieces)
            left[w.index] -= 1
            if not left[w.index]:
                done(w)

    def scored_or_failed(self, w: _Work) -> None:
        self.finish(w, RowStatus.FAILED, w.error) if w.error else self.finish(w, RowStatus.SCORED)

    def race_costly(self, costly: list, reference: ComparisonRow | None, ties: bool) -> None:
        """``costly`` on the first fold, each STOPPED there against ``reference`` (None: no race) or scored on the
        other folds."""
        survivors: list[_Work] = []
        n_folds, plan = len(self.folds), self.comparison.plan

        def after_first(w: _Work) -> None:
            if w.error:
                self.finish(w, RowStatus.FAILED, w.error)
                return
            w.stopped = None if reference is None else _race_verdict(
                w, reference, self.y, self.comparison.alpha, self.axes, plan, n_folds, ties)
            if w.stopped:
                self.finish(w, RowStatus.STOPPED, w.stopped)
            elif n_folds == 1:
                self.finish(w, RowStatus.SCORED)
            else:
                survivors.append(w)

        if costly:
            self.run(costly, True, after_first)
        if survivors:
            self.run(sorted(survivors, key=lambda w: w.index), False, self.scored_or_failed)


def race_stop(errors: NDArray, reference_errors: NDArray, units: NDArray | None, tie_mse: float, *,
              ties: bool = False, share: float = 1.0) -> tuple[bool, float, float, float]:
    """Whether a raced candidate is stopped, from its per-row errors and the reference's on the same rows (the
    folds both were scored on): ``(stop, excess, paired_se, threshold)``.

    ``excess`` is the candidate's mean squared error minus the reference's and ``paired_se`` the standard error of
    that **paired** difference over ``units`` (groups, or rows: :func:`mean_and_se`). Within one SE of the
    reference means an excess of at most one paired SE (the one-SE rule's test, :func:`paired_excess`), or the
    tie margin ``tie_mse``: ``threshold = max(paired_se, tie_mse)``. The candidate is stopped when even
    :data:`RACE_SIGMAS` paired SE below its excess lies beyond it: ``excess - RACE_SIGMAS * paired_se >
    threshold``. The reference's own (unpaired) SE plays no part: models that err on the same rows have a
    difference far less noisy than either's error.

    With ``ties`` (large data, where a costly fold is dear) a candidate is also stopped when it cannot **win**
    the one-SE rule against the reference (a cheap model, ranked simpler): that needs a gain ``-excess`` beyond
    one paired SE of the difference on *all* folds (or the tie margin). That SE is about ``paired_se *
    sqrt(share)``, ``share`` being the scored folds' part of all the units (rows or groups); the candidate is
    stopped when even one paired SE in its favour leaves its gain short of that bar, ``-excess + paired_se <
    max(paired_se * sqrt(share), tie_mse)``: one SE, the one-SE rule's own level. The reference would then be
    chosen over it (it could only have joined a stack).

    Examples
    --------
    >>> rng = np.random.default_rng(0)
    >>> reference = rng.exponential(1.0, 200)  # its errors spread widely over the rows
    >>> race_stop(reference + 0.1, reference, None, 0.01)[0]  # worse on every row by 0.1 N²: stopped
    True
    >>> race_stop(reference + rng.normal(0.0, 1.0, 200), reference, None, 0.01)[0]  # noise: it races on
    False
    >>> race_stop(reference + 0.05, reference, None, 0.1)[0]  # worse on every row, but within the tie margin
    False
    >>> race_stop(reference + 0.05, reference, None, 0.1, ties=True)[0]  # ... and it cannot win: stopped
    True
    >>> race_stop(reference - 0.5, reference, None, 0.1, ties=True)[0]  # better on every row: it races on
    False
    >>> race_stop(reference + rng.normal(0.0, 1.0, 200), reference, None, 0.01, ties=True, share=0.2)[0]
    False
    """
    excess, se = mean_and_se(np.asarray(errors, dtype=float) - np.asarray(reference_errors, dtype=float), units)
    threshold = max(se, float(tie_mse)) if np.isfinite(se) else float("inf")
    worse = excess - RACE_SIGMAS * se > threshold
    tied = ties and -excess + se < max(se * float(np.sqrt(share)), float(tie_mse))
    return bool(np.isfinite(se) and (worse or tied)), float(excess), float(se), threshold


def _race_verdict(w: _Work, reference: ComparisonRow, y: NDArray, alpha: float, axes, plan: FoldPlan,
                  n_folds: int, ties: bool = False) -> str | None:
    """Why ``w``, scored on the plan's first fold, is stopped (None: it races on): :func:`race_stop` on that
    fold's rows against ``reference`` (the best cheap row), paired over the fold's groups (a plan over groups),
    else over its rows; the tie margin is the one-SE rule's (:func:`tie_margin`) on those rows and units."""
    test, pred = w.pieces[0]
    errors = _row_errors(np.asarray(pred).reshape(len(test), -1), y[test], alpha, axes)
    grouped = plan.kind == "group" and plan.units is not None
    units = plan.units[test] if grouped else None
    share = np.unique(units).size / np.unique(plan.units).size if grouped else len(test) / plan.n_rows
    ref = reference.row_errors[test]
    tie = tie_margin(ref, units)
    stop, excess, se, threshold = race_stop(errors, ref, units, tie, ties=ties, share=share)
    if stop and excess - RACE_SIGMAS * se <= threshold:  # stopped as a tie (``ties``): it cannot win
        bar = max(se * float(np.sqrt(share)), tie)
        return (f"after fold 1 of {n_folds}, it cannot come better than {reference.name} beyond one SE (excess "
                f"MSE {excess:.3g} ± {se:.2g} N², paired; even one SE in its favour short of the {bar:.3g} N² a "
                "gain must clear on all folds): on large data a tie is not raced on (the simpler model would be "
                "chosen)")
    if stop:
        ratio = float(np.sqrt(np.mean(errors) / max(np.mean(ref), 1e-300)))
        return (f"after fold 1 of {n_folds}, its RMSE there is {ratio:.2f}x {reference.name}'s (excess MSE "
                f"{excess:.3g} ± {se:.2g} N², paired: more than {RACE_SIGMAS:g} paired SE beyond the one-SE bar, "
                f"the larger of one paired SE and the tie margin, {threshold:.3g} N²)")
    return None


def choice_stability(models: Sequence[tuple[str, Any]], X: ArrayLike, y: ArrayLike, plan: FoldPlan, *,
                     chosen: str, seeds: Sequence[int] = (1, 2, 3, 4), groups: ArrayLike | None = None,
                     finish: Callable[[Comparison], None] | None = None, **compare_kwargs) -> ChoiceStability | None:
    """Repeat the choice on folds with other ``seeds`` (the same fold rule, :meth:`FoldPlan.with_seed`): in how
    many of the repeats (the plan's own included) is ``chosen`` chosen again by the one-SE rule.

    Meant for cheap comparisons (the caller decides: small data, light models). ``finish(comparison)`` adds
    rows made from the others (``auto``'s stack) before each choice. None when other seeds give the same folds
    (as many groups as folds, contiguous blocks).

    Examples
    --------
    >>> from sklearn.linear_model import LinearRegression, Ridge
    >>> rng = np.random.default_rng(0); X = rng.normal(size=(80, 3)); y = X @ rng.normal(size=(3, 2))
    >>> models = [("ols", LinearRegression()), ("ridge", Ridge(alpha=50.0))]
    >>> choice_stability(models, X, y, FoldPlan.for_data(X, y), chosen="ols", min_rows=lambda e, n: 5).words()
    'chosen in 5 of 5 repeats (fold seeds 0, 1, 2, 3, 4)'
    """
    choices, used = [chosen], [plan.seed]
    for seed in seeds:
        other = plan.with_seed(int(seed), X, y, groups)
        if other is None:
            return None
        c = compare(models, X, y, other, groups=groups, race=False, **compare_kwargs)
        if finish is not None:
            finish(c)
        try:
            choices.append(c.choose())
        except CalibrationInputError:
            choices.append("(none)")
        used.append(int(seed))
    return ChoiceStability(chosen, sum(c == chosen for c in choices), len(choices), tuple(used), tuple(choices))
