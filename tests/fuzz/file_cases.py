"""Hostile files for the command line: a corpus of valid input files of every kind a command
reads (measurement files of each type, registration points and frames, tolerance, masses and
target files, joint-chain and six-axis machine files, CMM files, ball-bar plans, G-code), the
command lines that read them, mutations of a file or an option, and the classification of a
run (``ok``, ``typed`` error, ``traceback``, ``hang``, ``partial`` file).

Shared by ``test_fuzz_cli_files.py`` (Hypothesis, in-process) and ``tools/fuzz_cli.py``
(subprocesses, the counts of ``docs/reliability.md``). A case is drawn from a
:class:`random.Random`, so a seed reproduces it exactly.
"""

from __future__ import annotations

import functools
import random
import shutil
import tempfile
from dataclasses import dataclass
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
EXAMPLES = ROOT / "docs" / "examples"
DATA = ROOT / "src" / "pkmkit" / "machines" / "data"

#: Commands run once (in-process) to write the valid corpus, ``{d}`` the corpus directory.
CORPUS_COMMANDS = [
    "simulate-measurements linear-delta --measure point --poses 30 --defects random --seed 3 "
    "--units mm --out {d}/point.csv",
    "simulate-measurements linear-delta --measure point --poses 12 --defects {d}/point.truth.toml"
    " --seed 4 --units mm --out {d}/valid.csv",
    "simulate-measurements linear-delta --measure height --poses 30 --defects random --units mm "
    "--out {d}/height.csv",
    "simulate-measurements gough-stewart --measure pose --poses 30 --defects random --units mm "
    "--out {d}/pose.csv",
    "machined-part program verne --out {d}/part.nc",
    "machined-part simulate verne --gcode {d}/part.nc --defects random --sections 30 --units mm "
    "--out {d}/cmm.csv",
    "machined-part reconstruct {d}/cmm.csv --gcode {d}/part.nc --units mm --out {d}/centres.csv",
    "machined-part ballbar-plan verne --points 6 --units mm --out {d}/plan.csv",
    "simulate-measurements verne --measure ballbar --poses {d}/plan.csv --defects "
    "{d}/cmm.truth.toml --units mm --out {d}/ballbar.csv",
    f"register --measured {EXAMPLES}/lts.csv --nominal {EXAMPLES}/bcs.csv --units mm "
    "--out {d}/frame.json",
    "simulate-measurements linear-delta --measure point --poses 30 --defects {d}/point.truth.toml"
    " --frame {d}/frame.json --units mm --out {d}/tracker.csv",
]
#: Files written by hand into the corpus.
CORPUS_TEXT = {
    "targets.csv": "# units: mm\nx,y,z\n0,0,150\n20,10,160\n-30,5,140\n",
    "hexapod-targets.csv": "# units: mm\nx,y,z,rx,ry,rz\n0,0,800,0,0,0\n20,10,820,1,0,2\n",
    "delta-q.csv": "# units: mm\nid,q1,q2,q3\n" + "".join(
        f"p{k},{1100 + 37 * k % 150},{1150 + 53 * k % 140},{1120 + 71 * k % 130}\n"
        for k in range(14)),
    "stiffness-poses.csv": "x,y,z\n0,0,0\n0.05,0.02,-0.01\n",
    "chain-poses.csv": "Q1,Q2,Q3,Q4,Q5\n0.98,1.06,0.99,0,0\n0.99,1.05,0.98,5,-5\n",
}
#: Valid files copied from the documentation and the machine library.
CORPUS_COPIES = {
    "lts.csv": EXAMPLES / "lts.csv", "bcs.csv": EXAMPLES / "bcs.csv",
    "lts-points.csv": EXAMPLES / "lts-points.csv",
    "bcs-points.csv": EXAMPLES / "bcs-points.csv",
    "hexapod-6-6.toml": EXAMPLES / "hexapod-6-6.toml",
    "hexapod-tolerances.toml": EXAMPLES / "hexapod-tolerances.toml",
    "delta-masses.toml": EXAMPLES / "delta-masses.toml",
    "crank-slider.toml": EXAMPLES / "crank-slider.toml",
    "planar-3rpr.toml": EXAMPLES / "planar-3rpr.toml",
    "orthoglide-stiffness.toml": EXAMPLES / "orthoglide-stiffness.toml",
    "my-machine.toml": EXAMPLES / "my-machine.toml",
    "pocket.nc": EXAMPLES / "pocket.nc",
    "tripteor-x7.toml": DATA / "tripteor-x7.toml",
    "trimule-600.toml": DATA / "trimule-600.toml",
    "gough-stewart.toml": DATA / "gough-stewart.toml",
    "dietmaier-hexapod.toml": DATA / "dietmaier-hexapod.toml",
    "verne.toml": DATA / "verne.toml",
}


