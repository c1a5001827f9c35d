"""The robot's own recordings on the command line: ROS bags and continuous pose files, their still poses.

``identify-load`` and ``prepare`` read them alike: the options name the topics (``--wrench-topic``,
``--raw-topic`` with ``--raw-field``, ``--joint-topic``, or ``--tf BASE,SENSOR``), the stamps
(``--stamps``) and the still-pose thresholds (``--still-tolerance``, ``--min-still``, ``--settle``).
"""

from __future__ import annotations

import argparse
import re
from pathlib import Path

from ._common import CliError, Console, finite_float, positive_float

__all__ = ["add_recording_options", "add_bag_options", "still_poses", "read_bag_from_args", "bag_joints",
           "bag_files", "bag_run_log"]


def nonnegative_float(text: str) -> float:
    """argparse type: a finite number >= 0."""
    value = finite_float(text)
    if value < 0:
        raise argparse.ArgumentTypeError(f"{text!r}: give a number >= 0")
    return value


def _frames(text: str) -> tuple[str, str]:
    parts = tuple(p.strip() for p in text.split(","))
    if len(parts) != 2 or not all(parts):
        raise argparse.ArgumentTypeError(f"{text!r}: give the base frame and the sensor frame, e.g. base_link,ft_sensor")
    return parts


def add_recording_options(g: argparse._ArgumentGroup) -> None:
    """The still-pose thresholds: ``--still-tolerance``, ``--min-still``, ``--settle``."""
    from ..experiment import DEFAULT_MIN_STILL_S, DEFAULT_STILL_TOLERANCE_DEG

    g.add_argument("--still-tolerance", type=positive_float, default=DEFAULT_STILL_TOLERANCE_DEG, metavar="DEG",
                   help="a pose is still while it stays within this [deg] (each joint, or the orientation)")
    g.add_argument("--min-still", type=positive_float, default=DEFAULT_MIN_STILL_S, metavar="S",
                   help="shortest still segment that is a pose [s]")
    g.add_argument("--settle", type=nonnegative_float, metavar="S",
                   help="seconds dropped at the start of each still pose (default: from the data, until the "
                   "drift has decayed into the noise)")


def add_bag_options(p: argparse.ArgumentParser, *, wrench: bool = True) -> None:
    """The topics and stamps of a ROS bag input."""
    from ..io import DEFAULT_MAX_SAMPLES

    g = p.add_argument_group("ROS bags (rosbag2 sqlite3 / MCAP folders, ROS 1 .bag files; pip install \"ftcal[ros]\")")
    if wrench:
        g.add_argument("--wrench-topic", metavar="TOPIC",
                       help="the sensor's geometry_msgs/WrenchStamped topic (default: the bag's only one, unless "
                       "--raw-topic)")
    g.add_argument("--raw-topic", metavar="TOPIC",
                   help="a topic of raw gauge readings (an array message, e.g. std_msgs/Float64MultiArray)"
                   + (" instead of a wrench; needs --model" if wrench else ""))
    g.add_argument("--raw-field", default="data", metavar="FIELD",
                   help="the array field of the raw topic's messages (dotted for a nested one)")
    g.add_argument("--joint-topic", metavar="TOPIC",
                   help="the sensor_msgs/JointState topic (default: the bag's only one); the joints named like "
                   "the robot's are used, in its order")
    g.add_argument("--tf", type=_frames, metavar="BASE,SENSOR",
                   help="take the sensor's orientation from /tf and /tf_static (base frame to sensor frame) "
                   "instead of the joints and the robot model")
    g.add_argument("--stamps", choices=("header", "receive"), default="header",
                   help="the messages' header stamps, or the times the recorder received them (for a sensor "
                   "driver stamping with its own clock)")
    g.add_argument("--max-samples", type=positive_int_10, default=DEFAULT_MAX_SAMPLES, metavar="N",
                   help="most samples kept per topic; longer topics are averaged in blocks on the fly, so memory "
                   "stays bounded for a bag of any size")


def refuse_bag_options(args: argparse.Namespace, inputs: str) -> None:
    """Refuse the ROS bag options (:func:`add_bag_options`) given for inputs that are not bags (``inputs`` says
    what they are): they would do nothing, without a word."""
    from ..io import DEFAULT_MAX_SAMPLES

    defaults = {"wrench_topic": None, "raw_topic": None, "raw_field": "data", "joint_topic": None, "tf": None,
                "stamps": "header", "max_samples": DEFAULT_MAX_SAMPLES}
    given = ["--" + dest.replace("_", "-") for dest, default in defaults.items()
             if hasattr(args, dest) and getattr(args, dest) != default]
    if given:
        raise CliError(f"{', '.join(given)} read{'s' if len(given) == 1 else ''} ROS bags, but the inputs are "
                       f"{inputs}; drop {'it' if len(given) == 1 else 'them'}, or give the recording's bag")


