"""ROS bags in (rosbag2 in sqlite3 or MCAP, ROS 1 ``.bag``): the sensor's stream and the arm's pose, aligned.

Read through ``rosbags`` (pure Python, no ROS install; ``pip install "ftcal[ros]"``), imported only here and
only when a bag is read or written.

What is read
------------
* **the sensor**: a wrench topic (``geometry_msgs/WrenchStamped`` or ``Wrench``: a factory-calibrated
  sensor) or a raw-gauge topic (any message with a numeric array field, e.g.
  ``std_msgs/Float64MultiArray`` and its ``data``; ``raw_field`` names the field, dotted for a nested one);
* **the pose**: joint states (``sensor_msgs/JointState``: names and positions [rad]), or the sensor's
  orientation from ``/tf`` and ``/tf_static`` (``tf2_msgs/TFMessage``), the chain of transforms from a base
  frame to the sensor frame composed at each sensor stamp.

**Stamps.** Each message's header stamp (``stamps="header"``), or the time the recorder received it
(``"receive"``; messages without a header always use it). The joints are interpolated linearly at the
sensor's stamps (the tf rotations spherically); sensor samples outside the pose stream's span are dropped.
**Clock offsets**: for every stamped topic the median of (receive time - header stamp) is its clock's offset
from the recorder's; two topics whose offsets differ by more than :data:`CLOCK_OFFSET_TOLERANCE_S` are
named (:attr:`BagRecording.notes`), and topics whose stamps do not even overlap are refused, with the fix
(``stamps="receive"``).

**Memory** stays bounded whatever the bag's size: the bag is streamed message by message, only the chosen
topics are decoded, and a topic with more than ``max_samples`` messages is reduced on the fly (the sensor by
averaging blocks of consecutive messages, which a still pose's average does anyway; the pose streams by
keeping every k-th message, they are smooth). A several-GB bag is read in the memory of ``max_samples``
samples.

Every error is a :class:`~ftcal.core.LogFormatError` naming the bag and, for a missing topic or a wrong type,
the topics the bag holds.
"""

from __future__ import annotations

import contextlib
import functools
import math
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..core._exceptions import LogFormatError, Placeholder

__all__ = ["BagRecording", "read_bag", "write_bag", "is_bag", "bag_topics", "bag_values", "WRENCH_TYPES", "JOINT_STATE_TYPE",
           "TF_TYPE", "CLOCK_OFFSET_TOLERANCE_S", "DEFAULT_MAX_SAMPLES", "BAG_STORAGES"]

WRENCH_TYPES = ("geometry_msgs/msg/WrenchStamped", "geometry_msgs/msg/Wrench")
JOINT_STATE_TYPE = "sensor_msgs/msg/JointState"
TF_TYPE = "tf2_msgs/msg/TFMessage"
#: Two topics whose clocks differ by more than this [s] (judged against the recorder's receive times) are named.
CLOCK_OFFSET_TOLERANCE_S = 0.05
#: Most samples kept per topic; longer topics are reduced on the fly (see the module docstring).
DEFAULT_MAX_SAMPLES = 200_000
#: Numbers no recording holds, serialized once to find where a message's values and stamp sit in its bytes.
_SENTINELS = np.array([1.2345678901234567e300 + k * 1e285 for k in range(4096)])
_STAMP_SEC, _STAMP_NSEC = 0x1234567, 0x7654321
_STAMP_SENTINEL = np.array([(_STAMP_SEC, _STAMP_NSEC)], dtype=[("s", "<i4"), ("n", "<u4")]).tobytes()
#: The bag formats :func:`write_bag` writes (and :func:`read_bag` reads).
BAG_STORAGES = ("sqlite3", "mcap", "ros1")
#: A /tf quaternion shorter than this is no rotation (a zero quaternion); scipy would normalise anything longer.
_MIN_QUATERNION_NORM = 1e-6
#: Most distinct joint-name sets read from one joint-state topic (an arm's, a gripper's, ...).
_MAX_JOINT_GROUPS = 16


def check_rosbags() -> None:
    """Raise the fix (install the extra) when rosbags is missing."""
    try:
        import rosbags  # noqa: F401
    except ImportError:
        raise LogFormatError('reading ROS bags needs the rosbags package: pip install "ftcal[ros]"') from None


def is_bag(path: str | Path) -> bool:
    """Whether ``path`` is a ROS bag: a ROS 1 ``.bag`` file, or a rosbag2 folder (``metadata.yaml``), or the
    ``.db3`` / ``.mcap`` file inside one.

    Examples
    --------
    >>> is_bag("run.bag"), is_bag("poses.csv")
    (True, False)
    """
    p = Path(path)
    if p.suffix == ".bag":
        return True
    if p.is_dir():
        return (p / "metadata.yaml").is_file()
    return p.suffix in (".db3", ".mcap") and (p.parent / "metadata.yaml").is_file()


def _streaming_ros1_reader():
    """rosbags' ROS 1 reader without its per-message index: the chunks are read in file order, one at a time.

    rosbags' reader builds an index entry for every message when it opens a bag (about 160 bytes each: gigabytes
    for a bag of tens of millions of messages); this one keeps the connections and the per-chunk counts only.
    """
    import os
    from io import BytesIO

    from rosbags.rosbag1.reader import Header, Reader, RecordType, read_bytes, read_uint32

    class StreamingReader(Reader):
        def read_index_data(self, pos, indexes) -> None:  # skipped, never kept: messages() reads chunk by chunk
            buf = self.bio.read(55)  # the index record's header (47 bytes, as rosbags reads it), its data's size
            self.bio.seek(int.from_bytes(buf[51:55], "little"), os.SEEK_CUR)

        def open(self) -> None:
            super().open()
            counts: dict[int, int] = {}
            for info in getattr(self, "chunk_infos", None) or ():
                for conn, n in info.connection_counts.items():
                    counts[conn] = counts.get(conn, 0) + n
            self.connections = [c._replace(msgcount=counts.get(c.id, 0)) for c in self.connections]

        def messages(self, connections=(), start=None, stop=None):
            self._check_open()
            wanted = {c.id for c in (connections or self.connections)}
            by_id = {c.id: c for c in self.connections}
            for info in self.chunk_infos:
                if not wanted & set(info.connection_counts):
                    continue
                self.bio.seek(info.pos)
                chunk = self.read_chunk()
                self.bio.seek(chunk.datapos)
                raw = chunk.decompressor(read_bytes(self.bio, chunk.datasize))
                records = BytesIO(raw)
                while records.tell() < len(raw):
                    header = Header.read(records)
                    size = read_uint32(records)
                    if header.get_uint8("op") != RecordType.MSGDATA or header.get_uint32("conn") not in wanted:
                        records.seek(size, os.SEEK_CUR)
                        continue
                    time = header.get_time("time")
                    data = read_bytes(records, size)
                    if (start is None or time >= start) and (stop is None or time < stop):
                        yield by_id[header.get_uint32("conn")], time, data

    return StreamingReader


