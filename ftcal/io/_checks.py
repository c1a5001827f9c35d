"""Readings checked before anything is fitted or predicted: impossible values, spikes, stuck channels, repeated rows.

A recording can hold readings no sensor gave: a value an ADC cannot produce (``4598`` on a 10-bit channel that reads
0..1023), a single glitch among steady neighbours, a channel frozen while the others move, a row the logger wrote
twice. Fitted silently they turn into calibration errors with no pointer to the cause. :func:`check_readings` finds
them and names each by file, line and channel (:class:`~ftcal.io.RowSources`); ``ftcal fit``, ``report``,
``evaluate`` and ``predict`` print them; all but ``predict`` can drop them (``--drop-bad-readings``): ``predict``
writes one wrench per input line, in order, so it points them out and drops none.

The thresholds come from the data's own noise and one false-alarm budget, not from fixed numbers:

* **out of range** -- for an integer-valued channel, the smallest power-of-two range (unsigned ``0..2^b-1`` or
  signed ``-2^(b-1)..2^(b-1)-1``) that holds all but the ``max(1, 0.1 %)`` most extreme readings is the ADC's range
  the other readings fit in; a reading beyond *twice* that range (two more bits) is impossible for it (one more bit
  could be a larger ADC whose top the other readings never reached) when it is alone there: none of its three
  neighbours before and after lies beyond the range. A genuine peak of a rare load rises and falls through its
  neighbours and is never called impossible (nor dropped by ``--drop-bad-readings auto``); a glitch jumps alone. A reading exactly at the range's limit (``0``)
  is flagged too when it is rare and stands out from its neighbours in time (a dropped sample reads 0);
* **spike** -- a reading that differs from the median of its three neighbours before *and* the median of its three
  neighbours after, in the same direction, by more than ``z`` robust standard deviations (the mean absolute
  difference of the channel in its group over its 99 % smallest, scaled to a Gaussian standard deviation; at least
  one quantisation step). ``z`` is the Gaussian quantile
  that keeps the expected number of false alarms over the whole dataset at ``false_alarm_rate`` (Bonferroni over
  every reading tested): about 4.8 for 6 000 readings, 5.9 for a million. A load step matches one side and is no
  spike; a row where the reference wrench or another channel stands out too (beyond a single test at 1 %, z 2.58)
  is a change of load, not a glitch of one channel; the first and last rows of a group, having one side only, are
  not tested;
* **stuck** -- a channel exactly constant over a run of rows of a group while most other channels move there: a
  live channel gives its commonest value with a chance ``p`` (the largest of its share in the group outside the run,
  its share in the rows next to the run, and the 90th percentile of its share in the other groups), so a run of ``L`` equal readings comes by chance about
  ``n p^L`` times; runs longer than where that falls below ``false_alarm_rate`` (and at
  least :data:`MIN_STUCK_ROWS`) are stuck. A channel is stuck too where it holds one value over whole groups whose
  loads differ (the other channels' group means spread at least half as much there as over the groups where it
  lives) while elsewhere its group means follow the loads over at least :data:`_FROZEN_STEPS` quantisation steps
  (a value at the channel's extreme is a pinned, saturated channel, not this);
* **repeated** -- rows (readings and wrench) that equal an earlier row of their group exactly, when more such pairs
  occur than quantisation explains: the expected number of equal pairs is the product over channels of each
  channel's chance that two readings of the group under the same reference wrench are equal (one steady load's
  spread, not that of several poses mixed in one file); the rows are flagged when the Poisson chance of as
  many pairs is below ``false_alarm_rate`` and, where quantisation alone gives pairs, when the excess is beyond
  the Gaussian quantile of ``false_alarm_rate`` in standard deviations of the pair count (the pairs share rows:
  its variance is a U-statistic's, far wider than a Poisson count's).

:func:`range_excess` says, per axis, how many rows lie beyond a calibrated range and how far (x the range): the
loads of a validation session beyond those a model was calibrated on (``ftcal evaluate``), or readings beyond the
calibration's (``ftcal predict``).
"""

from __future__ import annotations

import enum
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import ArrayLike, NDArray

__all__ = ["FindingKind", "ReadingFinding", "ReadingChecks", "check_readings", "MIN_STUCK_ROWS", "AxisExcess",
           "RangeExcess", "range_excess"]

#: Fewest rows of a group over which an exactly constant channel is called stuck (a live channel whose noise spans
#: at least one quantisation step stays put for ten rows with a chance of about 2^-9).
MIN_STUCK_ROWS = 10
#: Fewest readings of a channel from which its ADC range is inferred.
_MIN_RANGE_ROWS = 20
#: Fraction of a channel's readings (at least one) left out at each end when its ADC range is inferred.
_RANGE_TRIM = 0.001
#: Neighbours on each side of a reading whose median it is compared with (three: the median ignores one glitch).
_SIDE = 3
#: Fewest rows of a group whose own noise scales its spikes; smaller groups use the channel's scale over all groups.
_MIN_SCALE_ROWS = 20
#: Rows on each side of a constant run (at least the run's length) whose commonest value's share tells how often a
#: live channel holds one value there.
_LOCAL_ROWS = 50
#: Fewest quantisation steps a channel's group means spread over (standard deviation across the groups where it
#: lives) for one value held over whole groups of differing loads to be called frozen.
_FROZEN_STEPS = 5
#: Most rows at a range limit still called isolated readings (more are a pinned, saturated channel).
_MAX_RAIL_ROWS = 3


