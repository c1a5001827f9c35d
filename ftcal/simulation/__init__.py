"""Virtual sensors and the artificial benchmark's data: sensor profiles (also from an ATI ``.cal``
file), the thesis' error models and presets, load sampling, artificial datasets and field-like datasets
(dead weights, a robot-held sensor, a soft sensor).

Layer: above :mod:`ftcal.io`. Imports :mod:`ftcal.core` and :mod:`ftcal.io`.
"""

from ..core._lazy import lazy_namespace

#: Public names of this package -> the private module holding each.
_PUBLIC = dict(
    make_artificial_dataset="_artificial", VirtualSensor="_artificial", noise_floor="_artificial",
    ERROR_PRESETS="_presets", error_preset="_presets", ErrorModel="_error_models", SampledErrors="_error_models",
    SensorProfile="_sensor", default_calibration_matrix="_sensor", read_ati_calibration="_ati",
    make_dead_weight_dataset="_field_sensors", make_robot_held_dataset="_field_sensors",
    make_soft_sensor_dataset="_field_sensors",
)
_PUBLIC.update(  # names the CLI uses
    MAX_DATASETS="_presets", MAX_POINTS="_sampling", TEST_DISTRIBUTIONS="_sampling",
    ZERO_OFFSET_LIMIT="_artificial", zero_offset_bound="_artificial",
)
__all__ = list(_PUBLIC)
__getattr__, __dir__ = lazy_namespace(__name__, _PUBLIC)
