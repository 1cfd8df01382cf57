"""Shared fixtures: built-in machines and random poses inside their workspaces; the Hypothesis
settings profiles, registered here once for the whole session and loaded here only:

- ``dev`` (alias ``default``): 25 examples per property, the same on every run (``derandomize``);
- ``ci``: 100 examples, the same on every run: ``.ci/run``'s second stage (``-m "slow or ci or
  hypothesis"``: the heavy tests and every property test again with 4x the examples); the
  ordinary run keeps ``dev`` even when ``CI`` is set (docs/testing.md, "Suite time");
- ``fuzz``: 400 examples, the same on every run (``.ci/run``'s gate of ``tests/fuzz``);
- ``explore``: 400 new random examples on every run, to hunt for bugs by hand;
- ``mutation``: ``dev``'s examples without shrinking failures (``tools/mutation.py
  --plausible``).

``HYPOTHESIS_PROFILE=NAME`` chooses one explicitly. No other conftest loads a profile (a load
at collection would change the settings of every test collected after it).
"""

from __future__ import annotations

import os
import sys

# Write the bytecode caches (``__pycache__``) even under PYTHONDONTWRITEBYTECODE=1: without
# them every test process compiles pkmkit's ~300 modules and pytest rewrites the asserts of
# ~260 test modules again (≈ 9 s of CPU per pytest-xdist worker, ≈ 0.1 s per ``pkmkit``
# subprocess the tests start, which read the caches whatever the variable says).
# docs/testing.md, "Suite time".
sys.dont_write_bytecode = False

import numpy as np  # noqa: E402
import pytest  # noqa: E402
from hypothesis import HealthCheck, Phase, settings  # noqa: E402

import pkmkit  # noqa: E402
from pkmkit.machines.registry import ALIASES  # noqa: E402
from pkmkit.model.rods import CRANK  # noqa: E402

_COMMON = {"deadline": None,
           "suppress_health_check": [HealthCheck.too_slow, HealthCheck.filter_too_much,
                                     HealthCheck.data_too_large]}
#: The profiles that draw the same examples on every run (everything but ``explore``).
DETERMINISTIC_PROFILES = ("dev", "default", "ci", "fuzz", "mutation")
settings.register_profile("dev", max_examples=25, derandomize=True, **_COMMON)
settings.register_profile("default", settings.get_profile("dev"))
settings.register_profile("ci", settings.get_profile("dev"), max_examples=100)
settings.register_profile("fuzz", settings.get_profile("dev"), max_examples=400)
settings.register_profile("explore", settings.get_profile("fuzz"), derandomize=False)
# the examples of dev without shrinking a failure (tools/mutation.py --plausible: a kill is a
# kill, the smallest failing example is not needed)
settings.register_profile("mutation", settings.get_profile("dev"),
                          phases=[Phase.explicit, Phase.reuse, Phase.generate])
settings.load_profile(os.environ.get("HYPOTHESIS_PROFILE") or "dev")


ALL_PRESETS = [m for m in pkmkit.machines() if m not in ALIASES]
#: Presets whose platform only translates (dims 2 or 3).
PRESETS = [m for m in ALL_PRESETS if pkmkit.machine(m).dims in (2, 3)]
#: Rod-leg presets whose platform has a full pose (dims 6).
FULL_POSE_PRESETS = [m for m in ALL_PRESETS
                     if type(pkmkit.machine(m)).__name__ == "FullPoseMachine"]
#: Joint-chain presets.
CHAIN_PRESETS = [m for m in ALL_PRESETS
                 if type(pkmkit.machine(m)).__name__ == "JointChainMachine"]
#: Translational presets whose actuators are all linear (slides, struts): what the dynamics
#: layer models.
LINEAR_PRESETS = [m for m in PRESETS if not (pkmkit.machine(m).model.leg_kind == CRANK).any()]


