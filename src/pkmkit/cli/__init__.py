"""The ``pkmkit`` command line (thin layer over the library).

The demos moved to :mod:`pkmkit.demos` and the command-line coordinates to
:mod:`pkmkit.boundary.coordinates`; the old paths (``pkmkit.cli.demo``,
``pkmkit.cli.demo_analysis``, …, ``pkmkit.cli.coordinates``) still import, with a
:class:`DeprecationWarning`, for one release (:mod:`pkmkit.aliases`).
"""

from __future__ import annotations

from pkmkit import aliases

#: Old module path → new one (kept for one release).
MOVED = {
    "pkmkit.cli.demo": "pkmkit.demos.run",
    **{f"pkmkit.cli.demo_{name}": f"pkmkit.demos.{name}"
       for name in ("analysis", "calibration", "design", "errors", "machines", "machining",
                    "motion", "stiffness")},
    "pkmkit.cli.coordinates": "pkmkit.boundary.coordinates",
}

aliases.install(modules=MOVED)
