"""The fork server runs a block as a new process would (``fork_server``): the same output and
exit status as the fresh-process path, a fresh state for every block, and a wrong output
fails either way."""

import subprocess

import pytest

from .docs_blocks import blocks
from .fork_server import ForkServer, shell_words
from .test_docs_run import _command, _environment, _python, _run


def test_only_plain_pkmkit_command_lines_are_split_without_a_shell():
    assert shell_words("pkmkit ik orthoglide --pose 0,0,0.1   # a note") == [
        "pkmkit", "ik", "orthoglide", "--pose", "0,0,0.1"]
    assert shell_words("""pkmkit fk x --set 'a b' --q "1, 2" c#d""") == [
        "pkmkit", "fk", "x", "--set", "a b", "--q", "1, 2", "c#d"]
    for text in ("pkmkit ik x > out.txt", "pkmkit ik x | head -2", "pkmkit ik $M",
                 "pkmkit ik *.toml", "pkmkit ik x && ls", "pkmkit ik x\\ y",
                 'pkmkit ik "$HOME"', "pkmkit ik ~/m.toml", "pkmkit ik {a,b}", "pkmkit ik 'x"):
        assert shell_words(text) is None, text
    assert shell_words("X=1 pkmkit ik x")[0] == "X=1"  # not a plain pkmkit: through bash


@pytest.mark.parametrize("text", [
    "pkmkit --version",
    "pkmkit ik orthoglide --pose 0.01,0.02,0.03",
    "pkmkit ik no-such-machine --pose 0,0,0",  # an error: status 1, message on stderr
    "pkmkit ik orthoglide --pose 0,0",  # a usage error: status 2
])
def test_a_command_prints_and_exits_as_in_a_new_process(text, tmp_path):
    env = _environment()
    forked = _command(text, tmp_path, env, fresh=False)
    assert forked == _command(text, tmp_path, env, fresh=True)
    assert forked[1].strip()


def test_each_program_starts_from_a_fresh_state(tmp_path):
    """What a block changes (a module, the environment, the folder) does not reach the next;
    it runs as ``python -c`` in its folder, without Numba imported (pkmkit's compiled paths
    depend on that); exit statuses and tracebacks as the interpreter gives them."""
    env = _environment()
    first = ("import os, sys, numpy, pkmkit\n"
             "print(__name__, sys.argv, os.getcwd(), repr(sys.path[0]), 'numba' in sys.modules)\n"
             "def f(x: int): pass\n"
             "print(f.__annotations__)\n"  # no future flag of the server's code
             "pkmkit.planted = 1; os.environ['PLANTED'] = '1'; os.chdir('/')\n")
    later = ("import os, pkmkit\n"
             "print(hasattr(pkmkit, 'planted'), 'PLANTED' in os.environ, os.getcwd())\n")
    for fresh in (False, True):
        status, out, _ = _python(first, tmp_path, env, fresh)
        assert (status, out) == (0, f"__main__ ['-c'] {tmp_path} '' False\n"
                                    "{'x': <class 'int'>}\n")
        assert _python(later, tmp_path, env, fresh)[:2] == (0, f"False False {tmp_path}\n")
    for program, want in (("import sys; sys.exit(3)", (3, "")),
                          ("import sys; sys.exit('stopped')", (1, "stopped\n")),
                          ("print('out'); 1 / 0", (1, "ZeroDivisionError"))):
        for fresh in (False, True):
            status, out, err = _python(program, tmp_path, env, fresh)
            assert status == want[0] and want[1] in err, (program, fresh, err)


@pytest.mark.parametrize("fresh", [False, True])
def test_a_wrong_output_fails_either_way(fresh, tmp_path, monkeypatch):
    if fresh:
        monkeypatch.setenv("PKMKIT_DOCS_FRESH", "1")
    page = tmp_path / "page.md"
    page.write_text("""```console
$ pkmkit ik orthoglide --pose 0.01,0.02,0.03 --units mm
...
```

```console
$ pkmkit ik orthoglide --pose 0.01,0.02,0.03 --units mm
Error: planted
```

```python
print(round(2 ** 0.5, 4))
```

<!-- docs-test: output -->
```text
1.4152
```
""")
    right, error, program = blocks(page)
    _run(right, tmp_path, check=True)
    for wrong in (error, program):
        with pytest.raises(AssertionError):
            _run(wrong, tmp_path, check=True)


def test_a_block_marked_fresh_runs_in_a_new_process(tmp_path, monkeypatch):
    """The fork server's children see its warm imports; a ``fresh`` block does not."""
    monkeypatch.delenv("PKMKIT_DOCS_FRESH", raising=False)
    program = '```python\nimport sys\nprint("numpy" in sys.modules)\n```\n'
    page = tmp_path / "page.md"
    page.write_text(f"""{program}
<!-- docs-test: output -->
```text
True
```

<!-- docs-test: fresh -->
{program}
<!-- docs-test: output -->
```text
False
```
""")
    warm, fresh = blocks(page)
    assert "fresh" in fresh.options
    _run(warm, tmp_path, check=True)
    _run(fresh, tmp_path, check=True)


def test_a_block_past_its_time_limit_is_stopped(tmp_path):
    """A hung block is killed with the server at the limit (as ``subprocess.run`` would kill
    its process); the next block gets a new server."""
    server = ForkServer(_environment())
    request = {"cwd": str(tmp_path), "env": _environment()}
    try:
        with pytest.raises(subprocess.TimeoutExpired):
            server.run({**request, "program": "import time; time.sleep(600)"}, merge=False,
                       timeout=2)
        assert server.run({**request, "program": "print(6 * 7)"}, merge=False,
                          timeout=600) == (0, "42\n", "")
    finally:
        server.close()
