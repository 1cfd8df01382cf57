"""Geometric error models of every machine: defects, sensitivity, compatibility, identifiability.

Sub-modules:
    model: named defect sets of a machine, exact defected models and the tool-point sensitivity
        ∂(tool point)/∂(defects) through the closure.
    measurements: measurement models (tool point, pose, ball-bar, height, machined part) and their
        analytic identification Jacobians.
    compatibility: which defects an over-constrained (hyperstatic) machine absorbs (seed 002).
    identifiability: base parameters, gauges and observability indices of a measurement plan.
    pose_selection: choosing measurement poses for identification.
    sensitivity, tolerance: first-order and Monte Carlo error budgets.
    configurations, selection: sampling regions and choosing which defects to study.

The typed exceptions every layer raises live in :mod:`pkmkit.exceptions`, not here.
"""
