"""``pkmkit workspace`` of a joint chain by a flood fill from home (issue 22 §3): the same
workspace as ``--whole-grid``, the criteria counts over the points evaluated (said so)."""

from __future__ import annotations

import pytest


def _same_workspace(flood: dict, whole: dict) -> None:
    assert flood["evaluation"] == "flood fill from home" and whole["evaluation"] == "whole grid"
    size = 1
    for n in whole["grid"]["shape"]:
        size *= n
    assert whole["points_evaluated"] == size > flood["points_evaluated"]
    assert flood["grid"] == whole["grid"]
    for key in ("feasible_points", "volume", "reference", "faces_reached"):
        assert flood[key] == whole[key], key
    assert flood["inscribed"] == whole["inscribed"]
    # to round-off: the closures are reached from other starts (and a process's first batch
    # already differs from its second in the 16th digit)
    assert flood["index_range"] == pytest.approx(whole["index_range"], rel=1e-13)
    assert flood["workspace_index_range"] == pytest.approx(whole["workspace_index_range"],
                                                           rel=1e-13)
    assert flood["global_conditioning_index"] == pytest.approx(
        whole["global_conditioning_index"], rel=1e-13)
    # counts over the points evaluated: every one of them in the whole grid's counts
    for name, count in flood["points_per_criterion"].items():
        assert flood["feasible_points"] <= count <= flood["points_evaluated"]
        assert count <= whole["points_per_criterion"][name]


def test_the_flood_says_what_it_evaluated(run, as_json):
    args = ("workspace", "tripteor-x7", "--resolution", "7")
    flood = as_json(run(*args, "--json"))
    whole = as_json(run(*args, "--whole-grid", "--json"))
    _same_workspace(flood, whole)
    text = run(*args).output
    assert f"; {flood['points_evaluated']} evaluated, by a flood fill from home)" in text
    assert "flood fill" not in run(*args, "--whole-grid").output


@pytest.mark.ci
@pytest.mark.parametrize("name", ["tripteor-x7", "trimule-600"])
def test_the_default_studies_by_flood_are_the_whole_grids(run, as_json, name):
    flood = as_json(run("workspace", name, "--json"))
    whole = as_json(run("workspace", name, "--whole-grid", "--json"))
    _same_workspace(flood, whole)
