"""The network calibrators (torch, trained through skorch): the torch modules and loss, the thesis'
three-phase schedule, the shared network base (lean training loop, numpy inference), the directional
and comparative calibrators, and stacked training of several nets as one module.

Imports :mod:`ftcal.core` and :mod:`ftcal.calibrators` (the base class); nothing above.
"""
