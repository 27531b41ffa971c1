"""relloc — relative and cooperative localization of heterogeneous multi-robot teams.

Nothing runs on import; see the README for the two entry commands and DESIGN notes.
"""

__version__ = "0.1.0"
