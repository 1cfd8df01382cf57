"""``pkmkit demo`` and the seed studies it runs: the kinematic summary of every built-in machine
(:mod:`.run`), then analysis, design, motion, full-pose and joint-chain machines, stiffness,
geometric errors, calibration and the machined part (one module each).

Above the library and below the command line: the ``demo`` command calls :func:`.run.run_demo`;
nothing here imports :mod:`pkmkit.cli`.
"""