class FindingKind(str, enum.Enum):
    """What is wrong with a reading (the ``kind`` of :class:`ReadingFinding`; its value is the JSON spelling)."""

    OUT_OF_RANGE = "out_of_range"
    SPIKE = "spike"
    STUCK = "stuck"
    REPEATED = "repeated"
    SATURATED = "saturated"


@dataclass(frozen=True)
class ReadingFinding:
    """One bad reading (or a stuck channel over a group's rows), and where it came from.

    Attributes
    ----------
    kind : FindingKind
    rows : ndarray of int
        The rows of the dataset it covers (counted from 0; one row except for a stuck channel).
    file : str
        The file the (first) row came from.
    line : int
        Its 1-based line (the 1-based row of an ``.npz`` / ``.mat`` array).
    channel : str or None
        The channel (None: the whole row, a repeated row).
    value : float or None
        The reading.
    reason : str
        One sentence: why it is flagged, with the figures.
    """

    kind: FindingKind
    rows: NDArray[np.int64]
    file: str
    line: int
    channel: str | None
    value: float | None
    reason: str

    def where(self) -> str:
        """``file:line:channel`` (``file:line`` for a whole row)."""
        return f"{self.file}:{self.line}" + (f":{self.channel}" if self.channel is not None else "")

    def to_dict(self) -> dict:
        """The finding as plain JSON: ``kind``, ``file``, ``line``, ``channel``, ``value``, ``reason``, ``rows``
        (how many rows it covers)."""
        return {"kind": self.kind.value, "file": self.file, "line": int(self.line), "channel": self.channel,
                "value": None if self.value is None else float(self.value), "reason": self.reason,
                "rows": int(self.rows.size)}


@dataclass(frozen=True)
class ReadingChecks:
    """What :func:`check_readings` found.

    Attributes
    ----------
    findings : tuple of ReadingFinding
        In kind order, then row order.
    n_rows : int
        Rows checked.
    adc_ranges : dict
        Channel name -> ``(low, high)``: the power-of-two range inferred for each integer-valued channel.
    spike_z : float
        The spike threshold used [robust standard deviations].
    """

    findings: tuple[ReadingFinding, ...]
    n_rows: int
    adc_ranges: dict = field(default_factory=dict)
    spike_z: float = float("nan")

    @property
    def clean(self) -> bool:
        """Whether nothing was found."""
        return not self.findings

    def of_kind(self, kind: FindingKind | str) -> tuple[ReadingFinding, ...]:
        """The findings of one kind."""
        return tuple(self._of_kinds([kind]))

    def kinds(self) -> list[FindingKind]:
        """The kinds found, in :class:`FindingKind` order."""
        return [k for k in FindingKind if self.of_kind(k)]

    def _of_kinds(self, kinds) -> list[ReadingFinding]:
        """The findings of ``kinds`` (None: all)."""
        wanted = set(FindingKind) if kinds is None else {FindingKind(k) for k in kinds}
        return [f for f in self.findings if f.kind in wanted]

    def mask(self, kinds=None) -> NDArray[np.bool_]:
        """The rows the findings of ``kinds`` (default: all) cover, as a mask over the checked rows."""
        out = np.zeros(self.n_rows, dtype=bool)
        for f in self._of_kinds(kinds):
            out[f.rows] = True
        return out

    def to_json(self, kinds=None) -> list[dict]:
        """The findings of ``kinds`` (default: all) as plain JSON (:meth:`ReadingFinding.to_dict`)."""
        return [f.to_dict() for f in self._of_kinds(kinds)]

    def summary(self, shown: int = 3) -> list[str]:
        """One line per kind found: how many, the rows they cover and the first ``shown`` as ``file:line:channel``.

        Examples
        --------
        >>> raw = np.round(700 + 5 * np.random.default_rng(1).standard_normal((40, 3)))
        >>> raw[20, 1] = 4598.0
        >>> print(check_readings(raw).summary()[0])  # doctest: +ELLIPSIS
        1 out_of_range reading (1 row): dataset:21:s1 = 4598 (beyond twice the 0..1023 range ...
        """
        lines = []
        for kind in self.kinds():
            found = self.of_kind(kind)
            rows = int(self.mask([kind]).sum())
            first = "; ".join(f"{f.where()}" + ("" if f.value is None else f" = {f.value:.6g}") for f in found[:shown])
            more = f"; ... ({len(found) - shown} more)" if len(found) > shown else ""
            noun = {FindingKind.REPEATED: "row", FindingKind.STUCK: "channel run"}.get(kind, "reading")
            plural = "s" if len(found) != 1 else ""
            said = found[0].reason if len({f.reason for f in found}) == 1 else f"the first: {found[0].reason}"
            lines.append(f"{len(found)} {kind.value} {noun}{plural} ({rows} row{'s' if rows != 1 else ''}): "
                         f"{first}{more} ({said})")
        return lines