class _Reader:
    """An open bag, every failure of the reader (truncated, damaged, not a bag) turned into one LogFormatError."""

    def __init__(self, path: Path) -> None:
        check_rosbags()
        from rosbags.highlevel import AnyReader
        from rosbags.typesys import Stores, get_typestore

        self.path = path
        with self.failures():  # a path the file system refuses to look at is named as the bag's failure too
            if path.suffix in (".db3", ".mcap") and (path.parent / "metadata.yaml").is_file():
                path = path.parent  # the storage file of a rosbag2 folder: the folder
            if not path.exists():
                raise LogFormatError(f"{path}: no such bag.")
            if path.suffix != ".bag" and not (path / "metadata.yaml").is_file():
                raise LogFormatError(f"{path}: not a ROS bag (a ROS 1 .bag file, or a rosbag2 folder with "
                                     "metadata.yaml).")
            self.reader = AnyReader([path], default_typestore=get_typestore(Stores.ROS2_HUMBLE))
            if not self.reader.is2:  # streamed chunk by chunk (rosbags' reader indexes every message first)
                self.reader.readers = [_streaming_ros1_reader()(path)]
            self.reader.open()

    @contextlib.contextmanager
    def failures(self):
        """Every failure of the reader within (truncated, damaged, not a bag) raised as one LogFormatError naming
        the bag and the fix; ftcal's own errors pass as they are."""
        try:
            yield
        except LogFormatError:
            raise
        except Exception as exc:  # rosbags raises its own errors, sqlite3's, struct's, KeyError on damaged data
            text = " ".join(str(exc).split())[:160] or type(exc).__name__
            raise LogFormatError(f"{self.path}: cannot read the bag ({text}); is it truncated or damaged (a "
                                 "recording cut short)? Re-index or re-record it (ROS 1: rosbag reindex; ROS 2: ros2 "
                                 "bag reindex).") from None

    def __enter__(self) -> "_Reader":
        return self

    def __exit__(self, *exc) -> None:
        with contextlib.suppress(Exception):  # closing a damaged bag may fail too; the first error is the one to show
            self.reader.close()

    def topics(self) -> dict[str, tuple[str, int]]:
        return {name: (info.msgtype or "?", int(info.msgcount)) for name, info in self.reader.topics.items()}


def bag_topics(path: str | Path) -> dict[str, tuple[str, int]]:
    """The topics of a bag: name -> (message type, message count).

    Examples
    --------
    >>> import tempfile, pathlib, numpy as np
    >>> bag = pathlib.Path(tempfile.mkdtemp()) / "rec"
    >>> _ = write_bag(bag, "mcap", sensor_time=[0.0, 0.1], reading=np.zeros((2, 6)), pose_time=[0.0, 0.1],
    ...               joints=np.zeros((2, 2)), joint_names=["a", "b"])
    >>> bag_topics(bag)
    {'/ft_sensor/wrench': ('geometry_msgs/msg/WrenchStamped', 2), '/joint_states': ('sensor_msgs/msg/JointState', 2)}
    """
    with _Reader(Path(path)) as r:
        return r.topics()


def bag_values(path: str | Path, head: int | None = None):
    """The values a bag's reader can use, as digests (for :func:`ftcal.core.content_twins`): the listing of the
    topics it can read (name, type, count: wrenches, joint states, ``/tf``, and topics holding an array of
    numbers, the raw readings), then per topic one SHA-256 of its messages' field values in their order (numbers
    as float64, then text; a ROS 1 header's ``seq`` left out), so one recording stored as sqlite3, MCAP or ROS 1
    gives the same values. Receive times and topics of anything else (log text, strings) are left out: a copy of
    a bag with its receive times shifted, or with a topic of log messages added, gives the same values (its header
    stamps, which the reader uses, are the same). The messages are streamed: memory does not grow with the bag.
    A list of arrays. With ``head``, only the first ``head`` messages of each topic: a cheap key that tells most
    different recordings apart.

    Examples
    --------
    >>> import tempfile, pathlib, numpy as np
    >>> d = pathlib.Path(tempfile.mkdtemp())
    >>> kw = dict(sensor_time=[0.0, 0.1], reading=np.zeros((2, 6)), pose_time=[0.0, 0.1], joints=np.zeros((2, 2)),
    ...           joint_names=["a", "b"])
    >>> a, b = write_bag(d / "a", "sqlite3", **kw), write_bag(d / "b.bag", "ros1", **kw)
    >>> [v.tolist() for v in bag_values(a)] == [v.tolist() for v in bag_values(b)]
    True
    >>> bag_values(a)[0].tolist()  # the listing, then a digest per topic
    ['/ft_sensor/wrench geometry_msgs/msg/WrenchStamped 2', '/joint_states sensor_msgs/msg/JointState 2']
    """
    import hashlib

    def flat(value, numbers: list, text: list) -> None:
        if hasattr(value, "__dataclass_fields__"):
            for name in value.__dataclass_fields__:
                if name != "seq" and not name.startswith("__"):
                    flat(getattr(value, name), numbers, text)
        elif isinstance(value, (list, tuple)):
            text.append(f"[{len(value)}")  # the length: [1, 2], [] and [1], [2] differ
            for item in value:
                flat(item, numbers, text)
        elif isinstance(value, np.ndarray) and value.dtype.kind in "biuf":
            text.append(f"<{value.size}")
            numbers.extend(value.astype(np.float64).ravel().tolist())
        elif isinstance(value, (bool, int, float, np.number)):
            numbers.append(float(value))
        else:
            text.append(str(value))

    def has_numbers(value) -> bool:  # an array of numbers somewhere in a message: a raw topic's kind (a byte blob,
        if isinstance(value, np.ndarray):  # a camera's or a point cloud's, is not: no reader takes its readings)
            return value.dtype.kind in "biuf" and value.dtype.itemsize > 1 and value.size > 0
        if hasattr(value, "__dataclass_fields__"):
            return any(has_numbers(getattr(value, n)) for n in value.__dataclass_fields__ if not n.startswith("__"))
        return False

    known = (*WRENCH_TYPES, JOINT_STATE_TYPE, TF_TYPE)
    digests: dict[str, object] = {}  # topic -> its running digest (None: a topic the reader cannot use)
    counts: dict[str, int] = {}
    with _Reader(Path(path)) as r:
        # with head: the topics still short of their first messages; the bag is read no further once none is
        listed = r.topics()
        pending = {t for t, (_, n) in listed.items() if n > 0} if head is not None else None
        with r.failures():
            for conn, _receive_ns, data in r.reader.messages():
                topic = conn.topic
                if topic in digests and digests[topic] is None or head is not None and counts.get(topic, 0) >= head:
                    continue
                msg = r.reader.deserialize(data, conn.msgtype)
                if topic not in digests:
                    digests[topic] = hashlib.sha256() if conn.msgtype in known or has_numbers(msg) else None
                if digests[topic] is not None:
                    numbers, text = [], []
                    flat(msg, numbers, text)
                    digests[topic].update(np.asarray(numbers, dtype=np.float64).tobytes())
                    digests[topic].update("\x00".join(text).encode("utf-8") + b"\x01")
                    counts[topic] = counts.get(topic, 0) + 1
                if pending is not None and (digests[topic] is None or counts[topic] >= min(head, listed[topic][1])):
                    pending.discard(topic)
                    if not pending:
                        break
    used = sorted(t for t, digest in digests.items() if digest is not None)
    return [np.array([f"{t} {listed[t][0]} {listed[t][1]}" for t in used]),
            *(np.array([digests[t].hexdigest()]) for t in used)]