@dataclass(frozen=True)
class Template:
    """A command line reading ``target`` (the file the fuzzer mutates, a corpus name);
    ``{f}`` is the mutated file, ``{d}`` the corpus, ``{o}`` the output directory. Outputs
    are written in ``{o}``: none may exist after a failed run (exit 1 or 2); after exit 3
    (some rows or a verdict flagged), none of ``acted_on`` may (a calibrated machine file, a
    corrected program, an export); a correction table with its rows flagged may."""

    name: str
    args: str
    target: str
    options: tuple[str, ...] = ()
    acted_on: tuple[str, ...] = ()


TEMPLATES = [
    Template("calibrate point", "calibrate linear-delta --measure point --measurements {f}",
             "point.csv", ("--sigma", "--tolerance", "--parameters", "--units")),
    Template("calibrate point --validate", "calibrate linear-delta --measure point "
             "--measurements {d}/point.csv --validate {f} --out {o}/cal", "valid.csv",
             ("--sigma",), ("cal/linear-delta-calibrated.toml",)),
    Template("calibrate height", "calibrate linear-delta --measure height --measurements {f}",
             "height.csv", ("--sigma", "--units")),
    Template("calibrate pose", "calibrate gough-stewart --measure pose --measurements {f}",
             "pose.csv", ("--sigma", "--robust")),
    Template("calibrate ballbar", "calibrate verne --measure ballbar --measurements {f}",
             "ballbar.csv", ("--sigma", "--units")),
    Template("calibrate part", "calibrate verne --measure part --measurements {f}",
             "centres.csv", ("--sigma",)),
    Template("calibrate --frame", "calibrate linear-delta --measure point --measurements "
             "{d}/tracker.csv --frame {f} --units mm", "frame.json", ("--identify-frame",)),
    Template("register", "register --measured {f} --nominal {d}/bcs.csv --out {o}/frame.json",
             "lts.csv", ("--direction-weight", "--units")),
    Template("register nominal", "register --measured {d}/lts-points.csv --nominal {f} "
             "--out {o}/frame.json", "bcs-points.csv", ("--units",)),
    Template("compensate --targets", "compensate linear-delta --calibrated "
             "{d}/point.truth.toml --targets {f} --out {o}/table.csv", "targets.csv",
             ("--max-correction", "--units")),
    Template("compensate six-axis --targets", "compensate gough-stewart --calibrated "
             "{d}/pose.truth.toml --targets {f} --out {o}/table.csv", "hexapod-targets.csv",
             ("--max-correction",)),
    Template("compensate --calibrated", "compensate linear-delta --calibrated {f} "
             "--targets {d}/targets.csv --out {o}/table.csv", "point.truth.toml"),
    Template("compensate --gcode", "compensate linear-delta --calibrated {d}/point.truth.toml "
             "--gcode {f} --units mm --out {o}/fixed.nc", "pocket.nc",
             ("--step", "--tolerance", "--max-correction", "--origin"), ("fixed.nc",)),
    Template("errors --tolerance", "errors {d}/hexapod-6-6.toml --tolerance {f} "
             "--monte-carlo 10 --resolution 3", "hexapod-tolerances.toml",
             ("--region", "--seed")),
    Template("machined-part reconstruct", "machined-part reconstruct {f} --gcode {d}/part.nc "
             "--units mm --out {o}/centres.csv", "cmm.csv", ("--end-mill", "--ball-end",
                                                             "--origin")),
    Template("machined-part reconstruct --gcode", "machined-part reconstruct {d}/cmm.csv "
             "--gcode {f} --units mm --out {o}/centres.csv", "part.nc", ("--origin",)),
    Template("machined-part simulate", "machined-part simulate verne --gcode {f} "
             "--sections 20 --units mm --out {o}/cmm.csv", "part.nc",
             ("--sigma", "--placement", "--probe-radius", "--sections")),
    Template("simulate-measurements --poses plan", "simulate-measurements verne --measure "
             "ballbar --poses {f} --units mm --out {o}/bb.csv", "plan.csv", ("--noise",)),
    Template("simulate-measurements --poses", "simulate-measurements linear-delta --measure "
             "point --poses {f} --out {o}/m.csv", "delta-q.csv", ("--noise", "--units")),
    Template("identifiability --poses", "identifiability linear-delta --measure point "
             "--poses {f} --units mm", "delta-q.csv", ("--rtol", "--scaling")),
    Template("select-poses --candidates", "select-poses linear-delta --measure point --n 7 "
             "--candidates {f} --units mm --out {o}/chosen.csv", "delta-q.csv", ("--n",)),
    Template("stiffness machine file", "stiffness {f} --pose 0,0,0", "orthoglide-stiffness.toml",
             ("--wrench", "--reference", "--units")),
    Template("stiffness chain file", "stiffness {f} --q 0.98,1.06,0.99,0,0", "tripteor-x7.toml",
             ("--wrench", "--tool-length")),
    Template("stiffness six-axis file", "stiffness {f} --pose 0,0,0.8,0,0,0",
             "gough-stewart.toml", ("--wrench", "--reference")),
    Template("stiffness --input", "stiffness orthoglide --input {f} --output {o}/k.csv",
             "stiffness-poses.csv", ("--wrench",), ()),
    Template("show chain file", "show {f}", "trimule-600.toml", ("--units",)),
    Template("show joint-chain example", "show {f}", "planar-3rpr.toml", ()),
    Template("show six-axis file", "show {f}", "hexapod-6-6.toml", ("--units",)),
    Template("fk chain --input", "fk tripteor-x7 --input {f} --output {o}/x.csv",
             "chain-poses.csv", ()),
    Template("export klipper", "export {f} --to klipper --out {o}/printer.cfg",
             "my-machine.toml", ("--endstops", "--units"), ("printer.cfg",)),
    Template("export mjcf", "export {f} --to mjcf --out {o}/model.xml", "verne.toml", (),
             ("model.xml",)),
    Template("export linuxcnc", "export {f} --to linuxcnc --out {o}/fuzzkins.c",
             "gough-stewart.toml", ("--units",), ("fuzzkins.c",)),
    Template("export --masses", "export linear-delta --to mjcf --masses {f} "
             "--out {o}/model.xml", "delta-masses.toml", (), ("model.xml",)),
    Template("show crank-slider", "show {f}", "crank-slider.toml", ()),
]

