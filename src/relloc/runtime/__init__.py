"""Robot node processes over Zenoh (extra runtime)."""

#: The clock process' tick (its publication period), simulated s, where none is given:
#: ``team up`` and ``team clock`` without ``--tick``, :class:`~relloc.runtime.launcher.TeamSettings`
#: and a reproduction's :class:`~relloc.runtime.launcher.ProcessTeam`.
CLOCK_TICK_S = 0.1
