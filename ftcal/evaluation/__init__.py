"""Benchmarks and reports: the artificial (Tables II-III) and real-world (Tables IV-V) benchmarks,
the plots, and the demo.

May import every ftcal package except :mod:`ftcal.cli`.
"""
