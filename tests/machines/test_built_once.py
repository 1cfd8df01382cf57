"""``lazy_records.built_once``: threads making their first calls at once get one object, built
once and handed out complete (a joint chain's one-pose record classes: docs/testing.md, "Audit
of threads, session 35")."""

import pickle
import threading
import time

import numpy as np

import pkmkit
from pkmkit.machines import chain_one
from pkmkit.machines.lazy_records import built_once


def test_threads_at_once_get_one_object_built_once():
    builds = []

    @built_once
    def make():
        builds.append(1)
        time.sleep(0.02)  # a slow build: every thread arrives while it runs
        return object()

    barrier = threading.Barrier(8)
    got = []

    def call():
        barrier.wait()
        got.append(make())

    threads = [threading.Thread(target=call) for _ in range(8)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    assert len(builds) == 1
    assert len({id(o) for o in got}) == 1 and len(got) == 8


def test_the_object_is_handed_out_only_when_complete():
    @built_once
    def make():
        cls = type("Built", (), {})
        time.sleep(0.02)
        cls.ready = True  # set after construction, before any thread may see it
        return cls

    barrier = threading.Barrier(4)
    seen = []

    def call():
        barrier.wait()
        seen.append(getattr(make(), "ready", False))

    threads = [threading.Thread(target=call) for _ in range(4)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    assert seen == [True] * 4


def test_chain_records_share_one_class_and_pickle_as_the_plain_record():
    m = pkmkit.machine("trimule-600")
    act = np.flatnonzero(m.model.actuated)
    x = m.fk(0.5 * (m.model.q_min[act] + m.model.q_max[act]))  # mid-stroke
    m.ik(x, full_output=True)  # a machine's first one-pose call may take the batch path
    a = m.ik(x, full_output=True)
    b = m.ik(x, full_output=True)
    assert type(a) is type(b) is chain_one._inverse_record_class()
    plain = pickle.loads(pickle.dumps(a))
    assert type(plain).__name__ == "ChainInverseResult"
    np.testing.assert_array_equal(plain.q, a.q)
