"""Matplotlib figures; functions draw into an Axes they are given. Never imported by core code.

:func:`relloc.plotting.setup.pyplot` is the one place that loads matplotlib (Agg backend).
"""