def _gaussian_z(p: float) -> float:
    """The upper-tail Gaussian quantile of ``p``."""
    from scipy.special import ndtri  # scipy.stats takes seconds to import

    return float(-ndtri(p))


def _group_rows(groups, n: int) -> list[NDArray[np.int64]]:
    """The rows of each group, in dataset (time) order; one group of every row without groups."""
    if groups is None:
        return [np.arange(n)]
    g = np.asarray(groups)
    order = np.argsort(g, kind="stable")
    cuts = np.flatnonzero(np.diff(g[order])) + 1
    return np.split(order, cuts)


def _quantum(column: NDArray[np.float64]) -> float:
    """The channel's quantisation step: the smallest gap between two distinct readings (0 for a constant one)."""
    u = np.unique(column)
    return float(np.min(np.diff(u))) if u.size > 1 else 0.0


def _adc_range(column: NDArray[np.float64]) -> tuple[float, float] | None:
    """The power-of-two range (low, high) that holds the bulk of an integer-valued channel, or None."""
    n = column.size
    if n < _MIN_RANGE_ROWS or not np.all(column == np.round(column)):
        return None
    m = max(1, int(_RANGE_TRIM * n))
    s = np.sort(column)
    low, high = s[m], s[n - 1 - m]
    if high <= low:
        return None
    if low >= 0:
        bits = max(1, int(np.ceil(np.log2(high + 1))))
        return 0.0, float(2**bits - 1)
    bits = max(1, int(np.ceil(np.log2(max(-low, high + 1)))) + 1)
    return float(-(2 ** (bits - 1))), float(2 ** (bits - 1) - 1)


#: E|Z| over the 99 % smallest |Z| of a standard normal Z: the trimmed mean absolute deviation over this is a
#: robust standard deviation that, unlike the median absolute deviation, does not jump with the quantisation steps.
_TRIMMED_MEAN_ABS = 2 * (1 / np.sqrt(2 * np.pi)) * (1 - np.exp(-2.5758293035489 ** 2 / 2)) / 0.99


def _robust_scale(deviations: NDArray[np.float64]) -> NDArray[np.float64]:
    """A robust standard deviation of each column of absolute deviations: their mean over the 99 % smallest
    (finite ones), over :data:`_TRIMMED_MEAN_ABS` (0 for a column without any)."""
    out = np.zeros(deviations.shape[1])
    for j in range(deviations.shape[1]):
        column = deviations[:, j]
        column = np.sort(column[np.isfinite(column)])
        kept = column[: max(1, int(np.ceil(0.99 * column.size)))] if column.size else column
        out[j] = float(np.mean(kept)) / _TRIMMED_MEAN_ABS if kept.size else 0.0
    return out


def _top_share(column: NDArray[np.float64]) -> float:
    """The share of the commonest value among ``column``'s readings."""
    if column.size == 0:
        return 0.0
    _, counts = np.unique(column, return_counts=True)
    return float(counts.max() / column.size)


def _runs(flags: NDArray[np.bool_]) -> list[tuple[int, int]]:
    """``(start, stop)`` of each run of True in ``flags``."""
    padded = np.concatenate([[False], flags, [False]])
    edges = np.flatnonzero(np.diff(padded.astype(np.int8)))
    return list(zip(edges[::2], edges[1::2]))


def _side_medians(x: NDArray[np.float64]) -> tuple[NDArray, NDArray]:
    """The median of the ``_SIDE`` readings before and after each row (NaN where a side is empty)."""
    import warnings

    m, k = x.shape
    pad = np.full((_SIDE, k), np.nan)
    padded = np.vstack([pad, x, pad])
    with warnings.catch_warnings():  # a row without neighbours on one side (a group's edge): NaN, no warning
        warnings.simplefilter("ignore", RuntimeWarning)
        return tuple(np.nanmedian(np.stack([padded[_SIDE + s * j:_SIDE + s * j + m] for j in range(1, _SIDE + 1)]),
                                  axis=0) for s in (-1, 1))


