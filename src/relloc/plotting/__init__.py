"""Matplotlib figures; functions draw into an Axes they are given. Never imported by core code."""
