"""The build cache of the generated C modules (:mod:`tests.export.c_build`): the same inputs are
compiled once, anything a build reads changes the key, and a failing ``-Werror`` build fails
every time (never served from the cache)."""

from __future__ import annotations

import ctypes
import subprocess

import pytest

from . import c_build
from .test_linuxcnc import FLAGS, _compiler

GOOD = "int pkm_answer(void) { return 42; }\n"


@pytest.fixture
def cache(tmp_path, monkeypatch):
    """An empty cache of its own, and the stub headers copied so a test may change one."""
    stub = tmp_path / "stub"
    stub.mkdir()
    for path in c_build.STUB.iterdir():
        if path.is_file():
            (stub / path.name).write_bytes(path.read_bytes())
    monkeypatch.setattr(c_build, "CACHE", tmp_path / "cache")
    monkeypatch.setattr(c_build, "STUB", stub)
    monkeypatch.delenv("PKMKIT_TEST_C_CACHE", raising=False)
    return tmp_path


def _source(directory, name, text):
    path = directory / f"{name}.c"
    path.write_text(text, encoding="utf-8")
    return path


def test_the_same_inputs_are_compiled_once_and_each_caller_gets_its_own_library(cache):
    cc = _compiler()
    (cache / "a").mkdir()
    (cache / "b").mkdir()
    first, second = cache / "a" / "m.so", cache / "b" / "m.so"
    assert c_build.build_shared(cc, FLAGS, [_source(cache / "a", "m", GOOD)], first)
    # the same text at another path (the file's name is an input: the library records it)
    assert not c_build.build_shared(cc, FLAGS, [_source(cache / "b", "m", GOOD)], second)
    assert first.read_bytes() == second.read_bytes() and not first.samefile(second)
    assert ctypes.CDLL(str(second)).pkm_answer() == 42


def test_a_changed_source_flag_or_header_is_compiled_again(cache):
    cc = _compiler()
    source = _source(cache, "a", GOOD)
    key = c_build.build_key(cc, FLAGS, [source])
    assert c_build.build_key(cc, FLAGS, [source]) == key
    assert c_build.build_key(cc, [*FLAGS, "-DX"], [source]) != key
    assert c_build.build_key(cc, FLAGS, [_source(cache, "b", GOOD)]) != key  # the name
    (cache / "c").mkdir()
    assert c_build.build_key(cc, FLAGS, [_source(cache / "c", "a", GOOD + "\n")]) != key
    (c_build.STUB / "hal.h").write_text("/* changed */\n", encoding="utf-8")
    assert c_build.build_key(cc, FLAGS, [source]) != key


def test_a_warning_fails_the_build_every_time_and_is_never_kept(cache):
    cc = _compiler()
    warned = _source(cache, "w", "int pkm_answer(void) { int unused; return 42; }\n")
    for _ in range(2):
        with pytest.raises(subprocess.CalledProcessError):
            c_build.build_shared(cc, FLAGS, [warned], cache / "w.so")
    assert not c_build.CACHE.exists() or not any(c_build.CACHE.iterdir())


def test_without_the_cache_every_build_compiles(cache, monkeypatch):
    monkeypatch.setenv("PKMKIT_TEST_C_CACHE", "0")
    cc = _compiler()
    for name in ("a", "b"):
        assert c_build.build_shared(cc, FLAGS, [_source(cache, name, GOOD)], cache / f"{name}.so")
    assert not c_build.CACHE.exists()


def test_the_oldest_libraries_beyond_the_limit_are_dropped(cache, monkeypatch):
    monkeypatch.setattr(c_build, "MAX_KEPT", 1)
    cc = _compiler()
    for k, name in enumerate(("a", "b")):
        c_build.build_shared(cc, FLAGS, [_source(cache, name, GOOD + "\n" * k)],
                             cache / f"{name}.so")
    kept = list(c_build.CACHE.glob("*.so"))
    assert [p.stem for p in kept] == [c_build.build_key(cc, FLAGS, [cache / "b.c"])]