def _listing(topics: dict[str, tuple[str, int]]) -> str:
    return ", ".join(f"{t} ({typ}, {n} messages)" for t, (typ, n) in sorted(topics.items())) or "no topics"


def _choose_topic(path: Path, topics: dict, given: str | None, types: tuple[str, ...], role: str,
                  parameter: str) -> str:
    """The topic of ``role`` (the argument ``parameter``): the given one (checked), else the bag's only topic of
    one of ``types``."""
    if given is not None:
        if given not in topics:
            raise LogFormatError(f"{path}: no topic {given} ({role}); the bag has {_listing(topics)}.",
                                 parameter=parameter, value=given)
        if types and topics[given][0] not in types:
            raise LogFormatError(f"{path}: topic {given} holds {topics[given][0]}, not {' or '.join(types)} ({role}); "
                                 f"the bag has {_listing(topics)}.", parameter=parameter, value=given,
                                 fix=f"name the right topic with {{{parameter}}}")
        return given
    candidates = sorted(t for t, (typ, _) in topics.items() if typ in types)
    if len(candidates) != 1:
        what = "no" if not candidates else f"{len(candidates)}"
        raise LogFormatError(f"{path}: {what} topics of type {' or '.join(types)} ({role}); the bag has "
                             f"{_listing(topics)}.", parameter=parameter, value=None,
                             fix=f"name it with {{{parameter}}}", settings={parameter: Placeholder("TOPIC")})
    return candidates[0]


class _Stream:
    """A topic's (or a /tf edge's) samples, reduced on the fly to at most ``2 * max_samples`` (block means, or
    every k-th).

    The bag's declared message count only sets the first block size: when the buffer fills (a bag whose index or
    ``metadata.yaml`` under-counts), neighbouring stored samples are merged in pairs in place and the block doubles,
    so memory stays bounded whatever the bag declares.
    """

    def __init__(self, count: int, max_samples: int, average: bool) -> None:
        self.block = max(1, math.ceil(count / max_samples))
        self.average = average
        self.capacity = 2 * max_samples
        self._rows = min(self.capacity, max(1, math.ceil(count / self.block)) + 1)
        self.data: NDArray[np.float64] | None = None  # columns: header time, receive time, value...
        self.n = 0
        self.n_messages = 0  # how many messages were added
        self._sum: NDArray[np.float64] | None = None
        self._in_block = 0

    def add(self, t: float, receive: float, value: NDArray[np.float64]) -> None:
        row = np.concatenate([[t, receive], value])
        if self.data is None:
            self.data, self._sum = np.empty((self._rows, len(row))), np.zeros(len(row))
        self.n_messages += 1
        if not self.average:
            if (self.n_messages - 1) % self.block == 0:
                self._store(row)
            return
        self._sum += row
        self._in_block += 1
        if self._in_block == self.block:
            self.flush()

    def flush(self) -> None:
        if self.average and self._in_block:
            self._store(self._sum / self._in_block)
            self._sum[:] = 0.0
            self._in_block = 0

    def _store(self, row: NDArray[np.float64]) -> None:
        if self.n >= self.capacity:  # more messages than the bag declared: halve what is kept, double the block
            half = self.n // 2
            if self.average:  # each stored sample is the mean of one block: a pair's mean is that of two blocks
                self.data[:half] = 0.5 * (self.data[0:2 * half:2] + self.data[1:2 * half:2])
            else:  # every k-th message: keep every 2k-th
                self.data[:half] = self.data[0:2 * half:2]
            self.n = half
            self.block *= 2
        if self.n >= len(self.data):  # grown: the first rows kept (np.resize fills the rest with copies)
            self.data = np.resize(self.data, (min(self.capacity, 2 * len(self.data)), self.data.shape[1]))
        self.data[self.n] = row
        self.n += 1

    def arrays(self) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64]]:
        self.flush()
        if self.data is None:
            return np.empty(0), np.empty(0), np.empty((0, 0))
        kept = self.data[:self.n]
        return kept[:, 0].copy(), kept[:, 1].copy(), kept[:, 2:].copy()


@dataclass
class BagRecording:
    """A bag's sensor stream with the pose at each sensor stamp.

    Attributes
    ----------
    path : pathlib.Path
    sensor_topic : str
    kind : str
        ``"wrench"`` [N, N·m] or ``"raw"`` (the raw gauges' array).
    time : ndarray of shape (n,)
        Sensor stamps [s] (header stamps or receive times; see ``stamps``).
    reading : ndarray of shape (n, m)
    joints : ndarray of shape (n, n_joints) or None
        Joint positions [rad] interpolated at ``time``.
    joint_names : tuple of str
    rotation : ndarray of shape (n, 3, 3) or None
        The sensor's orientation (sensor to base) from tf at ``time``.
    pose_topic : str
    frame_id : str
        The sensor messages' ``header.frame_id`` ('' without a header).
    clock_offset_s : dict
        Per stamped topic, the median of (receive time - header stamp) [s].
    stamps : str
    notes : list of LogFormatError
        What a user should know (not errors; ``str(note)`` is its text, its fields as for an error): clock
        offsets between topics, samples dropped outside the pose stream, messages averaged per sample.
    topics : dict
        Every topic of the bag: name -> (type, count).
    """

    path: Path
    sensor_topic: str
    kind: str
    time: NDArray[np.float64]
    reading: NDArray[np.float64]
    joints: NDArray[np.float64] | None
    joint_names: tuple[str, ...]
    rotation: NDArray[np.float64] | None
    pose_topic: str
    frame_id: str
    clock_offset_s: dict[str, float]
    stamps: str
    notes: list[LogFormatError] = field(default_factory=list)
    topics: dict[str, tuple[str, int]] = field(default_factory=dict)


def _stamp(msg) -> float | None:
    header = getattr(msg, "header", None)
    if header is None:
        return None
    return float(header.stamp.sec) + 1e-9 * float(header.stamp.nanosec)


def _frame(name: str) -> str:
    return name.strip().lstrip("/")


class _FramePair(tuple):
    """Two frame names, written ``base,sensor`` as ``--tf`` takes them (a tuple in Python)."""

    def __str__(self) -> str:
        return ",".join(self)


def _refuse_without_joints(path: Path, r: "_Reader", topics: dict, sensor: str, n_messages: int = 200) -> None:
    """A bag with /tf but no joint states: refused with ``tf`` proposed, its frames read from the bag (the first
    ``n_messages`` of /tf and /tf_static, the sensor's frame from its first message)."""
    wanted = [c for c in r.reader.connections if c.topic in ("/tf", "/tf_static", sensor)]
    edges: set[tuple[str, str]] = set()
    sensor_frame, seen = "", 0
    with r.failures():
        for conn, _, data in r.reader.messages(connections=wanted):
            msg = r.reader.deserialize(data, conn.msgtype)
            if conn.topic == sensor:
                header = getattr(msg, "header", None)
                sensor_frame = sensor_frame or (_frame(header.frame_id) if header is not None else "")
            else:
                edges |= {(_frame(tr.header.frame_id), _frame(tr.child_frame_id)) for tr in msg.transforms}
                seen += 1
            if seen >= n_messages and sensor_frame:
                break
    parents, children = {p for p, _ in edges}, {c for _, c in edges}
    frames = sorted(parents | children)
    base = (sorted(parents - children) or frames or ["BASE"])[0]  # a root of the tree, else any frame
    sensor_guess = sensor_frame if sensor_frame in children else (sorted(children - parents) or ["SENSOR"])[-1]
    proposal = _FramePair((base, sensor_guess)) if base != sensor_guess else Placeholder("BASE,SENSOR")
    raise LogFormatError(
        f"{path}: no topics of type {JOINT_STATE_TYPE} (joint states) for the sensor's pose, but /tf holds the "
        f"frames {', '.join(frames) or 'none'}; the bag has {_listing(topics)}.", parameter="tf", value=None,
        fix="take the sensor's orientation from /tf with {tf} (base frame, sensor frame)",
        settings={"tf": proposal})


