"""The options that say how to read a user's calibration data: column mapping, units; and the lever-arm check.

``ftcal fit``, ``evaluate`` and ``report`` take ``--channels``, ``--wrench``, ``--force-unit`` and
``--torque-unit``; a dataset whose loads' lever arm is implausible (torques in N·mm read as N·m) is
refused with the likely unit and the option that fixes it, unless the unit was declared (an implausibly short
arm is only warned about: a 3-axis cell's torque columns may hold noise alone).
"""

from __future__ import annotations

import argparse
import sys

from ._common import CliError

__all__ = ["add_dataset_options", "load_dataset_from_args"]


def _names(text: str) -> tuple[str, ...]:
    names = tuple(n.strip() for n in text.split(","))
    if not all(names):
        raise argparse.ArgumentTypeError(f"{text!r}: give comma-separated column names, e.g. s1,s2,s3")
    return names


def add_dataset_options(p: argparse.ArgumentParser) -> None:
    """``--channels``, ``--wrench``, ``--force-unit``, ``--torque-unit``."""
    from ..io._readers import FORCE_UNITS, TORQUE_UNITS

    g = p.add_argument_group("reading the dataset (.csv, .npz, .mat)")
    g.add_argument("--channels", type=_names, metavar="NAME,...",
                   help="the raw-channel columns (or .mat/.npz variables) in channel order, e.g. s1,s2,s3,s4,s5,s6 "
                   "(default: s0,s1,... or the variable 'raw')")
    g.add_argument("--wrench", type=_names, metavar="NAME,...",
                   help="the six wrench columns in the order Fx,Fy,Fz,Tx,Ty,Tz, e.g. Fx,Fy,Fz,Mx,My,Mz "
                   "(default: Fx..Tz or Mx/My/Mz, or the variable 'wrench')")
    g.add_argument("--force-unit", metavar="UNIT",
                   help=f"unit of the file's forces, converted to N: {', '.join(FORCE_UNITS)} (default N)")
    g.add_argument("--torque-unit", metavar="UNIT",
                   help=f"unit of the file's torques, converted to N·m: {', '.join(TORQUE_UNITS)} (default N.m; "
                   "declaring it also confirms an unusual lever arm)")


def load_dataset_from_args(args: argparse.Namespace, path, role: str = "dataset"):
    """The dataset at ``path`` read as the options say, its units checked by the loads' lever arm."""
    from ..io._readers import PLAUSIBLE_LEVER_ARM_M, ColumnMap, lever_arm_m, lever_arm_problem
    from ._models import load_dataset

    columns = ColumnMap(channels=args.channels, wrench=args.wrench, force_unit=args.force_unit or "N",
                        torque_unit=args.torque_unit or "N.m")
    data = load_dataset(path, role, columns=columns)
    problem = lever_arm_problem(data.wrench, columns.torque_unit)
    if problem is not None:
        # too long an arm (torques in N·mm read as N·m) is refused unless a unit was declared; too short a one
        # (a 3-axis cell whose torque columns hold only noise) is only pointed out
        too_long = lever_arm_m(data.wrench) > PLAUSIBLE_LEVER_ARM_M[1]
        if too_long and args.torque_unit is None and args.force_unit is None:
            raise CliError(f"{path}: {problem}")
        print(f"ftcal: warning: {path}: {problem}", file=sys.stderr)
    return data
