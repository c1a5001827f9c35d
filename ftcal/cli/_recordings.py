"""The robot's own recordings on the command line: ROS bags and continuous pose files, their still poses.

``identify-load`` and ``prepare`` read them alike: the options name the topics (``--wrench-topic``,
``--raw-topic`` with ``--raw-field``, ``--joint-topic``, or ``--tf BASE,SENSOR``), the stamps
(``--stamps``) and the still-pose thresholds (``--still-tolerance``, ``--min-still``, ``--settle``).
"""

from __future__ import annotations

import argparse
from pathlib import Path

from ..io import refuse_twin_recordings
from ._common import CliError, Console, finite_float, positive_float

__all__ = ["add_recording_options", "add_bag_options", "bag_files", "bag_run_log", "refuse_bag_options",
           "recording_options", "say_notes"]


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
    from ftcal.experiment import DEFAULT_MIN_STILL_S, DEFAULT_STILL_TOLERANCE_DEG

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
        value = 0  # not an integer: refused below, in the same words
    if value < 10:
        raise argparse.ArgumentTypeError(f"{text!r}: give an integer >= 10")
    return value


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
    refuse_twin_recordings(found, "ROS bag", CliError)
    return found or None


#: The field of :class:`ftcal.experiment.RecordingOptions` each option sets (destination -> field).
_RECORDING_FIELDS = {"wrench_frame": "wrench_frame", "still_tolerance": "tolerance_deg", "min_still": "min_duration_s",
                     "settle": "settle_s", "wrench_topic": "wrench_topic", "raw_topic": "raw_topic",
                     "raw_field": "raw_field", "joint_topic": "joint_topic", "tf": "tf", "stamps": "stamps",
                     "max_samples": "max_samples"}


def recording_options(args: argparse.Namespace, **fields):
    """The library's :class:`~ftcal.experiment.RecordingOptions` from the options the command has (its units
    unset: N and N·m), ``fields`` given as they are."""
    from ftcal.experiment import RecordingOptions

    given = {field: getattr(args, dest) for dest, field in _RECORDING_FIELDS.items() if hasattr(args, dest)}
    units = {"force_unit": getattr(args, "force_unit", None) or "N",
             "torque_unit": getattr(args, "torque_unit", None) or "N.m"}
    return RecordingOptions(**given, **units, **fields)


def say_notes(console: Console, notes, args: argparse.Namespace) -> None:
    """The library's notes on a recording (``(source, note)``: a text, or a warning to say in the options' terms),
    one status line each."""
    from ._messages import cli_message

    for source, note in notes:
        console.info(f"{source}: {note if isinstance(note, str) else cli_message(note, args)}")


def bag_run_log(args, path: Path, robot, console: Console):
    """A bag of one run (raw gauges + joints, or /tf) as a run log of its still poses
    (:func:`ftcal.experiment.bag_run_log` with the options); its notes on stderr, its errors as one line."""
    from ftcal.core import FtcalError
    from ftcal.experiment import bag_run_log as read_run

    from ._messages import cli_error

    try:
        log, still, notes = read_run(path, robot, options=recording_options(args))
    except FtcalError as exc:
        raise cli_error(exc, args) from None
    say_notes(console, notes, args)
    console.info(f"{path}: {still.summary()}")
    return log
