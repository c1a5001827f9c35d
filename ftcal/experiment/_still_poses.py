"""Still poses found in a continuous recording: where the robot stood still, minus the settling, averaged.

A robot's own recording (a ROS bag, a CSV with a ``time`` column) runs on while the arm moves between poses.
:func:`find_still_poses` finds the poses instead of assuming them:

1. **Still segments.** From each sample on, the segment grows while the pose stays within ``tolerance_deg``
   of the segment's first sample (the largest joint change, or the angle between the two orientations).
   Each segment is then trimmed to the samples within a tenth of that of its middle sample: the arm creeping
   into and out of the pose already changes the reading (0.5 deg of tilt moves ~1 % of the tool's weight
   between the axes). Segments shorter than ``min_duration_s`` are passes through a pose during a move.
2. **Settling.** A sensor reads a transient after each move (mechanical ringing, the gauges' creep, a
   cable settling): up to about 1 N over the first seconds on a real Axia80. The first ``settle_s`` seconds of
   each still segment are dropped. Without ``settle_s`` it comes from the data: in each segment, the
   moving mean of the reading (over a twentieth of the segment) is compared with the segment's final level
   (the mean of its last third); the settling lasts until that moving mean stays within 4 standard errors of
   the noise (estimated from the sample-to-sample differences of the segment's second half, which a slow
   transient does not inflate). The upper quartile over the segments is used for all of them.
3. **Averaging.** Each pose is the mean of its settled samples, with their standard deviation (the
   spread), the mean time (for a bias drift in time) and the mean pose.
4. **Rejections**, each with its reason: a segment with fewer than ``min_samples`` samples after the
   settling, and a pose whose spread is more than :data:`UNSTEADY_FACTOR` times the median spread of the
   poses in some component (something touched the tool, or the arm swayed).

Examples
--------
>>> import numpy as np
>>> t = np.arange(0, 20, 0.1)                             # 10 Hz, two 10 s poses
>>> q = np.where(t < 10, 0.0, 0.5)[:, None]               # one joint [rad], a jump at 10 s
>>> reading = np.where(t < 10, 1.0, 2.0)[:, None] + np.exp(-(t % 10) / 0.5)[:, None]  # a settling transient
>>> poses = find_still_poses(t, reading, joints=q)
>>> len(poses.time), poses.reading.round(3).ravel().tolist(), poses.settle_s > 1.0
(2, [1.0, 2.0], True)
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..core._exceptions import NO_SETTING, CalibrationInputError

__all__ = ["StillPoses", "find_still_poses", "DEFAULT_STILL_TOLERANCE_DEG", "DEFAULT_MIN_STILL_S", "UNSTEADY_FACTOR"]

#: A pose is still while it stays within this of its first sample [deg] (joints: each joint; else the orientation).
DEFAULT_STILL_TOLERANCE_DEG = 0.5
#: A still segment shorter than this is a pass through a pose during a move, not a pose [s].
DEFAULT_MIN_STILL_S = 1.0
#: A pose whose spread exceeds this many times the median spread of the poses (in a component) is rejected.
UNSTEADY_FACTOR = 5.0
#: A still segment is trimmed to the samples within this fraction of the tolerance of its middle sample.
_TRIM_FRACTION = 0.1
#: Settled moving means stay within this many standard errors of the segment's final level.
_SETTLED_Z = 4.0


@dataclass
class StillPoses:
    """The still poses of a recording, averaged, and what was found and rejected.

    Attributes
    ----------
    time : ndarray of shape (k,)
        Mean time of each kept pose's averaged samples [s] (the pose's time stamp).
    start_time, end_time : ndarray of shape (k,)
        First and last averaged sample of each pose [s] (after the settling).
    reading : ndarray of shape (k, m)
        Mean reading of each pose (wrench [N, N·m] or raw channels).
    spread : ndarray of shape (k, m)
        Standard deviation of the averaged samples.
    n_samples : ndarray of shape (k,)
        Samples averaged per pose.
    first_index : ndarray of shape (k,)
        Index of each pose's first averaged sample in the recording.
    rotation : ndarray of shape (k, 3, 3) or None
        Mean orientation (sensor to base frame), when the recording gave orientations.
    joints : ndarray of shape (k, n_joints) or None
        Mean joint angles [rad], when the recording gave joints.
    settle_s : float
        The settling dropped at the start of each pose [s].
    settle_from_data : bool
        Whether ``settle_s`` was estimated from the data (else given).
    n_found : int
        Still segments at least ``min_duration_s`` long.
    rejected : list of (float, str)
        Start time [s] and reason of each rejected segment.
    recording_start : float
        Time of the recording's first sample [s] (the summary gives times from it).
    """

    time: NDArray[np.float64]
    start_time: NDArray[np.float64]
    end_time: NDArray[np.float64]
    reading: NDArray[np.float64]
    spread: NDArray[np.float64]
    n_samples: NDArray[np.int64]
    first_index: NDArray[np.int64]
    rotation: NDArray[np.float64] | None
    joints: NDArray[np.float64] | None
    settle_s: float
    settle_from_data: bool
    n_found: int
    rejected: list[tuple[float, str]] = field(default_factory=list)
    recording_start: float = 0.0

    @property
    def n_kept(self) -> int:
        """Number of poses kept."""
        return int(len(self.time))

    def summary(self) -> str:
        """One line: how many poses were found, kept and rejected (and why), and the settling used."""
        how = "from the data: until the drift decays into the noise" if self.settle_from_data else "given"
        text = (f"found {self.n_found} still poses, kept {self.n_kept}, rejected {len(self.rejected)}; "
                f"settling {self.settle_s:.3g} s dropped from each ({how})")
        if self.rejected:
            shown = "; ".join(f"{t - self.recording_start:.1f} s into the recording: {why}"
                              for t, why in self.rejected[:5])
            more = f"; and {len(self.rejected) - 5} more" if len(self.rejected) > 5 else ""
            text += f" — rejected {shown}{more}"
        return text


def _deviation(rotations: NDArray | None, joints: NDArray | None):
    """``dev(a, sl)``: how far the samples ``sl`` are from sample ``a`` [rad]."""
    if joints is not None:
        return lambda a, sl: np.abs(joints[sl] - joints[a]).max(axis=1)

    def angle(a: int, sl: slice) -> NDArray[np.float64]:
        cos = (np.einsum("ij,nij->n", rotations[a], rotations[sl]) - 1.0) / 2.0
        return np.arccos(np.clip(cos, -1.0, 1.0))
    return angle


#: A looser still tolerance is advised at most this many times the given one, and at most this large [deg]; a
#: shorter still segment is advised only if the longest one lasts at least this long [s].
_LOOSER_TOLERANCE, _MAX_ADVISED_TOLERANCE_DEG, _MIN_ADVISED_STILL_S = 4.0, 5.0, 0.2


def _segments(n: int, dev, tol_rad: float) -> list[tuple[int, int]]:
    """Maximal runs ``[a, b)`` whose samples stay within ``tol_rad`` of sample ``a``, in order."""
    out = []
    a = 0
    while a < n:
        width, end = 16, None
        while end is None:
            stop = min(n, a + width)
            over = np.flatnonzero(dev(a, slice(a, stop)) > tol_rad)
            if over.size:
                end = a + int(over[0])
            elif stop == n:
                end = n
            else:
                width *= 4
        out.append((a, max(end, a + 1)))
        a = max(end, a + 1)
    return out


def _trim(dev, a: int, b: int, fine_rad: float) -> tuple[int, int]:
    """The segment ``[a, b)`` without its approach and departure: the samples from the first to the last within
    ``fine_rad`` of its middle sample (the arm creeping into and out of a pose changes the reading already)."""
    if b - a < 3:
        return a, b
    close = np.flatnonzero(dev((a + b) // 2, slice(a, b)) <= fine_rad)
    return a + int(close[0]), a + int(close[-1]) + 1


def _settle_time(t: NDArray[np.float64], y: NDArray[np.float64]) -> float:
    """How long the reading ``y`` (L, m) of one still segment takes to settle into its noise [s]."""
    L = len(y)
    if L < 12:
        return 0.0
    tail = y[L // 2:]
    d = np.diff(tail, axis=0)
    sigma = 1.4826 * np.median(np.abs(d - np.median(d, axis=0)), axis=0) / np.sqrt(2.0)
    sigma = np.maximum(sigma, 0.1 * tail.std(axis=0) + 1e-12 * (np.abs(tail).max(axis=0) + 1e-300))
    ref = y[L - max(L // 3, 1):].mean(axis=0)
    m = max(3, L // 20)
    c = np.cumsum(np.vstack([np.zeros((1, y.shape[1])), y]), axis=0)
    window_mean = (c[m:] - c[:-m]) / m  # window j covers samples j .. j+m-1
    z = (np.abs(window_mean - ref) / (sigma / np.sqrt(m))).max(axis=1)
    early = int(0.6 * L)  # settling happens at the start; a slow wander late in the pose is not settling
    over = np.flatnonzero(z[:early] > _SETTLED_Z)
    if not over.size:
        return 0.0
    return float(t[min(int(over[-1]) + m, L - 1)] - t[0])


def find_still_poses(
    time: ArrayLike,
    reading: ArrayLike,
    *,
    rotations: ArrayLike | None = None,
    joints: ArrayLike | None = None,
    tolerance_deg: float = DEFAULT_STILL_TOLERANCE_DEG,
    settle_s: float | None = None,
    min_duration_s: float = DEFAULT_MIN_STILL_S,
    min_samples: int = 3,
) -> StillPoses:
    """Find the still poses of a continuous recording and average each (method in the module docstring).

    Parameters
    ----------
    time : array-like of shape (n,)
        Sample times [s], increasing.
    reading : array-like of shape (n, m)
        The sensor's reading at those times (wrench [N, N·m] or raw channels).
    rotations : array-like of shape (n, 3, 3), optional
        The sensor's orientation (sensor to base frame) at those times.
    joints : array-like of shape (n, n_joints), optional
        The joint angles [rad] at those times (give ``rotations`` or ``joints``).
    tolerance_deg : float, default=0.5
        A pose is still while it stays within this of its first sample [deg].
    settle_s : float, optional
        Settling dropped at the start of each pose [s]; default from the data.
    min_duration_s : float, default=1.0
        Shortest still segment that is a pose [s].
    min_samples : int, default=3
        Fewest samples a pose keeps after the settling.

    Returns
    -------
    StillPoses

    Raises
    ------
    CalibrationInputError
        Bad shapes or values, times that do not increase, or no still pose at all (the message gives the
        longest still stretch and the options that set the thresholds).
    """
    t = np.asarray(time, dtype=float)
    y = np.asarray(reading, dtype=float)
    if y.ndim == 1:
        y = y[:, None]
    if t.ndim != 1 or y.ndim != 2 or len(y) != len(t):
        raise CalibrationInputError(f"time (shape {t.shape}) and reading (shape {y.shape}) must have one row per "
                                    "sample.")
    if (rotations is None) == (joints is None):
        raise CalibrationInputError("give the pose of each sample as rotations (n, 3, 3) or joints (n, n_joints), "
                                    "one of the two.")
    R = None if rotations is None else np.asarray(rotations, dtype=float)
    q = None if joints is None else np.asarray(joints, dtype=float)
    pose = R if R is not None else q
    if len(pose) != len(t) or (R is not None and R.shape[1:] != (3, 3)) or (q is not None and q.ndim != 2):
        raise CalibrationInputError(f"the poses (shape {pose.shape}) must have one row per sample ({len(t)}).")
    for name, a in (("time", t), ("reading", y), ("poses", pose)):
        if not np.isfinite(a).all():
            raise CalibrationInputError(f"{name} holds NaN or inf.")
    if len(t) > 1 and not (np.diff(t) > 0).all():
        i = int(np.flatnonzero(np.diff(t) <= 0)[0]) + 1
        raise CalibrationInputError(f"time must increase; sample {i} ({t[i]:.9g} s) follows {t[i - 1]:.9g} s.")
    for name, v in (("tolerance_deg", tolerance_deg), ("min_duration_s", min_duration_s)):
        if not (np.isfinite(v) and v > 0):
            raise CalibrationInputError(f"{name} must be a positive number; got {v!r}.")
    if settle_s is not None and not (np.isfinite(settle_s) and settle_s >= 0):
        raise CalibrationInputError(f"settle_s must be a number of seconds >= 0; got {settle_s!r}.")
    n = len(t)
    dev = _deviation(R, q)
    segments = _segments(n, dev, np.radians(tolerance_deg))
    segments = [_trim(dev, a, b, np.radians(tolerance_deg) * _TRIM_FRACTION) for a, b in segments]
    found = [(a, b) for a, b in segments if t[b - 1] - t[a] >= min_duration_s]
    if not found:
        longest = max((t[b - 1] - t[a] for a, b in segments), default=0.0)
        said = (f"no still pose in the {n} samples ({t[0]:.6g} to {t[-1]:.6g} s): the pose never stays within "
                f"{tolerance_deg:g} deg for {min_duration_s:g} s (the longest still stretch lasts {longest:.3g} s). ")
        # advice checked before it is given: a looser threshold is proposed only where it finds a still pose
        looser = _LOOSER_TOLERANCE * tolerance_deg
        wider = [(a, b) for a, b in _segments(n, dev, np.radians(looser)) if t[b - 1] - t[a] >= min_duration_s]
        options = {}
        if wider and looser <= _MAX_ADVISED_TOLERANCE_DEG:
            options["tolerance_deg"] = float(f"{looser:.3g}")
        if longest >= _MIN_ADVISED_STILL_S:
            options["min_duration_s"] = float(f"{longest * 0.9:.2g}")
        if not options:
            raise CalibrationInputError(said + "Loosening the thresholds would not find one either (the pose "
                                        "moves throughout). Fix: record the sensor while the robot stands still "
                                        "at each pose.", parameter="tolerance_deg", value=tolerance_deg)
        raise CalibrationInputError(
            said + "Fix: record the sensor while the robot stands still at each pose, or loosen "
            + " / ".join("{" + k + "}" for k in options) + " (checked: that finds still poses).",
            parameter="tolerance_deg", value=tolerance_deg, settings=options)
    from_data = settle_s is None
    if from_data:
        settle_s = float(np.percentile([_settle_time(t[a:b], y[a:b]) for a, b in found], 75))
    kept, rejected = [], []
    for a, b in found:
        idx = np.arange(a, b)[t[a:b] >= t[a] + settle_s]
        if len(idx) < min_samples:
            rejected.append((float(t[a]), f"{len(idx)} samples after the {settle_s:.3g} s settling (still for "
                                          f"{t[b - 1] - t[a]:.3g} s; at least {min_samples} needed)"))
        else:
            kept.append(idx)
    spread = np.array([y[i].std(axis=0) for i in kept]).reshape(len(kept), y.shape[1])
    if len(kept) >= 3:
        typical = np.median(spread, axis=0)
        ratio = np.where(typical > 0, spread / np.where(typical > 0, typical, 1.0), 0.0).max(axis=1)
        steady = ratio <= UNSTEADY_FACTOR
        for i in np.flatnonzero(~steady):
            rejected.append((float(t[kept[i][0]]), f"unsteady: its spread is {ratio[i]:.3g} times the typical pose's "
                                                   "(something touching the tool, or the arm swaying?)"))
        kept = [k for k, s in zip(kept, steady) if s]
        spread = spread[steady]
    rejected.sort()
    if not kept:
        raise CalibrationInputError(
            f"found {len(found)} still poses but kept none: {rejected[0][1]} (the first "
            f"{rejected[0][0] - t[0]:.1f} s into the recording). "
            "Fix: hold each pose longer, or give a shorter {settle_s}.", parameter="settle_s", value=settle_s)
    rotation = None
    if R is not None:
        from scipy.spatial.transform import Rotation

        rotation = np.array([Rotation.from_matrix(R[i]).mean().as_matrix() for i in kept])
    return StillPoses(
        time=np.array([t[i].mean() for i in kept]), start_time=np.array([t[i[0]] for i in kept]),
        end_time=np.array([t[i[-1]] for i in kept]), reading=np.array([y[i].mean(axis=0) for i in kept]),
        spread=spread, n_samples=np.array([len(i) for i in kept], dtype=np.int64),
        first_index=np.array([i[0] for i in kept], dtype=np.int64), rotation=rotation,
        joints=None if q is None else np.array([q[i].mean(axis=0) for i in kept]),
        settle_s=float(settle_s), settle_from_data=from_data, n_found=len(found), rejected=rejected,
        recording_start=float(t[0]),
    )