def _check_wrench_frame(path: Path, sensor: str, first: str | None, frame_id: str, t: float) -> str:
    """The frame of the wrench messages so far, after one more message's ``frame_id`` (stamped at ``t`` [s]):
    called on every change of frame. Refused: wrenches that change frame within the recording (a driver switched
    from ``ft_sensor`` to ``tool0`` half way: one frame's orientation or kinematics would be applied to wrenches of
    another)."""
    own = _frame(frame_id)
    if first is not None and _frame(first) != own:
        raise LogFormatError(
            f"{path}: the wrenches of {sensor} change frame at {t:.3f} s, from {_frame(first)!r} to {own!r} (their "
            "header.frame_id); a recording's wrenches are in one frame, and those after the change would be read "
            "in the wrong one. Cut the bag at the change (ros2 bag convert / rosbag filter) and read each part "
            "with its own frame.")
    return frame_id


def _check_tf_frame(path: Path, sensor: str, frame_id: str, tf: tuple[str, str], tree: "_TfTree") -> None:
    """Refuse wrenches stamped in another frame than the sensor frame ``tf`` names (a flange turned 180 deg from
    the sensor, a driver's ``tool0_controller``): one frame's orientation applied to another frame's wrenches.
    The fix proposes the wrenches' own frame only where /tf holds a chain to it from a frame other than itself."""
    own, base = _frame(frame_id), _frame(tf[0])
    if not own or own == _frame(tf[1]):
        return
    said = (f"{path}: the wrenches of {sensor} are expressed in frame {own!r} (their header.frame_id), not in "
            f"{_frame(tf[1])!r}, the sensor frame named for /tf; the orientation of {_frame(tf[1])!r} would be "
            "applied to wrenches of another frame.")
    try:
        tree.chain(path, base, own)
        works = base != own
    except LogFormatError:
        works = False
    if works:
        raise LogFormatError(said, parameter="tf", value=tuple(tf), fix="name the wrenches' own frame: {tf}",
                             settings={"tf": _FramePair((base, own))})
    frames = sorted(set(tree.parents) | {p for ps in tree.parents.values() for p in ps})
    raise LogFormatError(said + f" /tf holds no chain to {own!r} from another frame (its frames: "
                         f"{', '.join(frames) or 'none'}); the wrenches' frame is not in the recorded tree.")


def _raw_value(path: Path, sensor: str, msgtype: str, msg, raw_field: str, width: int | None,
               t: float) -> tuple[NDArray[np.float64], int]:
    """A raw-gauge message's values and the channel count (refused: no such field, not numbers, fewer than 3
    values, a count that changes)."""
    try:
        value = np.asarray(functools.reduce(getattr, raw_field.split("."), msg), dtype=float).ravel()
    except AttributeError:
        fields = [f for f in getattr(msg, "__dataclass_fields__", {}) if not f.startswith("__")]
        raise LogFormatError(f"{path}: topic {sensor} ({msgtype}) has no field {raw_field!r}; its fields are "
                             f"{', '.join(fields)}.", parameter="raw_field", value=raw_field,
                             fix="name the array field with {raw_field}",
                             settings={"raw_field": Placeholder("NAME")}) from None
    except (TypeError, ValueError):
        raise LogFormatError(f"{path}: field {raw_field!r} of topic {sensor} ({msgtype}) is not an array of numbers "
                             "(the raw gauges).") from None
    if width is None:
        if len(value) < 3:
            raise LogFormatError(f"{path}: field {raw_field!r} of topic {sensor} holds {len(value)} values; raw "
                                 "gauges are at least 3 channels.")
    elif len(value) != width:
        raise LogFormatError(f"{path}: topic {sensor} changes from {width} to {len(value)} raw values at {t:.9g} s; "
                             "one sensor has a fixed channel count.")
    return value, len(value)


def _add_joint_state(path: Path, topic: str, count: int, max_samples: int, groups: dict, msg, t: float,
                     receive: float) -> None:
    """Add a joint-state message to the group of the joints it names (its own names, message by message: a
    gripper's messages on the arm's topic form their own group). A message naming another count of joints than
    it has positions is skipped."""
    names = tuple(msg.name)
    position = np.asarray(msg.position, dtype=float)
    if names and len(names) != len(position):
        return
    names = names or tuple(f"joint{i + 1}" for i in range(len(position)))
    if names not in groups:
        if len(groups) >= _MAX_JOINT_GROUPS:
            raise LogFormatError(f"{path}: topic {topic} names more than {_MAX_JOINT_GROUPS} different sets of joints "
                                 f"(at {t:.3f} s); give the arm's joint-state topic.", parameter="joint_topic",
                                 value=topic, fix="name it with {joint_topic}",
                                 settings={"joint_topic": Placeholder("TOPIC")})
        groups[names] = _Stream(count, max_samples, average=False)
        groups[names]._rows = min(groups[names]._rows, 1024)  # grows as messages come (most groups are small)
    groups[names].add(t, receive, position)


def _joint_group(topic: str, groups: dict, notes: list) -> tuple[tuple[str, ...], NDArray, NDArray]:
    """The arm's joint states among the groups of a joint-state topic: the group naming the most joints (the most
    messages on a tie), its names, times (sorted, distinct) and positions; the other groups are noted."""
    names = max(groups, key=lambda g: (len(g), groups[g].n_messages))
    others = [g for g in groups if g != names]
    if others:
        skipped = sum(groups[g].n_messages for g in others)
        notes.append(LogFormatError(f"{topic}: {skipped} messages naming other joints ("
                                    f"{'; '.join(', '.join(g) for g in others[:3])}) were set aside; the arm's are "
                                    f"the {groups[names].n_messages} naming {', '.join(names)}"))
    return (names, *_distinct_times(groups[names]))


def _clock_offset(stream: "_Stream") -> float:
    """The median of (receive time - header stamp) [s] over a stream's kept samples: its clock's offset."""
    times, receive, _ = stream.arrays()
    return float(np.median(receive - times))


def _distinct_times(stream: "_Stream") -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """A pose stream's times, sorted (stable), each kept once (its first sample), and its values at them."""
    times, _, values = stream.arrays()
    order = np.argsort(times, kind="stable")
    times, values = times[order], values[order]
    keep = np.concatenate([[True], np.diff(times) > 0])
    return times[keep], values[keep]


