"""The sentence that says by how much a joint chain's legs miss the platform
(:func:`pkmkit.machines.chain_checks.miss_message`): the leg that misses most by translation +
L × rotation first, every length in mm and every angle in degrees (the library's metres and
radians × 1000 and × 180/π, written out here), the other legs that miss after it, largest first.
Added from the session-34 mutation sample of ``pkmkit.machines``, where
``translation[i] * 1e3`` → ``translation[i]`` (a miss printed in metres labelled mm) passed
every test that calls the function (docs/testing.md)."""

from __future__ import annotations

import numpy as np

import pkmkit
from pkmkit.machines.chain_checks import miss_message


def test_the_misses_in_mm_and_degrees_largest_first():
    model = pkmkit.machine("tripteor-x7").model  # three legs, L = 0.5 m
    translation = np.array([0.0124, 0.002, 0.0])  # m
    rotation = np.radians([0.31, 0.0, 0.5])  # rad: leg 3's 0.5° is 4.4 mm at L = 0.5 m
    leg, text = miss_message(model, translation, rotation)
    assert leg == 0
    assert text == ("leg 1 misses the platform by 12.4 mm and 0.31° "
                    "(leg 3 by 0 mm and 0.5°, leg 2 by 2 mm and 0°)")


def test_a_leg_that_closes_is_not_listed_and_a_large_miss_keeps_its_digits():
    model = pkmkit.machine("tripteor-x7").model
    leg, text = miss_message(model, np.array([0.0, 1.23456, 0.0]), np.array([0.0, 0.0, 0.0]))
    assert leg == 1
    assert text == "leg 2 misses the platform by 1235 mm and 0°"  # 4 significant digits
