"""Library workflows: what a command of the CLI does, as one public call (``calibrate``: fit, judge on the one
fold plan, keep the fit summary, certify).

Layer: the top of the library, right below :mod:`ftcal.cli` (which calls it). May import every package of ftcal
but the CLI.
"""

from ..core._lazy import lazy_namespace

#: Public names of this package -> the private module holding each.
_PUBLIC = dict(calibrate="_calibrate", Calibration="_calibrate")
__all__ = list(_PUBLIC)
__getattr__, __dir__ = lazy_namespace(__name__, _PUBLIC)