def _check_quaternion(path: Path, topic: str, t: float, edge: tuple[str, str], quat: NDArray[np.float64]) -> str:
    """'' for a quaternion that is a rotation, else the sentence saying why not (naming the bag, topic, edge, time)."""
    norm = float(np.sqrt(np.sum(quat * quat))) if np.isfinite(quat).all() else float("nan")
    if np.isfinite(norm) and norm > _MIN_QUATERNION_NORM:
        return ""
    what = "is not finite" if not np.isfinite(norm) else "has zero length"
    return (f"{path}: topic {topic} at {t:.3f} s: the transform {edge[0]} -> {edge[1]} has the quaternion "
            f"(x, y, z, w) = ({', '.join(f'{c:.6g}' for c in quat)}), which {what}; a rotation's quaternion has "
            "length 1. Fix the publisher of that transform, or record again.")


@dataclass
class _TfTree:
    """What /tf and /tf_static say, gathered while streaming: each child's parents (with where each was first
    seen), the dynamic edges' samples, the static edges, and each edge's first invalid quaternion."""

    max_samples: int
    parents: dict[str, dict[str, str]] = field(default_factory=dict)
    edges: dict[tuple[str, str], _Stream] = field(default_factory=dict)
    static: dict[tuple[str, str], NDArray[np.float64]] = field(default_factory=dict)
    invalid: dict[tuple[str, str], str] = field(default_factory=dict)

    def add(self, path: Path, topic: str, tr, t: float) -> None:
        key = (_frame(tr.header.frame_id), _frame(tr.child_frame_id))
        known = self.parents.setdefault(key[1], {})
        if key[0] not in known and len(known) < 8:
            known[key[0]] = f"{topic} at {t:.3f} s"
        q = tr.transform.rotation
        quat = np.array([q.x, q.y, q.z, q.w], dtype=float)
        bad = _check_quaternion(path, topic, t, key, quat)
        if bad:
            self.invalid.setdefault(key, bad)
        elif topic == "/tf_static":
            self.static[key] = quat
        else:  # every k-th message of *this* edge: evenly spaced whoever shares /tf
            self.edges.setdefault(key, _Stream(0, self.max_samples, average=False)).add(t, t, quat)

    def chain(self, path: Path, base: str, sensor: str) -> list[tuple[str, str]]:
        """The edges from ``base`` down to ``sensor`` (base first). Refused: no chain, a frame of the chain with two
        parents (which one holds is not for ftcal to guess), an edge of the chain with an invalid quaternion."""
        chain, frame = [], sensor
        while frame != base:
            if frame not in self.parents or len(chain) > 64:
                known = sorted(set(self.parents) | {p for ps in self.parents.values() for p in ps})
                raise LogFormatError(f"{path}: /tf holds no chain of transforms from {base} to {sensor} (stuck at "
                                     f"{frame}); the frames in /tf and /tf_static are {', '.join(known) or 'none'}.",
                                     parameter="tf", value=(base, sensor), fix="give {tf} two of them",
                                     settings={"tf": Placeholder("BASE,SENSOR")})
            options = self.parents[frame]
            if len(options) > 1:
                said = "; ".join(f"{p} ({where})" for p, where in sorted(options.items()))
                raise LogFormatError(f"{path}: /tf gives frame {frame} more than one parent: {said}; a tf tree has "
                                     f"one parent per frame, so the orientation of {sensor} is ambiguous. Record the "
                                     "bag with one publisher of that transform.")
            parent = next(iter(options))
            chain.append((parent, frame))
            frame = parent
        for edge in chain:
            if edge in self.invalid:
                raise LogFormatError(self.invalid[edge])
        return chain[::-1]

    def span(self, chain: list[tuple[str, str]]) -> tuple[float, float, str] | None:
        """The time span every dynamic edge of ``chain`` covers (the latest start, the earliest end) and the edge that
        limits it, or None for a chain of static transforms only."""
        spans = []
        for edge in chain:
            if edge in self.static:
                continue
            times = self.edges[edge].arrays()[0]
            spans.append((float(times.min()), float(times.max()), f"{edge[0]} -> {edge[1]}"))
        if not spans:
            return None
        start = max(spans, key=lambda s: s[0])
        end = min(spans, key=lambda s: s[1])
        which = end[2] if end[2] == start[2] else f"{start[2]} from {start[0]:.3f} s, {end[2]} until {end[1]:.3f} s"
        return start[0], end[1], which

    def rotations(self, chain: list[tuple[str, str]], t: NDArray[np.float64]) -> NDArray[np.float64]:
        """The rotation base <- sensor at the times ``t`` (within :meth:`span`) through ``chain``."""
        from scipy.spatial.transform import Rotation, Slerp

        R = np.broadcast_to(np.eye(3), (len(t), 3, 3)).copy()
        for edge in chain:  # base -> ... -> sensor
            times, quats = ((), self.static[edge][None]) if edge in self.static else _distinct_times(self.edges[edge])
            if len(quats) == 1:  # a static transform, or a dynamic one recorded once
                Re = np.broadcast_to(Rotation.from_quat(quats[0]).as_matrix(), (len(t), 3, 3))
            else:
                Re = Slerp(times, Rotation.from_quat(quats))(np.clip(t, times[0], times[-1])).as_matrix()
            R = R @ Re
        return R


