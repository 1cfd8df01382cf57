"""Property-based fuzzing of the public entry points and file readers (Hypothesis).

Every fuzz test feeds random and hostile inputs (NaN, ±inf, huge and tiny numbers, wrong shapes
and types, random bytes, truncated and malformed files) and checks the three promises of the
library: only :class:`pkmkit.PkmError` subclasses are raised on bad input (any other exception
fails the test), no call hangs (each example runs under a wall-clock alarm), and an answer that
is returned is checked (round trips, closure residuals, invariants).

Profiles (registered and loaded once, in ``tests/conftest.py``): ``dev`` keeps the suite fast
(25 examples per test, the same on every run); ``fuzz`` runs 400, also the same ones on every
run (``HYPOTHESIS_PROFILE=fuzz python -m pytest tests/fuzz``, what ``.ci/run`` runs);
``explore`` runs 400 new ones each time, to hunt for bugs. This file loads no profile: a load at
collection would change the settings of every test collected after it.
"""

from __future__ import annotations

import contextlib
import signal

from hypothesis import settings

#: For tests whose examples each run an optimiser (sizing rules, arm sizing): a fifth of the
#: profile's examples (5 by default, 80 with the fuzz profile).
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
