"""Virtual sensors and the artificial benchmark's data: sensor profiles (also from an ATI ``.cal``
file), the thesis' error models and presets, load sampling, and artificial datasets.

Imports :mod:`ftcal.core` and :mod:`ftcal.io`.
"""
