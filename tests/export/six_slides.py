"""A six-slide hexapod (hexaglide-like: six parallel horizontal slides, rods down to the
platform), written as a rod-legs machine file: the slide family of full-pose machines, which no
built-in has."""

from __future__ import annotations

from pathlib import Path

import numpy as np

import pkmkit


def six_slide_machine(directory: Path):
    ys = [-0.6, -0.6, 0.0, 0.0, 0.6, 0.6]  # two carriages per rail, condition 23 at home
    angles = np.radians([-120, -60, 0, 60, 120, 180])
    lines = ['[machine]', 'kind = "rod-legs"', 'name = "six slides"', 'dims = 6',
             'home = [0, 0, -0.5, 0, 0, 0]', '']
    for i, (y, a) in enumerate(zip(ys, angles, strict=True)):
        base = np.array([-0.5 if i % 2 else 0.5, y, 0.0])
        platform = np.array([0.25 * np.cos(a), 0.25 * np.sin(a), 0.0])
        length = float(np.linalg.norm(platform + np.array([0.0, 0.0, -0.5]) - base))
        lines += ['[[legs]]', f'actuator = "q{i + 1}"', 'type = "slide"',
                  f'base = [{base[0]}, {base[1]}, 0]', 'axis = [1, 0, 0]',
                  f'platform = [{platform[0]:.6f}, {platform[1]:.6f}, 0]',
                  f'length = {length:.6f}', '']
    path = directory / "six-slides.toml"
    path.write_text("\n".join(lines), encoding="utf-8")
    return pkmkit.load(path)