def read_bag(path: str | Path, *, wrench_topic: str | None = None, raw_topic: str | None = None,
             raw_field: str = "data", joint_topic: str | None = None, tf: tuple[str, str] | None = None,
             stamps: str = "header", max_samples: int = DEFAULT_MAX_SAMPLES) -> BagRecording:
    """Read the sensor stream of a bag and the pose at each sensor stamp (see the module docstring).

    Parameters
    ----------
    path : str or path
        A ROS 1 ``.bag``, or a rosbag2 folder (sqlite3 or MCAP storage).
    wrench_topic : str, optional
        The sensor's wrench topic; default the bag's only ``WrenchStamped`` / ``Wrench`` topic (unless
        ``raw_topic`` is given).
    raw_topic : str, optional
        A topic of raw gauge readings instead of a wrench.
    raw_field : str, default="data"
        The array field of the raw topic's messages (dotted for a nested field).
    joint_topic : str, optional
        The joint states; default the bag's only ``JointState`` topic (unless ``tf`` is given).
    tf : (str, str), optional
        ``(base_frame, sensor_frame)``: take the sensor's orientation from ``/tf`` and ``/tf_static`` instead
        of joints. Wrench messages stamped in another frame (their ``header.frame_id``) are refused, naming it.
    stamps : {"header", "receive"}
        Which time each message carries (see the module docstring).
    max_samples : int
        Most samples kept per topic (memory stays bounded; longer topics are reduced on the fly).

    Returns
    -------
    BagRecording

    Raises
    ------
    LogFormatError
        Not a bag, truncated or damaged; a missing topic or one of the wrong type (the bag's topics are listed);
        a raw field that is not a numeric array; wrenches in another frame than ``tf``'s sensor frame; clocks that do not overlap; no sensor sample within the pose
        stream.

    Examples
    --------
    >>> import tempfile, pathlib, numpy as np
    >>> bag = pathlib.Path(tempfile.mkdtemp()) / "rec"
    >>> t = np.arange(0.0, 1.0, 0.01)
    >>> _ = write_bag(bag, "sqlite3", sensor_time=t, reading=np.ones((100, 6)), pose_time=t[::2],
    ...               joints=np.c_[t[::2], -t[::2]], joint_names=["j1", "j2"])
    >>> rec = read_bag(bag)
    >>> rec.kind, rec.reading.shape, rec.joint_names, round(float(rec.joints[51, 0]), 6)
    ('wrench', (99, 6), ('j1', 'j2'), 0.51)
    """
    path = Path(path)
    if stamps not in ("header", "receive"):
        raise LogFormatError(f"stamps must be 'header' or 'receive'; got {stamps!r}.")
    if int(max_samples) != max_samples or max_samples < 10:
        raise LogFormatError(f"max_samples must be an integer >= 10; got {max_samples!r}.")
    if wrench_topic is not None and raw_topic is not None:
        raise LogFormatError("give the wrench topic or the raw-gauge topic, not both.")
    with _Reader(path) as r:
        topics = r.topics()
        sensor, kind, pose_topics = _pick_topics(path, r, topics, wrench_topic, raw_topic, joint_topic, tf)
        m = _read_messages(path, r, topics, sensor, kind, pose_topics, tf=tf, raw_field=raw_field, stamps=stamps,
                           max_samples=max_samples)
    notes: list = []
    t_s, reading = _sensor_samples(path, topics, sensor, m.streams[sensor], max_samples, notes)
    offsets = {}  # per stamped topic, the median of (receive time - header stamp) over its kept samples
    if stamps == "header" and sensor in m.stamped:  # (the pose topic's: _joint_poses)
        offsets[sensor] = _clock_offset(m.streams[sensor])
    pose = _joint_poses(path, pose_topics[0], m, stamps, offsets, notes) if tf is None else \
        _tf_poses(path, sensor, m, tf, t_s)
    t_s, reading = _common_time(path, sensor, pose, t_s, reading, stamps, offsets, notes)
    joints = np.column_stack([np.interp(t_s, pose.t, q) for q in pose.q.T]) if tf is None else None
    rotation = m.tree.rotations(pose.chain, t_s) if tf is not None else None
    return BagRecording(path=path, sensor_topic=sensor, kind=kind, time=t_s, reading=reading, joints=joints,
                        joint_names=pose.names, rotation=rotation, pose_topic=pose.topic, frame_id=m.frame_id or "",
                        clock_offset_s=offsets, stamps=stamps, notes=notes, topics=topics)


def _pick_topics(path: Path, r: _Reader, topics: dict, wrench_topic: str | None, raw_topic: str | None,
                 joint_topic: str | None, tf: tuple[str, str] | None) -> tuple[str, str, list[str]]:
    """The sensor's topic, its kind (``"wrench"`` or ``"raw"``) and the pose topics :func:`read_bag` reads."""
    kind = "wrench" if raw_topic is None else "raw"
    sensor = _choose_topic(path, topics, wrench_topic, WRENCH_TYPES, "the sensor's wrench", "wrench_topic") \
        if raw_topic is None else _choose_topic(path, topics, raw_topic, (), "raw gauges", "raw_topic")
    if tf is None:
        if joint_topic is None and not any(typ == JOINT_STATE_TYPE for typ, _ in topics.values()) and \
                any(topics.get(t, ("", 0))[0] == TF_TYPE for t in ("/tf", "/tf_static")):
            _refuse_without_joints(path, r, topics, sensor)
        return sensor, kind, [_choose_topic(path, topics, joint_topic, (JOINT_STATE_TYPE,), "joint states",
                                            "joint_topic")]
    pose_topics = [t for t in ("/tf", "/tf_static") if t in topics]
    if not pose_topics:
        raise LogFormatError(f"{path}: no topic /tf or /tf_static ({{tf}} {','.join(tf)}); the bag has "
                             f"{_listing(topics)}.", parameter="tf", value=tf)
    for t in pose_topics:
        if topics[t][0] != TF_TYPE:
            raise LogFormatError(f"{path}: topic {t} holds {topics[t][0]}, not {TF_TYPE}.")
    return sensor, kind, pose_topics


@dataclass
class _Messages:
    """What :func:`_read_messages` kept of a bag: the sensor's stream, the joint states by the joints each message
    names, the transforms, the topics with header stamps and the wrench's frame."""

    streams: dict
    joint_groups: dict
    tree: "_TfTree"
    stamped: set = field(default_factory=set)
    frame_id: str | None = None


def _read_messages(path: Path, r: _Reader, topics: dict, sensor: str, kind: str, pose_topics: list[str], *,
                   tf: tuple[str, str] | None, raw_field: str, stamps: str, max_samples: int) -> _Messages:
    """One pass over the bag's sensor and pose messages, each reduced on the fly (memory stays bounded)."""
    m = _Messages(streams={sensor: _Stream(topics[sensor][1], max_samples, average=True)}, joint_groups={},
                  tree=_TfTree(max_samples))
    width = None
    wanted = [c for c in r.reader.connections if c.topic in {sensor, *pose_topics}]
    with r.failures():
        for conn, receive_ns, data in r.reader.messages(connections=wanted):
            topic = conn.topic
            msg = r.reader.deserialize(data, conn.msgtype)
            receive = receive_ns * 1e-9
            if topic in ("/tf", "/tf_static") and tf is not None:
                for tr in msg.transforms:
                    m.tree.add(path, topic, tr, _stamp(tr) if stamps == "header" else receive)
                continue
            header = _stamp(msg)
            if header is not None:
                m.stamped.add(topic)
            t = header if (stamps == "header" and header is not None) else receive
            if topic == sensor:
                if kind == "wrench":
                    w = getattr(msg, "wrench", msg)
                    value = np.array([w.force.x, w.force.y, w.force.z, w.torque.x, w.torque.y, w.torque.z])
                    if header is not None and msg.header.frame_id != m.frame_id:
                        m.frame_id = _check_wrench_frame(path, sensor, m.frame_id, str(msg.header.frame_id), t)
                else:
                    value, width = _raw_value(path, sensor, conn.msgtype, msg, raw_field, width, t)
                m.streams[sensor].add(t, receive, value)
            else:  # joint states: grouped by the joints each message names (an arm's, a gripper's)
                _add_joint_state(path, topic, topics[topic][1], max_samples, m.joint_groups, msg, t, receive)
    return m


def _sensor_samples(path: Path, topics: dict, sensor: str, stream: _Stream, max_samples: int,
                    notes: list) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """The sensor's kept samples in time order (times [s], readings), refused when empty or not finite."""
    t_s, _, reading = stream.arrays()
    if stream.block > 1:
        notes.append(LogFormatError(f"{sensor}: {stream.n_messages} messages averaged in blocks of "
                                    f"{stream.block} (at most {max_samples} samples kept)"))
    if not len(t_s):
        raise LogFormatError(f"{path}: topic {sensor} holds no messages; the bag has {_listing(topics)}.")
    if not np.isfinite(reading).all():
        i = int(np.flatnonzero(~np.isfinite(reading).all(axis=1))[0])
        raise LogFormatError(f"{path}: topic {sensor} has a NaN or inf value at {t_s[i]:.9g} s.")
    order = np.argsort(t_s, kind="stable")
    return t_s[order], reading[order]