def positive_int_10(text: str) -> int:
    """argparse type: an integer >= 10."""
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r}: give an integer >= 10") from None
    if value < 10:
        raise argparse.ArgumentTypeError(f"{text!r}: give an integer >= 10")
    return value


def still_poses(args, source: str, time, reading, *, rotations=None, joints=None):
    """The still poses of a continuous recording, with the options' thresholds; errors name ``source``."""
    from ..core import CalibrationInputError
    from ..experiment import find_still_poses
    from ._messages import cli_message

    try:
        return find_still_poses(time, reading, rotations=rotations, joints=joints, tolerance_deg=args.still_tolerance,
                                settle_s=args.settle, min_duration_s=args.min_still)
    except CalibrationInputError as exc:
        raise CliError(f"{source}: {cli_message(exc, args)}") from None


def read_bag_from_args(args, path: Path, console: Console):
    """The bag at ``path`` read as the options say; its notes (clock offsets, dropped samples) on stderr."""
    from ..core import LogFormatError
    from ..io import read_bag
    from ._messages import cli_message

    try:
        rec = read_bag(path, wrench_topic=getattr(args, "wrench_topic", None), raw_topic=args.raw_topic,
                       raw_field=args.raw_field, joint_topic=args.joint_topic, tf=getattr(args, "tf", None),
                       stamps=args.stamps, max_samples=args.max_samples)
    except LogFormatError as exc:
        raise CliError(cli_message(exc, args)) from None
    for note in rec.notes:
        console.info(f"{path}: {cli_message(note, args)}")
    return rec


def bag_joints(rec, robot):
    """The bag's joint positions in the robot's joint order, matched by name.

    Joint-state publishers do not keep the URDF's order and drivers rename joints, so a bag whose joint names
    are not the robot's is refused even when the counts agree: taking its columns in order would give wrong
    forward kinematics without a word.
    """
    names = list(rec.joint_names)
    wanted = list(robot.joint_names)
    if set(wanted) <= set(names):
        return rec.joints[:, [names.index(n) for n in wanted]]
    raise CliError(f"{rec.path}: the joint states of {rec.pose_topic} name {', '.join(names)} but the robot "
                   f"{robot.name} has {', '.join(wanted)}; give the robot the bag was recorded with (--robot URDF "
                   "--sensor-frame FRAME), or the sensor's orientation from tf (--tf BASE,SENSOR)")


def bag_files(items: list[str]) -> list[Path] | None:
    """The bags among ``items`` (a bag, or a folder holding bags and no *.csv), or None when they are not bags;
    a mix of bags and other inputs is refused."""
    from ..io import is_bag

    found, other = [], []
    for item in items:
        path = Path(item)
        if is_bag(path):
            found.append(path)
        elif path.is_dir() and not any(path.glob("*.csv")) and any(is_bag(c) for c in path.iterdir()):
            found += sorted(c for c in path.iterdir() if is_bag(c))
        else:
            other.append(path)
    if found and other:
        raise CliError(f"the inputs mix ROS bags ({found[0]}) and other files ({other[0]}); give one kind")
    return found or None


_RUN_NAME = re.compile(r"config(-?\d+)_(load|no-load)")


def bag_run_log(args, path: Path, robot, console: Console):
    """A bag of one run (raw gauges + joints) as a run log of its still poses: one row per pose, in order."""
    import numpy as np

    from ..io import RunLog

    match = _RUN_NAME.search(path.name)
    if match is None:
        raise CliError(f"{path}: name each bag after its run, config<C>_load or config<C>_no-load (C the load "
                       "configuration id, -1 for a no-load run shared by all), as 'ftcal simulate experiment --bag' "
                       "writes them; the still poses of a load run and its no-load run pair in order")
    if args.raw_topic is None:
        raise CliError(f"{path}: prepare calibrates raw gauges: name their topic with --raw-topic TOPIC "
                       "(and --raw-field FIELD)")
    rec = read_bag_from_args(args, path, console)
    if rec.rotation is not None:  # --tf: the orientation recorded, no joints and no robot model needed
        still = still_poses(args, str(path), rec.time, rec.reading, rotations=rec.rotation)
        q, rotation, frame = np.empty((still.n_kept, 0)), still.rotation, None
    else:
        still = still_poses(args, str(path), rec.time, rec.reading, joints=bag_joints(rec, robot))
        q, rotation, frame = still.joints, None, robot.sensor_frame
    console.info(f"{path}: {still.summary()}")
    k = still.n_kept
    return RunLog(path=path, timestamp=still.time, run_kind=np.array([match.group(2)] * k),
                  config=np.full(k, int(match.group(1)), dtype=np.int64), pose=np.arange(k, dtype=np.int64),
                  q=q, raw=still.reading, line=np.arange(1, k + 1, dtype=np.int64),
                  raw_unit="raw", robot=robot.name, sensor_frame=frame, rotation=rotation,
                  meta={"bag": str(path), "topic": rec.sensor_topic})