class _ModuleGroups:
    """Run a test module's tests on one pytest-xdist worker (``--dist loadgroup``).

    A test without an ``xdist_group`` mark (the documentation pages have one each) joins the
    group of its module. Without it, ``loadgroup`` hands out the ungrouped tests one at a time,
    so consecutive tests of a module alternated between the workers and both paid the module's
    fixtures and the first calls of its compiled kernels (docs/testing.md, "Suite time").
    """

    @pytest.hookimpl(tryfirst=True)  # before pytest-xdist's worker hook reads the marks
    def pytest_collection_modifyitems(self, items: list[pytest.Item]) -> None:
        if os.environ.get("PKMKIT_TEST_GROUP") == "0":
            return
        for item in items:
            if item.get_closest_marker("xdist_group") is None:
                item.add_marker(pytest.mark.xdist_group(item.nodeid.split("::", 1)[0]))


def pytest_configure(config: pytest.Config) -> None:
    config.pluginmanager.register(_ModuleGroups(), "pkmkit-module-groups")


@pytest.hookimpl(trylast=True)
def pytest_collection_modifyitems(config: pytest.Config, items: list[pytest.Item]) -> None:
    """Carry pytest-xdist's ``@group`` suffix into the node id pytest 9 reads.

    With ``--dist loadgroup``, pytest-xdist 3.8's worker hook appends ``@<group>`` to
    ``item._nodeid``; pytest 9 computes ``item.nodeid`` from ``item._id`` and never reads
    ``_nodeid``, so the scheduler saw no group and spread a documentation page's blocks over
    both workers (docs/testing.md). This hook runs after xdist's and moves the suffixed id
    into ``_id``. It does nothing where the two already agree (pytest < 9, no xdist, no group).
    """
    for item in items:
        suffixed = item.__dict__.get("_nodeid")
        if not isinstance(suffixed, str) or suffixed == item.nodeid or "@" not in suffixed:
            continue
        from _pytest.nodeid import coerce_node_id  # pytest >= 9 only
        item._id = coerce_node_id(suffixed)
        if item.nodeid != suffixed:  # pragma: no cover - a pytest that parses ids differently
            raise pytest.UsageError(f"cannot group {suffixed!r} for --dist loadgroup")


def workspace_half_width(machine: pkmkit.Machine) -> float:
    """Half side of a box around home that is reachable and far from singularities."""
    return 0.25 * float(machine.model.leg_length.min())


def near_parallel_singular_poses(count: int, rng: np.random.Generator
                                  ) -> tuple[pkmkit.Machine, np.ndarray, np.ndarray]:
    """The Gough–Stewart platform and ``count`` of its poses ``(count, 6)`` whose parallel
    measure μ (σ_min/σ_max of the unit-row A, ``(count,)``, also returned) is below 1e-2, the
    smallest below 1e-4: drawn in its default box with angles within ±70°."""
    from pkmkit.spatial import pose_from_angles

    m = pkmkit.machine("gough-stewart")
    lo, hi = m.default_box()
    x = pose_from_angles(rng.uniform(lo, hi, (20000, 3)), rng.uniform(-70, 70, (20000, 3)),
                         "xyz", degrees=True)
    measure = m.jacobian(x).parallel_measure
    near = measure < 1e-2
    x, measure = x[near][:count], measure[near][:count]
    assert len(x) == count and measure.min() < 1e-4
    return m, x, measure


def random_poses(machine: pkmkit.Machine, n: int, seed: int = 0) -> np.ndarray:
    """``n`` poses drawn uniformly in a box around the home pose, ``(n, dims)``."""
    rng = np.random.default_rng(seed)
    h = workspace_half_width(machine)
    return machine.home_pose + rng.uniform(-h, h, (n, machine.dims))


@pytest.fixture(params=PRESETS)
def preset(request) -> pkmkit.Machine:
    """Every built-in preset machine with a translational platform."""
    return pkmkit.machine(request.param)


@pytest.fixture(params=FULL_POSE_PRESETS)
def full_pose_preset(request):
    """Every built-in full-pose (6-DOF platform) machine."""
    return pkmkit.machine(request.param)


@pytest.fixture(params=LINEAR_PRESETS)
def linear_preset(request) -> pkmkit.Machine:
    """Every built-in preset machine with linear actuators only (slides, struts)."""
    return pkmkit.machine(request.param)