@dataclass
class _PoseStream:
    """Where the sensor's orientation comes from: the pose topic, the time span it covers [s] (and its words),
    the joint names, times and angles (joint states) or the /tf chain."""

    topic: str
    span: tuple[float, float]
    span_words: str
    names: tuple = ()
    t: NDArray[np.float64] | None = None
    q: NDArray[np.float64] | None = None
    chain: list = field(default_factory=list)


def _joint_poses(path: Path, pose_topic: str, m: _Messages, stamps: str, offsets: dict, notes: list) -> _PoseStream:
    """The joint states of ``pose_topic`` (one group of joints), with its clock offset added to ``offsets``."""
    if not m.joint_groups:
        raise LogFormatError(f"{path}: topic {pose_topic} holds no joint states.")
    names, t_p, q = _joint_group(pose_topic, m.joint_groups, notes)
    if pose_topic in m.stamped and stamps == "header":
        offsets[pose_topic] = _clock_offset(m.joint_groups[names])
    span = (float(t_p.min()), float(t_p.max()))
    return _PoseStream(pose_topic, span, f"{pose_topic} {span[0]:.6f} to {span[1]:.6f} s", names, t_p, q)


def _tf_poses(path: Path, sensor: str, m: _Messages, tf: tuple[str, str], t_s: NDArray[np.float64]) -> _PoseStream:
    """The /tf chain from ``tf``'s base to its sensor frame and the time span all its transforms cover."""
    if not m.tree.edges and not m.tree.static:
        raise LogFormatError(f"{path}: /tf holds no transforms.")
    _check_tf_frame(path, sensor, m.frame_id or "", tf, m.tree)
    base, tip = _frame(tf[0]), _frame(tf[1])
    chain = m.tree.chain(path, base, tip)
    covered = m.tree.span(chain)
    span = (float(t_s[0]), float(t_s[-1])) if covered is None else covered[:2]
    span_words = (f"the /tf chain {base} to {tip} {span[0]:.6f} to {span[1]:.6f} s (limited "
                  f"by {covered[2]})") if covered is not None else ""
    if covered is not None and span[0] > span[1]:
        raise LogFormatError(f"{path}: the transforms of the /tf chain {base} to {tip} are "
                             f"never recorded at one time together ({covered[2]}); the sensor's orientation is "
                             "known at no time.")
    return _PoseStream("/tf", span, span_words, chain=chain)


def _common_time(path: Path, sensor: str, pose: _PoseStream, t_s: NDArray[np.float64], reading: NDArray[np.float64],
                 stamps: str, offsets: dict, notes: list) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """The sensor samples within the pose stream's span: a clock offset between the two noted, no overlap refused
    (with the fix the stamps allow), samples outside dropped and noted."""
    sensor_pose = sensor in offsets and pose.topic in offsets
    if stamps == "header" and sensor_pose:
        apart = offsets[sensor] - offsets[pose.topic]
        if abs(apart) > CLOCK_OFFSET_TOLERANCE_S:
            notes.append(LogFormatError(
                f"clock offset between {sensor} and {pose.topic}: their header stamps differ by {apart:+.3g} s "
                f"against the recorder's receive times ({sensor}'s clock {'behind' if apart > 0 else 'ahead'})",
                parameter="stamps", value=stamps, settings={"stamps": "receive"},
                fix="if that is the clocks, not transport latency, read the bag with {stamps}"))
    overlap = (t_s >= pose.span[0]) & (t_s <= pose.span[1])
    if not overlap.any():
        detail = (f"; against the recorder's receive times their clocks are "
                  f"{offsets[sensor] - offsets[pose.topic]:+.6g} s apart") if sensor_pose else ""
        said = f"{path}: clocks apart: {sensor} is stamped {t_s[0]:.6f} to {t_s[-1]:.6f} s but {pose.span_words}, " \
               f"no overlap{detail}."
        if stamps == "header":
            raise LogFormatError(said, parameter="stamps", value=stamps, settings={"stamps": "receive"},
                                 fix="{stamps} (the recorder's clock for both), or set the sensor driver's clock")
        raise LogFormatError(said.replace("clocks apart", "no common time").replace("is stamped", "is received") +
                             " Even on the recorder's receive times they were not recorded together: record the "
                             "sensor and the pose in one bag run.")
    if not overlap.all():
        notes.append(LogFormatError(f"{int((~overlap).sum())} of {len(t_s)} {sensor} samples lie outside "
                                    f"{pose.span_words or pose.topic + chr(39) + 's span'} and were dropped"))
        t_s, reading = t_s[overlap], reading[overlap]
    return t_s, reading

def write_bag(path: str | Path, storage: str, *, sensor_time: ArrayLike, reading: ArrayLike, pose_time: ArrayLike,
              joints: ArrayLike | None = None, joint_names: tuple[str, ...] | list[str] = (),
              rotations: ArrayLike | None = None, tf_frames: tuple[str, str] = ("base_link", "ft_sensor"),
              raw: bool = False, sensor_topic: str | None = None, joint_topic: str = "/joint_states",
              frame_id: str = "ft_sensor", sensor_clock_offset_s: float = 0.0, latency_s: float = 0.001,
              ros1_chunk_bytes: int | None = None) -> Path:
    """Write a recording as a ROS bag, as a robot would record it (for tests, examples and the README).

    Parameters
    ----------
    path : str or path
        The bag to create (a rosbag2 folder, or a ``.bag`` file for ``storage="ros1"``); must not exist.
    storage : {"sqlite3", "mcap", "ros1"}
    sensor_time, reading : array-like of shape (n,), (n, m)
        The sensor's stamps [s] and readings: a wrench (``geometry_msgs/WrenchStamped``) or, with ``raw``,
        raw gauges (``std_msgs/Float64MultiArray``, field ``data``).
    pose_time : array-like of shape (k,)
    joints : array-like of shape (k, n_joints), optional
        Joint states (``sensor_msgs/JointState`` on ``joint_topic``) with ``joint_names``.
    rotations : array-like of shape (k, 3, 3), optional
        The sensor's orientation, written to ``/tf`` as ``tf_frames`` = (base, sensor) through an intermediate
        ``flange`` frame whose static transform is in ``/tf_static``.
    sensor_topic : str, optional
        Default ``/ft_sensor/wrench`` (``/ft_sensor/raw`` with ``raw``).
    sensor_clock_offset_s : float
        The sensor's header stamps run this far ahead of the recorder's clock (a driver stamping with its own
        clock).
    latency_s : float
        Each message is received this long after its stamp.
    ros1_chunk_bytes : int, optional
        Size of a ROS 1 bag's chunks (default rosbags' 1 MiB).

    Returns
    -------
    pathlib.Path
    """
    check_rosbags()
    if storage not in BAG_STORAGES:
        raise LogFormatError(f"storage must be one of {', '.join(BAG_STORAGES)}; got {storage!r}.")
    path = Path(path)
    if path.exists():
        raise LogFormatError(f"{path} exists; a bag is never overwritten. Choose another path.")
    t_s = np.asarray(sensor_time, dtype=float)
    values = np.asarray(reading, dtype=float)
    t_p = np.asarray(pose_time, dtype=float)
    sensor_topic = sensor_topic or ("/ft_sensor/raw" if raw else "/ft_sensor/wrench")
    out = _Serializer(storage == "ros1")
    T = out.store.types
    if raw:
        Multi, Layout = T["std_msgs/msg/Float64MultiArray"], T["std_msgs/msg/MultiArrayLayout"]
        template = Multi(layout=Layout(dim=[], data_offset=0), data=_SENTINELS[:values.shape[1]].copy())
        out.add(sensor_topic, template, t_s, values, latency_s)
    else:
        Wrench, Vector3, Stamped = T["geometry_msgs/msg/Wrench"], T["geometry_msgs/msg/Vector3"], \
            T["geometry_msgs/msg/WrenchStamped"]
        v = _SENTINELS
        template = Stamped(header=out.header(frame_id), wrench=Wrench(force=Vector3(x=v[0], y=v[1], z=v[2]),
                                                                           torque=Vector3(x=v[3], y=v[4], z=v[5])))
        out.add(sensor_topic, template, t_s, values, latency_s, stamped=True, offset_s=sensor_clock_offset_s)
    if joints is not None:
        q = np.asarray(joints, dtype=float)
        empty = np.zeros(0)
        template = T["sensor_msgs/msg/JointState"](header=out.header(""), name=list(joint_names),
                                                   position=_SENTINELS[:q.shape[1]].copy(), velocity=empty,
                                                   effort=empty)
        out.add(joint_topic, template, t_p, q, latency_s, stamped=True)
    if rotations is not None:
        _add_tf(out, np.asarray(rotations, dtype=float), t_p, tf_frames, latency_s)
    out.write(path, storage, ros1_chunk_bytes)
    return path