#: Option values a careless or hostile user may type.
HOSTILE_VALUES = ["nan", "inf", "-inf", "1e999", "-1", "0", "1e-300", "1e300", "", " ", "x",
                  "1,2", "0,0,0", "nan,0,0", "1e308,1e308,1e308", "0,0,0,0", "9" * 400,
                  "dL1=nan", "dL1=-1", "bogus=1", "mm", "in", "km", "dA*", "none", "tracker",
                  "-0.1,0.1,-0.1,0.1,0.1,0.2", "1,1,1,1,1,1", "é", "auto",
                  "length", "norm", "1000000000"]
#: Tokens inserted into files.
TOKENS = ["nan", "NaN", "inf", "-inf", "1e999", "-1e308", "1e308", "1e-320", "5e-324", "0",
          "-0", "-1", '"', "'", "[", "]", "{", "}", "=", ":", ",", ",,", "\n", "\x00", "\xff",
          "é", "#", "# units: in\n", "# units: km\n", "[mm]", " [in]", "x", "id", "q1", "tool",
          "\t", "\r", "\r\n", "9" * 400, "1" * 5000, "true", "null", "[[legs]]", "[defects]",
          "G2", "G3", "F0", "M30", "%", "1_0", "0x10", "&a", "*a", "!!python/object:x"]


def mutate_text(rng: random.Random, text: str, *, big: bool = True) -> bytes:
    """``text`` with one to four mutations (cell, row, column, token, span, truncation,
    encoding), or binary garbage, an empty file or an oversized field (up to 2 MB, 100 kB
    unless ``big``)."""
    roll = rng.random()
    if roll < 0.04:
        return bytes(rng.randrange(256) for _ in range(rng.randrange(1, 400)))
    if roll < 0.06:
        return b"" if rng.random() < 0.5 else b"\n\n# nothing\n"
    for _ in range(rng.randint(1, 4)):
        text = _mutation(rng, text, big)
    encoding = rng.choice(["utf-8"] * 8 + ["utf-16", "latin-1"])
    return text.encode(encoding, "replace")