class _Finder:
    """The state one :func:`check_readings` call shares between its checks."""

    def __init__(self, raw, wrench, groups, sources, names, false_alarm_rate):
        from ._dataset import RowSources

        self.raw, self.wrench = raw, wrench
        self.n, self.k = raw.shape
        self.sources = sources if sources is not None else \
            RowSources.of_file("dataset", np.arange(1, self.n + 1), "row")
        self.names = list(names) if names is not None else [f"s{j}" for j in range(self.k)]
        self.groups = _group_rows(groups, self.n)
        self._group_index = np.zeros(self.n, dtype=np.int64)  # row -> its group (rows in time order within each)
        for g, rows in enumerate(self.groups):
            self._group_index[rows] = g
        self.alpha = false_alarm_rate
        self.findings: list[ReadingFinding] = []
        self.flagged = np.zeros((self.n, self.k), dtype=bool)  # (row, channel) already named

    def add(self, kind, rows, channel, value, reason) -> None:
        """Note a finding; a channel's readings it names are :attr:`flagged` (not named again by a later check)."""
        rows = np.atleast_1d(np.asarray(rows, dtype=np.int64))
        if channel is not None:
            self.flagged[rows, channel] = True
        file, line = self.sources.where(int(rows[0]))
        self.findings.append(ReadingFinding(kind=kind, rows=rows, file=file, line=line,
                                            channel=None if channel is None else self.names[channel],
                                            value=value, reason=reason))

    # ---------------------------------------------------------------- spikes (and the statistics the range needs)
    def side_statistics(self, exclude=None):
        """Per row and channel: the same-direction distance to both sides' medians over the robust scale (0 where
        the directions differ, NaN where a side is missing), and the distance to the one side there is. The
        readings ``exclude`` (n, N) marks (a stuck run) do not set the scale."""
        z_both, z_one = np.full((2, self.n, self.k), np.nan)
        quanta = np.array([_quantum(self.raw[:, j]) for j in range(self.k)])
        parts = []
        for rows in self.groups:
            x = self.raw[rows]
            before, after = _side_medians(x)
            dl, dr = x - before, x - after
            usable = np.abs(dl)
            if exclude is not None:
                usable = np.where(exclude[rows], np.nan, usable)
            parts.append((rows, dl, dr, usable))
        pooled = np.vstack([u for *_, u in parts]) if parts else np.zeros((0, self.k))
        pooled_scale = _robust_scale(pooled)
        for rows, dl, dr, usable in parts:
            own = _robust_scale(usable)
            small = np.isfinite(usable).sum(axis=0) < _MIN_SCALE_ROWS
            scale = np.maximum(np.where(small, pooled_scale, own), quanta)
            with np.errstate(divide="ignore", invalid="ignore"):
                same = np.sign(dl) == np.sign(dr)
                both = np.where(same, np.minimum(np.abs(dl), np.abs(dr)), 0.0) / scale
                one = np.where(np.isnan(dl), np.abs(dr), np.abs(dl)) / scale
            both[np.isnan(dl) | np.isnan(dr)] = np.nan
            both[:, scale == 0] = np.nan
            one[:, scale == 0] = np.nan
            z_both[rows], z_one[rows] = both, one
        return z_both, z_one

    def out_of_range(self, z_both, z_one) -> dict:
        ranges = {}
        for j in range(self.k):
            column = self.raw[:, j]
            found = _adc_range(column)
            if found is None:
                continue
            low, high = found
            ranges[self.names[j]] = found
            width = high - low + 1
            for r in np.flatnonzero((column < low - width) | (column > high + width)):
                if self._alone_beyond(r, j, low, high):
                    self.add(FindingKind.OUT_OF_RANGE, r, j, float(column[r]),
                             f"beyond twice the {int(low)}..{int(high)} range of the channel's other readings: no ADC "
                             "of that range gives it")
            for rail in (low, high):
                at = np.flatnonzero(column == rail)
                if not 0 < at.size <= _MAX_RAIL_ROWS:
                    continue
                z = np.where(np.isnan(z_both[at, j]), z_one[at, j], z_both[at, j])
                limit = _gaussian_z(self.alpha / (2 * max(1, at.size)))
                for r, zr in zip(at, z):
                    if np.isfinite(zr) and zr > limit:
                        self.add(FindingKind.OUT_OF_RANGE, r, j, float(column[r]),
                                 f"at the limit {int(rail)} of the channel's {int(low)}..{int(high)} range, alone "
                                 f"({zr:.1f} robust SD from its neighbours in time; {at.size} such reading(s))")
        return ranges

    def _alone_beyond(self, r: int, j: int, low: float, high: float) -> bool:
        """Whether none of the ``_SIDE`` readings before and after row ``r`` in its group lies beyond
        ``low..high`` too: a glitch is alone; a genuine peak past the range the other readings fit in rises and
        falls through its neighbours (a larger ADC's top, reached by a rare load), and is no impossible reading."""
        rows = self.groups[int(self._group_index[r])]
        at = int(np.searchsorted(rows, r))  # a group's rows are increasing (a stable sort of the labels)
        near = np.concatenate([rows[max(0, at - _SIDE):at], rows[at + 1:at + 1 + _SIDE]])
        values = self.raw[near, j]
        return not np.any((values < low) | (values > high))

    def load_moves(self, z_both) -> NDArray[np.bool_]:
        """Rows where the load changes abruptly: the reference wrench, or at least two channels at once, stand out
        from their neighbours in time by more than a single test at 1 % would allow (a reading's jump is then the
        load's, not a glitch's: a glitch is one channel's)."""
        excuse = _gaussian_z(0.005)
        crowd = np.nan_to_num(z_both, nan=0.0) > excuse
        moves = crowd.sum(axis=1) >= 2
        if self.wrench is not None:
            w = _Finder(self.wrench, None, None, self.sources, None, self.alpha)
            w.groups = self.groups
            wz, _ = w.side_statistics()
            moves |= (np.nan_to_num(wz, nan=0.0) > excuse).any(axis=1)
        return moves

    def spikes(self, z_both) -> float:
        tested = int(np.isfinite(z_both).sum())
        if not tested:
            return float("nan")
        limit = _gaussian_z(self.alpha / (2 * tested))
        hits = np.argwhere(np.nan_to_num(z_both, nan=0.0) > limit)
        moves = self.load_moves(z_both) if hits.size else None
        for r, j in hits:
            if self.flagged[r, j] or moves[r]:
                continue
            self.add(FindingKind.SPIKE, r, j, float(self.raw[r, j]),
                     f"differs from its neighbours in time on both sides by more than {limit:.1f} robust SD (the "
                     f"threshold that keeps false alarms below {self.alpha:g} per dataset over {tested} readings)")
        return limit

    # ---------------------------------------------------------------- stuck channels
    def stuck(self) -> NDArray[np.bool_]:
        """Runs of a channel exactly constant while most other channels move; returns the (row, channel) mask (the
        first check: what it flags is all that is :attr:`flagged` yet)."""
        same = np.zeros((self.n, self.k), dtype=bool)  # the reading equals the previous one of its group
        for rows in self.groups:
            if rows.size > 1:
                same[rows[1:]] = self.raw[rows[1:]] == self.raw[rows[:-1]]
        pairs = max(1, self.n - len(self.groups))
        big = [rows for rows in self.groups if rows.size >= MIN_STUCK_ROWS]
        # how concentrated each channel's readings are in each group: a quiet channel (noise below a quantisation
        # step, its mean near a level) reads one value most of the time, and a run there is less telling
        peak = np.array([[_top_share(self.raw[rows, j]) for j in range(self.k)] for rows in big]) if big \
            else np.zeros((0, self.k))
        for g, rows in enumerate(big):
            for j in range(self.k):
                for start, stop in _runs(same[rows, j]):
                    if stop - start + 1 < MIN_STUCK_ROWS:
                        continue
                    span = rows[start - 1:stop]  # the run's first reading is the one the others repeat
                    # a live channel reads its commonest value with a chance p: a run of L equal readings comes by
                    # chance about n p^L times; it is stuck when that is below the false-alarm rate. p: the larger
                    # of the group's own outside the run and the 90th percentile of the other groups'
                    outside = np.setdiff1d(rows, span)
                    p = _top_share(self.raw[outside, j]) if outside.size >= _MIN_SCALE_ROWS else 0.0
                    if len(big) > 1:
                        p = max(p, float(np.quantile(np.delete(peak[:, j], g), 0.9)))
                    elif outside.size < _MIN_SCALE_ROWS:
                        continue  # one short group: nothing tells a quiet channel from a stuck one
                    # and the share near the run: a group spanning several steady poses (no group column) mixes
                    # their levels, and its overall share understates how often a quiet channel holds one value
                    reach = max(_LOCAL_ROWS, stop - start)
                    for near in (rows[max(0, start - 1 - reach):max(0, start - 1)], rows[stop:stop + reach]):
                        if near.size >= _MIN_SCALE_ROWS:  # each side alone: the run may sit where the pose changes
                            p = max(p, _top_share(self.raw[near, j]))
                    needed = MIN_STUCK_ROWS if p <= 0 else max(MIN_STUCK_ROWS,
                                                               np.log(self.alpha / pairs) / np.log(min(p, 0.999)))
                    moving = np.ptp(np.delete(self.raw[span], j, axis=1), axis=0) > 0
                    if span.size < needed or moving.size == 0 or moving.mean() <= 0.5:
                        continue
                    first, last = self.sources.describe(int(span[0])), self.sources.describe(int(span[-1]))
                    self.add(FindingKind.STUCK, span, j, float(self.raw[span[0], j]),
                             f"constant over {span.size} rows ({first} to {last}) while the other channels move "
                             f"(a live reading gives one value with chance {p:.2g} at most: runs of "
                             f"{int(np.ceil(needed))} rows or more are beyond chance)")
        self.frozen_across_groups()
        return self.flagged.copy()

    def frozen_across_groups(self) -> None:
        """A channel that keeps one value over whole groups whose loads differ (dead for the second half of a
        steady-pose recording): in the groups where it lives, its group means spread over several quantisation
        steps with the load, while over the frozen groups the other channels' means spread as much (their loads
        differ) and it does not move at all (a run already found stuck within a group is left to that finding)."""
        if len(self.groups) < 4 or self.k < 2:
            return
        sizes = np.array([rows.size for rows in self.groups])
        means = np.array([self.raw[rows].mean(axis=0) for rows in self.groups])
        for j in range(self.k):
            q = _quantum(self.raw[:, j])
            constant = np.array([rows.size >= 2 and np.ptp(self.raw[rows, j]) == 0 and not self.flagged[rows, j].any()
                                 for rows in self.groups])
            live = ~constant & (sizes >= 2)
            if q <= 0 or live.sum() < 2 or constant.sum() < 2:
                continue
            live_spread = np.std(means[live], axis=0, ddof=1)
            if live_spread[j] < _FROZEN_STEPS * q:  # a channel that barely follows the loads may hold one value
                continue
            others = [i for i in range(self.k) if i != j and live_spread[i] > 0]
            extremes = (self.raw[:, j].min(), self.raw[:, j].max())
            for value in np.unique(means[constant, j]):
                frozen = np.flatnonzero(constant & (means[:, j] == value))
                if frozen.size < 2 or not others or value in extremes:  # at its extreme: pinned (saturated)
                    continue
                moved = np.std(means[frozen][:, others], axis=0, ddof=1) / live_spread[others]
                if np.median(moved) < 0.5:  # the frozen groups' loads hardly differ: one value is no surprise
                    continue
                rows = np.concatenate([self.groups[g] for g in frozen])
                self.add(FindingKind.STUCK, np.sort(rows), j, float(value),
                         f"holds {value:.6g} over all {rows.size} rows of {frozen.size} groups whose loads differ "
                         f"(the other channels' means spread {np.median(moved):.2g}x as much as over all groups) while "
                         f"it follows the loads elsewhere (its group means spread {live_spread[j] / q:.3g} steps)")

    # ---------------------------------------------------------------- repeated rows
    def _same_load(self, groups: list[NDArray[np.int64]]) -> list[tuple[NDArray[np.int64], NDArray[np.int64]]]:
        """The rows of each group split by their reference wrench, each with the rows whose spread gives the
        readings' chance to coincide: equal rows have equal wrenches, so that chance is the one under one load (a
        steady pose's), not that of the group's whole spread (several poses without a group column mix their
        levels); a load held for fewer than ``_MIN_SCALE_ROWS`` rows takes its group's spread."""
        if self.wrench is None:
            return [(rows, rows) for rows in groups]
        out = []
        for rows in groups:
            if rows.size < 2:
                continue
            _, inverse = np.unique(self.wrench[rows], axis=0, return_inverse=True)
            for part in _group_rows(inverse.ravel(), rows.size):  # a load's own spread needs rows enough to tell
                out.append((rows[part], rows[part] if part.size >= _MIN_SCALE_ROWS else rows))
        return out

    def repeated(self) -> None:
        table = self.raw if self.wrench is None else np.hstack([self.raw, self.wrench])
        observed, expected, variance, copies = 0, 0.0, 0.0, []
        for rows, spread in self._same_load(self.groups):
            m = rows.size
            if m < 2:
                continue
            _, first, inverse, counts = np.unique(table[rows], axis=0, return_index=True, return_inverse=True,
                                                  return_counts=True)
            inverse = inverse.ravel()
            observed += int(np.sum(counts * (counts - 1) // 2))
            chance, triple = 1.0, 1.0  # two (three) readings of the group equal, channels independent
            for j in range(self.k):
                _, c = np.unique(self.raw[spread, j], return_counts=True)
                chance *= float(np.sum((c / spread.size) ** 2))
                triple *= float(np.sum((c / spread.size) ** 3))
            expected += m * (m - 1) / 2 * chance
            # the pairs share rows, so their count varies more than a Poisson count of that mean: its variance
            # (a U-statistic's) adds the covariance of the pairs that share a row
            variance += m * (m - 1) / 2 * chance * (1 - chance) + m * (m - 1) * (m - 2) * max(triple - chance**2, 0)
            later = np.flatnonzero(np.arange(m) != first[inverse])
            copies.extend((int(rows[i]), int(rows[first[inverse[i]]])) for i in later)
        if not copies:
            return
        from scipy.special import pdtrc

        if pdtrc(observed - 1, expected) >= self.alpha:  # the Poisson chance of at least `observed` pairs
            return
        # many expected pairs (a quiet channel near one level): the count is near Gaussian with the U-statistic's
        # variance, far wider than a Poisson count's; rows are repeated only beyond that too
        if expected >= 1 and observed - expected <= _gaussian_z(self.alpha) * np.sqrt(max(variance, expected)):
            return
        for row, original in copies:
            self.add(FindingKind.REPEATED, row, None, None,
                     f"repeats {self.sources.describe(original)} exactly; {observed} equal pairs of rows where "
                     f"quantisation explains {expected:.2g}")


def check_readings(raw: ArrayLike, *, wrench: ArrayLike | None = None, groups: ArrayLike | None = None,
                   sources=None, channel_names=None, false_alarm_rate: float = 0.01) -> ReadingChecks:
    """Find readings no sensor gave: out of the channel's range, spikes, stuck channels, repeated rows.

    The rules and their thresholds are in the module docstring: every threshold comes from the data's noise and
    ``false_alarm_rate`` (the expected number of false alarms of each check over the dataset, for Gaussian noise).

    Parameters
    ----------
    raw : array-like of shape (n, N)
        The raw readings, rows in recording order within each group.
    wrench : array-like of shape (n, k), optional
        The reference wrench: a repeated row repeats it too.
    groups : array-like of shape (n,), optional
        A label per row (a pose, a session, a file): neighbours in time are looked for within a group.
    sources : RowSources, optional
        Where each row came from (:attr:`CalibrationDataset.sources`); default: rows of ``"dataset"`` from 1.
    channel_names : sequence of str, optional
        The channels' names (default ``s0, s1, ...``).
    false_alarm_rate : float, default=0.01

    Returns
    -------
    ReadingChecks

    Examples
    --------
    >>> rng = np.random.default_rng(0)
    >>> raw = np.round(500 + 5 * rng.standard_normal((200, 4)))  # a 10-bit channel near mid-range
    >>> raw[50, 2] = 4598; raw[120, 0] = 560; raw[150, 3] = 0
    >>> found = check_readings(raw)
    >>> [(f.kind.value, f.line, f.channel, f.value) for f in found.findings]
    [('out_of_range', 51, 's2', 4598.0), ('out_of_range', 151, 's3', 0.0), ('spike', 121, 's0', 560.0)]
    >>> found.adc_ranges["s2"]
    (0.0, 1023.0)
    >>> check_readings(np.round(500 + 5 * rng.standard_normal((200, 4)))).clean
    True
    """
    x = np.asarray(raw, dtype=float)
    if x.ndim != 2:
        raise ValueError(f"raw must be 2-D (n_rows, n_channels); got shape {x.shape}.")
    w = None if wrench is None else np.asarray(wrench, dtype=float)
    if not 0 < false_alarm_rate < 1:
        raise ValueError(f"false_alarm_rate must lie in (0, 1); got {false_alarm_rate!r}.")
    finder = _Finder(x, w, groups, sources, channel_names, false_alarm_rate)
    if x.shape[0] == 0:
        return ReadingChecks(findings=(), n_rows=0)
    stuck = finder.stuck()  # its runs are flagged: not named again as spikes
    z_both, z_one = finder.side_statistics(exclude=stuck)
    ranges = finder.out_of_range(z_both, z_one)
    z = finder.spikes(z_both)
    finder.repeated()
    findings = sorted(finder.findings, key=lambda f: (list(FindingKind).index(f.kind), int(f.rows[0])))
    return ReadingChecks(findings=tuple(findings), n_rows=x.shape[0], adc_ranges=ranges, spike_z=z)


@dataclass(frozen=True)
class AxisExcess:
    """How far the values of one axis (or channel) go beyond its calibrated range.

    Attributes
    ----------
    name : str
        The axis (``Fz``) or channel (``s3``).
    low, high : float
        The calibrated range [N, N·m, or raw units].
    n_rows : int
        Rows looked at.
    n_beyond : int
        Rows below ``low`` or above ``high``.
    largest_factor : float
        The largest ``|value| / max(|low|, |high|)`` of a row beyond: how many times the calibrated full scale it
        reaches (``inf`` for a range of zero; 0 when no row is beyond).
    opposite_sign : int
        Rows beyond of a sign the range never had (a negative load on an axis calibrated from 0 up).
    largest_excess : float
        How far the row furthest beyond lies past the edge it crossed (same unit as the range; 0 when none).
    edge : str or None
        ``"low"`` or ``"high"``: the edge that row crossed.
    tolerance : float
        How far past an edge a value may lie and still count as within (the values' resolution and noise).
    """

    name: str
    low: float
    high: float
    n_rows: int
    n_beyond: int
    largest_factor: float
    opposite_sign: int
    largest_excess: float = 0.0
    edge: str | None = None
    tolerance: float = 0.0

    def words(self, unit: str = "") -> str:
        """One phrase: ``"Fz: 14 of 18 rows beyond -10..10 N, up to 15 N past the high edge (75 % of the calibrated
        span)"``."""
        u = f" {unit}" if unit else ""
        sign = f", {self.opposite_sign} of the opposite sign" if self.opposite_sign else ""
        span = self.high - self.low
        share = f" ({100 * self.largest_excess / span:.3g} % of the calibrated span)" if span > 0 and \
            np.isfinite(span) else ""
        return (f"{self.name}: {self.n_beyond} of {self.n_rows} rows beyond {self.low:.4g}..{self.high:.4g}{u}, up "
                f"to {self.largest_excess:.3g}{u} past the {self.edge} edge{share}{sign}")

    def to_dict(self) -> dict:
        """Plain JSON."""
        return {"axis": self.name, "low": self.low, "high": self.high, "rows": self.n_rows, "beyond": self.n_beyond,
                "largest_factor": None if not np.isfinite(self.largest_factor) else self.largest_factor,
                "largest_excess": self.largest_excess, "edge": self.edge, "tolerance": self.tolerance,
                "opposite_sign": self.opposite_sign}


@dataclass(frozen=True)
class RangeExcess:
    """Per axis, the rows beyond a calibrated range (:func:`range_excess`).

    Attributes
    ----------
    axes : tuple of AxisExcess
    mask : ndarray of bool, shape (n,)
        The rows beyond the range on any axis.
    """

    axes: tuple[AxisExcess, ...]
    mask: NDArray[np.bool_]

    @property
    def any(self) -> bool:
        """Whether some row lies beyond the range."""
        return bool(self.mask.any())

    def beyond(self) -> tuple[AxisExcess, ...]:
        """The axes some row goes beyond."""
        return tuple(a for a in self.axes if a.n_beyond)

    def words(self, units=None) -> str:
        """The axes beyond, one phrase each (:meth:`AxisExcess.words`), joined by ``"; "``."""
        units = dict(units or {})
        return "; ".join(a.words(units.get(a.name, "")) for a in self.beyond())

    @classmethod
    def combined(cls, parts: list["RangeExcess"]) -> "RangeExcess":
        """The excess of the rows of ``parts`` (chunks of one input, same columns and range) taken together."""
        from dataclasses import replace

        axes = []
        for column in zip(*(p.axes for p in parts)):  # the furthest row's excess and edge, the counts summed
            axes.append(replace(max(column, key=lambda a: a.largest_excess), n_rows=sum(a.n_rows for a in column),
                                n_beyond=sum(a.n_beyond for a in column),
                                opposite_sign=sum(a.opposite_sign for a in column),
                                largest_factor=max(a.largest_factor for a in column),
                                tolerance=max(a.tolerance for a in column)))
        return cls(axes=tuple(axes), mask=np.concatenate([p.mask for p in parts]))

    def to_dict(self) -> dict:
        """Plain JSON: ``rows_beyond`` (any axis) and ``axes``."""
        return {"rows": int(self.mask.size), "rows_beyond": int(self.mask.sum()),
                "axes": [a.to_dict() for a in self.axes]}


def range_excess(values: ArrayLike, low: ArrayLike, high: ArrayLike, names=None,
                 tolerance: ArrayLike | None = None) -> RangeExcess:
    """Per axis, how many rows of ``values`` lie beyond the calibrated range ``low..high`` and by how much.

    Used on wrenches (the loads of a validation session against those a model was calibrated on: ``ftcal
    evaluate``, the certificate) and on raw readings (``ftcal predict``: a reading beyond the calibration's).

    Parameters
    ----------
    values : array-like of shape (n, k)
    low, high : array-like of shape (k,)
        The calibrated range of each column (its smallest and largest calibration value); ``-inf`` / ``inf``
        leave a column unchecked.
    names : sequence of str, optional
        The columns' names (default ``0, 1, ...``).
    tolerance : array-like of shape (k,), optional
        How far past an edge a value still counts as within. Default: per column, the larger of the values'
        resolution (their smallest step, an ADC's LSB) and twice their noise (a robust standard deviation of the
        differences of consecutive rows, over sqrt 2), at most 1 % of the calibrated span: a reading a hair past
        the edge (the same load read again, one LSB of noise) is not an extrapolation.

    Returns
    -------
    RangeExcess

    Examples
    --------
    >>> loads = np.array([[0.0, 5.0], [0.0, 22.0], [-3.0, 8.0]])
    >>> found = range_excess(loads, [0.0, -10.0], [10.0, 10.0], names=["Fx", "Fz"])
    >>> found.mask.tolist()
    [False, True, True]
    >>> print(found.words({"Fx": "N", "Fz": "N"}))  # doctest: +NORMALIZE_WHITESPACE
    Fx: 1 of 3 rows beyond 0..10 N, up to 3 N past the low edge (30 % of the calibrated span), 1 of the opposite
    sign; Fz: 1 of 3 rows beyond -10..10 N, up to 12 N past the high edge (60 % of the calibrated span)
    >>> range_excess([[10.0005], [3.0]], [0.0], [10.0]).any  # a hair past the edge: within the tolerance
    False
    """
    v = np.asarray(values, dtype=float)
    if v.ndim == 1:
        v = v[:, None]
    lo = np.broadcast_to(np.asarray(low, dtype=float), (v.shape[1],))
    hi = np.broadcast_to(np.asarray(high, dtype=float), (v.shape[1],))
    names = [str(j) for j in range(v.shape[1])] if names is None else [str(n) for n in names]
    if len(names) != v.shape[1]:
        raise ValueError(f"names gives {len(names)} names for {v.shape[1]} columns.")
    tol = _edge_tolerance(v, lo, hi) if tolerance is None else \
        np.broadcast_to(np.asarray(tolerance, dtype=float), (v.shape[1],))
    out_low, out_high = v < lo - tol, v > hi + tol
    outside = out_low | out_high
    axes = []
    with np.errstate(divide="ignore", invalid="ignore"):
        for j, name in enumerate(names):
            rows = outside[:, j]
            reach = max((abs(x) for x in (lo[j], hi[j]) if np.isfinite(x)), default=np.inf)
            factor = float(np.max(np.abs(v[rows, j]))) / reach if rows.any() else 0.0
            below = float(np.max(lo[j] - v[out_low[:, j], j], initial=0.0))
            above = float(np.max(v[out_high[:, j], j] - hi[j], initial=0.0))
            opposite = int(np.sum((out_low[:, j] & (lo[j] >= 0) & (v[:, j] < 0))
                                  | (out_high[:, j] & (hi[j] <= 0) & (v[:, j] > 0))))
            axes.append(AxisExcess(name=name, low=float(lo[j]), high=float(hi[j]), n_rows=int(v.shape[0]),
                                   n_beyond=int(rows.sum()), largest_factor=factor if reach > 0 or not rows.any()
                                   else float("inf"), opposite_sign=opposite, largest_excess=max(below, above),
                                   edge=None if not rows.any() else "low" if below >= above else "high",
                                   tolerance=float(tol[j])))
    return RangeExcess(axes=tuple(axes), mask=outside.any(axis=1))


def _edge_tolerance(v: NDArray[np.float64], lo: NDArray[np.float64], hi: NDArray[np.float64]) -> NDArray:
    """Per column: the larger of the values' resolution and twice their noise, at most 1 % of the span
    (:func:`range_excess`)."""
    out = np.zeros(v.shape[1])
    for j in range(v.shape[1]):
        span = hi[j] - lo[j]
        column = v[:, j][np.isfinite(v[:, j])]
        if column.size < 2 or not np.isfinite(span) or span <= 0:
            continue
        noise = float(_robust_scale(np.abs(np.diff(column))[:, None])[0]) / np.sqrt(2)
        out[j] = min(max(_quantum(column), 2 * noise), 0.01 * span)
    return out