class _Serializer:
    """The messages :func:`write_bag` writes, serialized for ROS 1 or ROS 2: each stream's template (sentinel
    numbers and stamp) serialized once, then the stamps and values written into copies of its bytes (the layout is
    fixed: same names, same counts)."""

    def __init__(self, ros1: bool) -> None:
        from rosbags.typesys import Stores, get_types_from_msg, get_typestore

        self.ros1 = ros1
        self.store = get_typestore(Stores.ROS1_NOETIC if ros1 else Stores.ROS2_HUMBLE)
        if TF_TYPE not in self.store.types:  # rosbags' ROS 1 store lacks it
            self.store.register(get_types_from_msg("geometry_msgs/TransformStamped[] transforms", TF_TYPE))
        self.serialize = self.store.serialize_ros1 if ros1 else self.store.serialize_cdr
        self.streams: list = []  # (topic, type, receive times, serialized rows)

    def header(self, frame: str):
        """A header in ``frame`` with the sentinel stamp (each message's stamp is written in by :meth:`add`)."""
        Header, Time = self.store.types["std_msgs/msg/Header"], self.store.types["builtin_interfaces/msg/Time"]
        return Header(stamp=Time(sec=_STAMP_SEC, nanosec=_STAMP_NSEC), frame_id=frame,
                      **({"seq": 0} if self.ros1 else {}))

    def add(self, topic: str, template, times: NDArray, values: NDArray, latency_s: float, stamped: bool = False,
            offset_s: float = 0.0) -> None:
        """The stream of ``template``'s messages with ``values`` (one row a message) at ``times`` [s], received
        ``latency_s`` later, their header stamps ``offset_s`` ahead."""
        typ = template.__msgtype__
        data = np.frombuffer(bytes(self.serialize(template, typ)), dtype=np.uint8)
        width = values.shape[1]
        at = bytes(data).find(_SENTINELS[:width].astype("<f8").tobytes())
        out = np.tile(data, (len(times), 1))
        out[:, at:at + 8 * width] = np.ascontiguousarray(values, dtype="<f8").view(np.uint8).reshape(len(times), -1)
        if stamped:
            st = bytes(data).find(_STAMP_SENTINEL)
            stamp = times + offset_s
            sec = np.floor(stamp)
            both = np.empty(len(times), dtype=[("sec", "<i4"), ("nsec", "<u4")])
            both["sec"], both["nsec"] = sec, np.clip(np.round((stamp - sec) * 1e9), 0, 999_999_999)
            out[:, st:st + 8] = both.view(np.uint8).reshape(len(times), 8)
        self.streams.append((topic, typ, times + latency_s, out))

    def write(self, path: Path, storage: str, ros1_chunk_bytes: int | None) -> None:
        """Every message in the order of receipt into a new bag at ``path``."""
        if self.ros1:
            from rosbags.rosbag1 import Writer as Writer1

            writer = Writer1(path)
            if ros1_chunk_bytes is not None:
                writer.chunk_threshold = int(ros1_chunk_bytes)
        else:
            from rosbags.rosbag2 import StoragePlugin, Writer as Writer2

            writer = Writer2(path, version=9, storage_plugin=StoragePlugin.MCAP if storage == "mcap"
                             else StoragePlugin.SQLITE3)
        streams = self.streams
        receive = np.concatenate([r for _, _, r, _ in streams])
        which = np.concatenate([np.full(len(r), k) for k, (_, _, r, _) in enumerate(streams)])
        row = np.concatenate([np.arange(len(r)) for _, _, r, _ in streams])
        order = np.argsort(receive, kind="stable")
        with writer:
            connections = [writer.add_connection(topic, typ, typestore=self.store)
                           for topic, typ, _, _ in streams]
            ns = np.round(receive * 1e9).astype(np.int64)
            for i in order:
                k = int(which[i])
                writer.write(connections[k], int(ns[i]), streams[k][3][row[i]].tobytes())


def _add_tf(out: _Serializer, rotations: NDArray, t_p: NDArray, tf_frames: tuple[str, str], latency_s: float) -> None:
    """The sensor's orientation on ``/tf`` (base to an intermediate ``flange`` frame) and a static transform from
    the flange to the sensor frame on ``/tf_static``."""
    from scipy.spatial.transform import Rotation

    T = out.store.types
    TF, TS, Tr = T[TF_TYPE], T["geometry_msgs/msg/TransformStamped"], T["geometry_msgs/msg/Transform"]
    Q, V = T["geometry_msgs/msg/Quaternion"], T["geometry_msgs/msg/Vector3"]
    flange_to_sensor = Rotation.from_euler("z", 90, degrees=True)  # a fixed adapter in /tf_static
    base, sensor_frame = tf_frames
    to_flange = Rotation.from_matrix(rotations) * flange_to_sensor.inv()

    def transform(head, child: str, quat) -> object:
        x, y, z, w = (float(c) for c in quat)
        return TS(header=head, child_frame_id=child,
                  transform=Tr(translation=V(x=0.0, y=0.0, z=0.0), rotation=Q(x=x, y=y, z=z, w=w)))

    template = TF(transforms=[transform(out.header(base), "flange", _SENTINELS[:4])])
    out.add("/tf", template, t_p, to_flange.as_quat(), latency_s, stamped=True)
    static = TF(transforms=[transform(out.header("flange"), sensor_frame, _SENTINELS[:4])])
    out.add("/tf_static", static, t_p[:1], flange_to_sensor.as_quat()[None], latency_s, stamped=True)
