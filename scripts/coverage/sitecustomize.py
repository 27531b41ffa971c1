"""Coverage of the robot processes, for ``scripts/coverage.sh`` only (never on a user's path).

The team launcher starts its robots through a ``forkserver`` and each child ends with
``os._exit`` (or is terminated), so neither coverage's atexit hook nor its multiprocessing
support ever saves their data. Put on ``PYTHONPATH``, this module wraps every multiprocessing
child's entry: it starts a :class:`coverage.Coverage` from ``$COVERAGE_RCFILE`` and saves it when
the child returns, calls ``os._exit`` or receives SIGTERM.
"""

import multiprocessing.process
import os
import signal

_bootstrap = multiprocessing.process.BaseProcess._bootstrap
_exit = os._exit


def _measured_bootstrap(self, *args, **kwargs):  # type: ignore[no-untyped-def]
    import coverage

    cov = coverage.Coverage(data_suffix=True, config_file=os.environ["COVERAGE_RCFILE"])
    cov.start()

    def save() -> None:
        cov.stop()
        cov.save()

    def exit_saved(code: int) -> None:
        save()
        _exit(code)

    os._exit = exit_saved
    signal.signal(signal.SIGTERM, lambda signum, frame: exit_saved(128 + signum))
    try:
        return _bootstrap(self, *args, **kwargs)
    finally:
        save()


multiprocessing.process.BaseProcess._bootstrap = _measured_bootstrap
