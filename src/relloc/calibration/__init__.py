"""Error models fitted on recorded data, each on a stated calibration window.

Every fit takes the data and a :class:`~relloc.calibration.window.CalibrationWindow` (a time
span of a recording, or the whole of a separate calibration recording) and returns a frozen
record that names its window, the fitted values and diagnostics, and writes itself to
summary.json with ``to_dict()``. The real-data experiments call these fits; none fits on its
own.

- :mod:`~relloc.calibration.window` — the window type and how a window is chosen;
- :mod:`~relloc.calibration.odometry` — odometry latency, scales and variance rates of a team,
  the equivalent white noise of one robot, the best linear filter of the commands and the
  ground truth's own velocities as odometry;
- :mod:`~relloc.calibration.turn_rate` — the turn-rate residual calibrated commands leave and
  the yaw random walk it implies;
- :mod:`~relloc.calibration.camera` — bearing offsets and noise, range bias and noise, their
  time correlation, the detection probability and the field of view of the MRCLAM camera;
- :mod:`~relloc.calibration.uwb` — UWB bias, link-to-link bias spread, core spread, outliers
  and correlation time;
- :mod:`~relloc.calibration.inflation` — the variance inflation a white-noise filter needs for
  time-correlated errors.
"""
