"""``pkmkit select-poses --out X.csv`` writes its small table without pyarrow (issue 22 §5:
start-up; docs/testing.md, "Audit of shared state, session 34", item 3): in a fresh
interpreter the command runs, writes the file, and ``pyarrow`` is not in ``sys.modules`` —
checked by import, never by timing (the style of tests/cli/test_startup_help.py). The bytes are
pyarrow's (:func:`pkmkit.io.table_writer.small_csv` against the pyarrow writer,
tests/io/test_small_csv.py)."""

import json
import subprocess
import sys
import textwrap

_SCRIPT = textwrap.dedent("""
    import json, sys
    from pkmkit.cli.main import cli

    try:
        cli(["select-poses", "delta", "--measure", "point", "--n", "10", "--candidates", "60",
             "--out", sys.argv[1]], standalone_mode=False)
    except SystemExit:
        pass
    print(json.dumps(sorted(m for m in sys.modules if m.split(".")[0] == "pyarrow")))
""")


def test_select_poses_writes_its_csv_without_pyarrow(tmp_path):
    out = tmp_path / "chosen.csv"
    run = subprocess.run([sys.executable, "-c", _SCRIPT, str(out)], capture_output=True,
                         text=True, check=True)
    assert json.loads(run.stdout.splitlines()[-1]) == []
    lines = out.read_text().splitlines()
    assert lines[0] == "# units: m" and lines[1] == "q1,q2,q3" and len(lines) == 12
    assert all(len(row.split(",")) == 3 for row in lines[2:])