def _mutation(rng: random.Random, text: str, big: bool) -> str:
    lines = text.split("\n")
    data = [k for k, line in enumerate(lines) if line and not line.startswith("#")]
    kind = rng.choice(["cell", "cell", "cell", "row-dup", "row-drop", "cells+", "cells-",
                       "header", "token", "span", "truncate", "oversize", "rows+"])
    if kind == "truncate":
        return text[:rng.randrange(len(text) + 1)]
    if kind == "token" or not data:
        at = rng.randrange(len(text) + 1)
        return text[:at] + rng.choice(TOKENS) + text[at:]
    if kind == "span":
        a = rng.randrange(len(text) + 1)
        b = min(len(text), a + rng.randrange(40))
        return text[:a] + (text[a:b] if rng.random() < 0.5 else "") + text[a:]
    k = rng.choice(data)
    sep = "," if "," in lines[k] else ("=" if "=" in lines[k] else " ")
    cells = lines[k].split(sep)
    if kind == "cell":
        i = rng.randrange(len(cells))
        cells[i] = rng.choice([*TOKENS, "", "1e9", "-1e9", "abc", "1,5", "0.0", "T1"])
    elif kind == "cells+":
        cells.insert(rng.randrange(len(cells) + 1), rng.choice(["0", "", "x", "1e3"]))
    elif kind == "cells-" and len(cells) > 1:
        del cells[rng.randrange(len(cells))]
    elif kind == "header":
        cells[rng.randrange(len(cells))] = rng.choice(["x", "id", "q1", "", "X", "x [mm]",
                                                       "x [km]", "tool_length", "z"])
    elif kind == "oversize":
        size = rng.choice([1000, 100000, 2_000_000 if big else 5000])
        cells[rng.randrange(len(cells))] = "7" * size
    elif kind == "row-dup":
        lines.insert(k + 1, lines[k])
        return "\n".join(lines)
    elif kind == "row-drop":
        del lines[k]
        return "\n".join(lines)
    elif kind == "rows+":
        copies = min(2000, 400_000 // (len(lines[k]) + 1))  # not 2000 copies of a 100 kB cell
        lines[k + 1:k + 1] = [lines[k].replace("1", str(j % 10), 1) for j in range(copies)]
        return "\n".join(lines)
    lines[k] = sep.join(cells)
    return "\n".join(lines)


@dataclass(frozen=True)
class Case:
    """One fuzz run: the template, the mutated file's bytes (None: the valid file) and the
    command line's extra options."""

    template: Template
    data: bytes | None
    extra: tuple[str, ...]

    def argv(self, corpus: Path, out: Path, file: Path) -> list[str]:
        """The command line, with the mutated file at ``file``."""
        args = self.template.args.format(f=file, d=corpus, o=out).split()
        return args + list(self.extra)


def draw_case(rng: random.Random, corpus: Path) -> Case:
    """A case: a template, its file mutated (nine draws in ten) and an option given a hostile
    value (one draw in three)."""
    template = rng.choice(TEMPLATES)
    text = (corpus / template.target).read_text(encoding="utf-8")
    data = mutate_text(rng, text) if rng.random() < 0.9 else None
    extra: tuple[str, ...] = ()
    if template.options and rng.random() < 1 / 3:
        option = rng.choice(template.options)
        extra = ((option,) if option in ("--robust", "--identify-frame")
                 else (option, rng.choice(HOSTILE_VALUES)))
    return Case(template, data, extra)


@functools.lru_cache(maxsize=1)
def corpus() -> Path:
    """The valid corpus, written once per process into a temporary directory."""
    from click.testing import CliRunner

    from pkmkit.cli.main import cli

    directory = Path(tempfile.mkdtemp(prefix="pkmkit-fuzz-corpus-"))
    for name, text in CORPUS_TEXT.items():
        (directory / name).write_text(text, encoding="utf-8")
    for name, source in CORPUS_COPIES.items():
        shutil.copyfile(source, directory / name)
    runner = CliRunner()
    for command in CORPUS_COMMANDS:
        result = runner.invoke(cli, command.format(d=directory).split())
        assert result.exit_code == 0, (command, result.output)
    return directory


def classify(exit_code: int | None, output: str, out: Path, template: Template) -> str:
    """``ok`` (exit 0, or 3 with nothing acted on written), ``typed`` (exit 1 or 2 with a
    one-line message, no output left), ``traceback``, ``hang`` (``exit_code`` None) or
    ``partial`` (a failed run left output)."""
    if exit_code is None:
        return "hang"
    if "Traceback" in output or exit_code not in (0, 1, 2, 3):
        return "traceback"
    left = sorted(p.relative_to(out).as_posix() for p in out.rglob("*") if p.is_file())
    if exit_code in (1, 2):
        last = output.strip().splitlines()[-1] if output.strip() else ""
        if not last.startswith("Error:"):
            return "traceback"
        return "partial" if left else "typed"
    if exit_code == 3 and any(name in left for name in template.acted_on):
        return "partial"
    return "ok"
