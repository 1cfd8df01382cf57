"""The Hypothesis settings of the ordinary run are the documented, deterministic ones
(docs/testing.md): registered and loaded once in ``tests/conftest.py``, never reloaded."""

import importlib
import os

import pytest
from hypothesis import settings

from tests.conftest import DETERMINISTIC_PROFILES

EXPLORING = os.environ.get("HYPOTHESIS_PROFILE") == "explore"


@pytest.mark.skipif(EXPLORING, reason="the explore profile draws new examples on purpose")
def test_the_active_profile_draws_the_same_examples_every_run():
    name = settings.get_current_profile_name()
    assert name in DETERMINISTIC_PROFILES
    assert settings.default.derandomize
    assert settings.default == settings.get_profile(name)
    # CI=true does not choose the profile: the ordinary run draws dev's 25 examples everywhere,
    # .ci/run asks for "ci" by name in its second stage (docs/testing.md, "Suite time")
    expected = os.environ.get("HYPOTHESIS_PROFILE") or "dev"
    assert name == expected


def test_the_fuzz_conftest_loads_no_profile():
    """Importing ``tests/fuzz/conftest.py`` (as collection does) leaves the active settings
    as they are; it used to load a random 25-example profile for the rest of the session."""
    before = (settings.get_current_profile_name(), settings.default)
    importlib.reload(importlib.import_module("tests.fuzz.conftest"))
    assert (settings.get_current_profile_name(), settings.default) == before


@pytest.mark.skipif(EXPLORING, reason="the explore profile draws new examples on purpose")
def test_property_tests_collected_after_the_fuzz_tests_are_deterministic():
    """A property test in a module collected after ``tests/fuzz`` keeps the profile's
    settings (derandomized, the profile's number of examples)."""
    module = importlib.import_module("tests.machines.test_properties")
    tests = [getattr(module, n) for n in dir(module) if n.startswith("test_")]
    used = [t._hypothesis_internal_use_settings for t in tests
            if getattr(t, "is_hypothesis_test", False)]
    assert used and all(s.derandomize for s in used)
