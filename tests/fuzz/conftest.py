"""Property-based fuzzing of the public entry points and file readers (Hypothesis).

Every fuzz test feeds random and hostile inputs (NaN, ±inf, huge and tiny numbers, wrong shapes
and types, random bytes, truncated and malformed files) and checks the three promises of the
library: only :class:`pkmkit.PkmError` subclasses are raised on bad input (any other exception
fails the test), no call hangs (each example runs under a wall-clock alarm), and an answer that
is returned is checked (round trips, closure residuals, invariants).

Profiles: ``default`` keeps the suite fast (few examples per test); ``ci`` runs many more,
the same ones on every run (``HYPOTHESIS_PROFILE=ci python -m pytest tests/fuzz``, what
``.ci/run`` runs); ``explore`` runs as many, new ones each time, to hunt for bugs.
"""

from __future__ import annotations

import contextlib
import os
import signal

from hypothesis import HealthCheck, settings

_COMMON = {"deadline": None,
           "suppress_health_check": [HealthCheck.too_slow, HealthCheck.data_too_large,
                                     HealthCheck.filter_too_much]}
settings.register_profile("default", max_examples=25, derandomize=False, **_COMMON)
# the gate of .ci/run: many examples, the same ones on every run (a landing does not depend on
# luck); `explore` draws new ones on every run, to hunt for bugs by hand
settings.register_profile("ci", max_examples=400, derandomize=True, **_COMMON)
settings.register_profile("explore", max_examples=400, derandomize=False, **_COMMON)
settings.load_profile(os.environ.get("HYPOTHESIS_PROFILE", "default"))

#: For tests whose examples each run an optimiser (sizing rules, arm sizing): a fifth of the
#: profile's examples (5 by default, 80 with the ci profile).
slow_examples = settings(max_examples=max(5, settings.default.max_examples // 5))

#: Wall-clock limit of one example, s (a hang fails the test instead of blocking it).
EXAMPLE_TIMEOUT = 20.0


class Hang(AssertionError):
    """An example ran longer than :data:`EXAMPLE_TIMEOUT`."""


@contextlib.contextmanager
def bounded(seconds: float = EXAMPLE_TIMEOUT):
    """Fail with :class:`Hang` if the block runs longer than ``seconds`` (main thread only)."""
    def alarm(_signum, _frame):
        raise Hang(f"example still running after {seconds:g} s")

    previous = signal.signal(signal.SIGALRM, alarm)
    signal.setitimer(signal.ITIMER_REAL, seconds)
    try:
        yield
    finally:
        signal.setitimer(signal.ITIMER_REAL, 0)
        signal.signal(signal.SIGALRM, previous)
