"""pkmkit.parallel: chunked work serially or on Dask, identical results; applied to workspace
grids, index maps and design populations."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

import pkmkit
from pkmkit.analysis import Criteria, compute_workspace
from pkmkit.analysis.grids import make_grid
from pkmkit.analysis.indices import index_values, indices, scalar_index
from pkmkit.exceptions import InputError
from pkmkit.parallel import (
    chunk_ranges,
    chunk_seeds,
    concatenate,
    executor,
    map_chunks,
    map_rows,
)


@dataclasses.dataclass
class Pair:
    a: np.ndarray
    b: dict


def test_chunk_ranges_and_map_chunks_keep_order():
    assert chunk_ranges(5, 2) == [(0, 2), (2, 4), (4, 5)]
    assert chunk_ranges(0, 3) == []
    with pytest.raises(InputError):
        chunk_ranges(4, 0)
    assert map_chunks(lambda a, b, c: (a, b, c), 7, chunk=3, args=("x",)) == [
        (0, 3, "x"), (3, 6, "x"), (6, 7, "x")]


def test_concatenate_nested_results():
    parts = [Pair(np.arange(2), {"m": np.ones(2), "n": "same"}),
             Pair(np.arange(2, 5), {"m": np.zeros(3), "n": "same"})]
    joined = concatenate(parts)
    np.testing.assert_array_equal(joined.a, np.arange(5))
    np.testing.assert_array_equal(joined.b["m"], [1, 1, 0, 0, 0])
    assert joined.b["n"] == "same"
    with pytest.raises(InputError, match="cannot join"):
        concatenate(["a", "b"])


def test_map_rows_equals_one_call():
    x = np.random.default_rng(0).normal(size=(1000, 3))
    np.testing.assert_array_equal(map_rows(np.cumsum, x.ravel(), chunk=7)[-3:],
                                  np.concatenate([np.cumsum(x.ravel()[k:k + 7])
                                                  for k in range(0, 3000, 7)])[-3:])
    m = pkmkit.machine("orthoglide")
    np.testing.assert_array_equal(map_rows(m.ik, x * 0.05, chunk=333), m.ik(x * 0.05))


def test_chunk_seeds_are_reproducible_and_independent():
    a = [np.random.default_rng(s).random(3) for s in chunk_seeds(7, 3)]
    b = [np.random.default_rng(s).random(3) for s in chunk_seeds(7, 3)]
    np.testing.assert_array_equal(a, b)
    assert not np.array_equal(a[0], a[1])


def test_bad_schedulers():
    with pytest.raises(InputError, match="local:N"), executor("local:zero"):
        pass
    with pytest.raises(InputError, match="scheduler must be"), executor(3.5):
        pass
    pytest.importorskip("distributed")
    with pytest.raises(InputError, match="cannot reach the Dask scheduler"), \
            executor("tcp://127.0.0.1:1", timeout=0.5):
        pass


def test_local_cluster_is_silent_when_port_8787_is_busy():
    """distributed starts the scheduler's HTTP server on 8787 even without a dashboard and
    warns when that port is taken (a documentation example's output failed CI so):
    ``local_cluster`` takes a free port instead."""
    import socket
    import warnings

    distributed = pytest.importorskip("distributed")
    from pkmkit.parallel import local_cluster

    holder = socket.socket(socket.AF_INET, socket.SOCK_STREAM)
    try:
        holder.bind(("", 8787))
        holder.listen(1)
    except OSError:
        pass                        # someone else holds it already: just as busy
    try:
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            with local_cluster(1) as cluster, distributed.Client(cluster) as c:
                assert c.submit(int, "7").result() == 7
    finally:
        holder.close()
    assert not [w for w in caught if "8787" in str(w.message)], [str(w.message) for w in caught]


@pytest.fixture(scope="module")
def client():
    distributed = pytest.importorskip("distributed")
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=False,
                                  dashboard_address=None,
                                  scheduler_kwargs={"dashboard_address": ":0"}) as cluster, \
            distributed.Client(cluster) as c:
        yield c


def test_workspace_on_dask_is_identical(client, monkeypatch):
    from pkmkit.analysis import criteria

    monkeypatch.setattr(criteria, "EVALUATION_CHUNK", 997)  # several tasks on a small grid
    m = pkmkit.machine("orthoglide")
    grid = make_grid(*m.default_box(), free=(0, 1, 2), base=m.home_pose,
                     names=m.pose_names, resolution=21)
    criteria = Criteria(bounds=(0.5, 2.0))
    serial = compute_workspace(m, grid, criteria)
    remote = compute_workspace(m, grid, criteria, scheduler=client)
    for name in serial.masks:
        np.testing.assert_array_equal(remote.masks[name], serial.masks[name])
    np.testing.assert_array_equal(remote.factors, serial.factors)
    np.testing.assert_array_equal(remote.q, serial.q)
    assert remote.inscribed.side == serial.inscribed.side


def test_index_map_on_dask_is_identical(client):
    m = pkmkit.machine("five-bar")
    pts = make_grid(*m.default_box(), free=(0, 1), base=m.home_pose, names=m.pose_names,
                    resolution=60).points
    serial = index_values(m, pts, "condition", chunk=500)
    remote = index_values(m, pts, "condition", chunk=500, scheduler=client)
    np.testing.assert_array_equal(remote, serial)
    np.testing.assert_allclose(serial, scalar_index(indices(m, pts), "condition"), rtol=1e-12)
    assert np.isnan(serial).any() and np.isfinite(serial).any()


def test_design_population_on_dask_is_identical(client):
    from pkmkit.design.metrics import Region
    from pkmkit.design.optimize import DesignProblem, Objective, Variable, optimize

    problem = DesignProblem(
        base=pkmkit.machine("linear-delta"),
        variables=[Variable("R", 0.45, 1.0), Variable("L", 0.9, 1.6)],
        objectives=[Objective("compactness", "max")],
        region=Region(0.4, (0.0, 0.0, 0.25)), criteria=Criteria(bounds=(0.4, 2.5)),
        samples=5)
    serial = optimize(problem, seed=3, generations=3, population=8)
    remote = optimize(problem, seed=3, generations=3, population=8, scheduler=client)
    assert len(remote.records) == len(serial.records) > 16
    for a, b in zip(remote.records, serial.records, strict=True):
        assert a.keys() == b.keys()
        for key in a:
            np.testing.assert_array_equal(np.asarray(a[key], dtype=object),
                                          np.asarray(b[key], dtype=object))
    assert remote.best == serial.best


@pytest.mark.ci
def test_cli_scheduler_option(client, tmp_path):
    """--scheduler ADDRESS on map, workspace and optimize: same output as the serial run."""
    import json

    from click.testing import CliRunner

    from pkmkit.cli.main import cli

    address = client.scheduler.address
    runner = CliRunner()

    def run(*args):
        result = runner.invoke(cli, [str(a) for a in args], catch_exceptions=False)
        assert result.exit_code == 0, result.output
        return json.loads(result.stdout)

    for command in (["map", "five-bar", "--index", "condition", "--out", tmp_path / "m.png"],
                    ["workspace", "five-bar", "--resolution", "40"],
                    ["optimize", "linear-delta", "--vary", "R=0.45:1.0", "--objective",
                     "max:compactness", "--region", "0.4@0,0,0.25", "--generations", "2",
                     "--population", "6", "--samples", "4", "--no-progress", "--out",
                     tmp_path / "opt"]):
        serial = run(*command, "--json")
        remote = run(*command, "--json", "--scheduler", address)
        assert remote == serial
