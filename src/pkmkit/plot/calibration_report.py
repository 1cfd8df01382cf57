"""Outputs of a calibration: the calibrated machine file, the JSON summary, the residual table,
the figures and one self-contained ``report.html`` (figures embedded as PNG data) that a person
reads to judge the calibration.

:func:`write_calibration_outputs` builds every file in memory first and then writes each one
atomically, so that an error leaves no half-written output.
"""

from __future__ import annotations

import base64
import html
import io
import json
from pathlib import Path
from typing import Any

import numpy as np

from pkmkit import __version__
from pkmkit.io.atomic import write_files_atomic
from pkmkit.io.json_io import to_jsonable
from pkmkit.io.machine_defects import machine_text_with_defects
from pkmkit.model.parameters import length_scale
from pkmkit.plot.gravity_section import gravity_html, gravity_json

FIGURES = ("residuals", "histograms", "parameters", "identifiability", "maps")
#: Rows listed in the report's "worst observations" table.
WORST_ROWS = 10


def figure_pngs(result, *, units: str = "mm", workspace: dict | None = None
                ) -> dict[str, bytes]:
    """The report's figures as PNG bytes, by name (``workspace``: the uncertainty over the
    workspace, :meth:`~pkmkit.calibration.results.CalibrationResult.workspace_uncertainty`,
    drawn in the maps)."""
    from pkmkit.plot.calibration_figures import (
        plot_error_maps,
        plot_histograms,
        plot_identifiability,
        plot_parameters,
        plot_residuals,
    )

    out = {}
    for name, func in (("residuals", plot_residuals), ("histograms", plot_histograms),
                       ("parameters", plot_parameters),
                       ("identifiability", plot_identifiability), ("maps", plot_error_maps)):
        if name == "maps" and result.tool_points is None and workspace is None:
            continue
        fig = (func(result) if name == "identifiability" else
               func(result, units=units, workspace=workspace) if name == "maps" else
               func(result, units=units))
        buf = io.BytesIO()
        fig.savefig(buf, format="png", dpi=100)
        out[name] = buf.getvalue()
    return out


def _num(v: float, digits: int = 4) -> str:
    if v is None or not np.isfinite(v):
        return "—"
    return f"{v:.{digits}g}"


def _table(header: list[str], rows: list[list[str]], cls: str = "") -> str:
    head = "".join(f"<th>{html.escape(h)}</th>" for h in header)
    body = "".join("<tr>" + "".join(f"<td>{c}</td>" for c in row) + "</tr>" for row in rows)
    return f'<table class="{cls}"><thead><tr>{head}</tr></thead><tbody>{body}</tbody></table>'


def report_html(result, *, units: str = "mm", figures: dict[str, bytes] | None = None,
                sources: dict[str, str] | None = None, title: str | None = None,
                workspace: dict | None = None, gravity: dict | None = None,
                view: bool = False) -> str:
    """The HTML report of a :class:`~pkmkit.calibration.identify.CalibrationResult`.

    Args:
        result: the calibration.
        units: length unit of the numbers shown.
        figures: PNGs by name (default: :func:`figure_pngs`).
        sources: labels → file names shown in the header (measurements, validation, …).
        title: page title.
        workspace: the tool-point uncertainty over the workspace (default: computed,
            :meth:`~pkmkit.calibration.results.CalibrationResult.workspace_uncertainty`).
        gravity: the gravity deflection at the measured configurations
            (:func:`pkmkit.calibration.gravity.gravity_beside_residual`), or None.
        view: embed the 3-D view of the machine with the tool error the calibration corrects
            as vectors (``pkmkit view --calibration``; the page grows by the Plotly library,
            ~4.7 MB, and stays self-contained).
    """
    workspace = result.workspace_uncertainty() if workspace is None else workspace
    figures = (figure_pngs(result, units=units, workspace=workspace) if figures is None
               else figures)
    scale = length_scale(units)
    data = result.to_json(units)
    title = title or f"Calibration of {result.nominal.name}"
    parts = _header_parts(result, units, sources, title)
    parts += _summary_parts(result, data, scale, units, workspace)
    parts += _residual_parts(result, figures, scale, units, gravity)
    parts += _parameter_parts(result, data, figures, scale, units)
    parts += _identifiability_parts(result, figures, scale, units)
    if view:
        parts.append(_view_section(result, units))
    return ("<!DOCTYPE html>\n<html lang='en'><head><meta charset='utf-8'>"
            f"<title>{html.escape(title)}</title><style>{_STYLE}</style></head><body>\n"
            + "\n".join(parts) + "\n</body></html>\n")


_STYLE = ("body{font-family:sans-serif;max-width:980px;margin:1.5em auto;color:#222}"
          "table{border-collapse:collapse;margin:0.6em 0;font-size:0.9em}"
          "td,th{border:1px solid #bbb;padding:2px 8px;text-align:right}"
          "td:first-child,th:first-child{text-align:left}"
          "table.unidentifiable td{text-align:left}"
          ".meta{color:#555;font-size:0.85em}.summary{background:#f4f4f4;padding:0.6em}"
          ".verdict{padding:0.6em;margin:0.8em 0}.verdict.passed{background:#eef5ee;"
          "border-left:6px solid #4a4}.verdict.failed{background:#fbeaea;border-left:6px "
          "solid #c22}.verdict h2{margin:0 0 0.3em 0}"
          "figure{margin:1em 0}img{max-width:100%}"
          "figcaption{font-size:0.85em;color:#555}")


def _header_parts(result, units: str, sources: dict[str, str] | None, title: str) -> list[str]:
    """The title, the verdict (when judged) and the metadata lines."""
    esc = html.escape
    parts = [f"<h1>{esc(title)}</h1>",
             f"<p class='meta'>pkmkit {esc(__version__)} · machine <b>{esc(result.nominal.id)}"
             f"</b> · measurement <b>{esc(result.kind)}</b> · lengths in {esc(units)}, angles "
             "in degrees, direction components dimensionless (≈ rad)</p>"]
    if sources:
        parts.append("<p class='meta'>" + " · ".join(
            f"{esc(k)}: <code>{esc(str(v))}</code>"
            + (f" (sha256 {esc(_sha256(v)[:16])}…)" if _sha256(v) else "")
            for k, v in sources.items()) + "</p>")
    parts.append(f"<p class='meta'>calibrated {esc(_now())}</p>")
    if result.verdict is not None:
        parts.insert(1, _verdict_html(result.verdict))
    return parts


def _summary_sentence(result, scale: float, units: str) -> str:
    """The RMS before → after, validation and a-posteriori noise in one paragraph."""
    esc = html.escape
    val = result.validation
    gain = result.before.rms / result.after.rms if result.after.rms > 0 else float("inf")
    verdict = (f"The identified machine reduces the RMS error of the {result.after.per_pose.size}"
               f" identification observations from {_num(result.before.rms / scale)} to "
               f"{_num(result.after.rms / scale)} {esc(units)} (× {_num(gain, 3)})")
    if val is not None:
        verdict += (f"; on the {val.after.per_pose.size} held-out validation observations from "
                    f"{_num(val.before.rms / scale)} to {_num(val.after.rms / scale)} "
                    f"{esc(units)}")
    verdict += (f". The a-posteriori noise is {_num(result.sigma_posterior / scale)} {esc(units)}"
                f" against {_num(result.sigma / scale)} {esc(units)} assumed"
                + ("." if result.verdict is not None else  # the verdict above judges it
                   " — the model explains the data to the noise level." if
                   result.sigma_posterior < 1.5 * result.sigma else
                   " — larger than assumed: unmodelled errors or outliers remain."))
    return f"<p class='summary'>{verdict}</p>"


def _summary_parts(result, data: dict, scale: float, units: str,
                   workspace: dict | None) -> list[str]:
    """The summary paragraph, the summary table and the parameter counts."""
    esc = html.escape
    val = result.validation
    summary = [
        ["observations (identification)", str(result.after.per_pose.size)],
        ["observations (validation)", str(val.after.per_pose.size) if val else "—"],
        ["candidate machine parameters", str(result.candidates)],
        ["identified parameters (machine + set-up)",
         f"{len(result.names)} + {len(result.setup_names)} (rank {result.rank})"],
        ["condition number (whitened, tolerance-scaled)", _num(result.condition, 4)],
        ["σ assumed / a posteriori", f"{_num(result.sigma / scale)} / "
                                     f"{_num(result.sigma_posterior / scale)} {esc(units)}"],
        ["iterations, time", f"{result.iterations}, {result.seconds:.3f} s"],
    ]
    if data.get("correlation_max"):
        cm = data["correlation_max"]
        summary.append(["largest correlation", f"{esc(cm['pair'][0])} / {esc(cm['pair'][1])}: "
                                               f"{cm['value']:+.3f}"])
    summary += _uncertainty_rows(result, scale, units, workspace)
    parts = [_summary_sentence(result, scale, units),
             "<h2>Summary</h2>" + _table(["", ""], summary, "summary")]
    if result.counts:
        c = result.counts
        parts.append("<h3>Parameter counts</h3>" + _table(
            ["candidates", "compatible", "identified", "gauges", "weak", "no effect",
             "combinations"],
            [[str(c.get(k, "—")) for k in ("candidates", "compatible", "identified", "gauges",
                                           "weak", "no_effect", "combinations")]], "counts"))
    return parts


def _uncertainty_rows(result, scale: float, units: str,
                      workspace: dict | None) -> list[list[str]]:
    """Summary rows of the tool-point uncertainty (k = 2), measured and over the workspace."""
    rows = []
    if result.tool_uncertainty is not None and result.tool_uncertainty.size:
        u = result.tool_uncertainty / scale
        rows.append(["tool-point uncertainty (k = 2) at the measured configurations"
                     + (", free rigid motion removed" if
                        result.tool_uncertainty_rigid_removed else ""),
                     f"RMS {_num(float(np.sqrt(np.mean(u**2))))}, max "
                     f"{_num(float(np.max(u)))} {html.escape(units)}"])
    if workspace is not None:
        u = np.asarray(workspace["uncertainty"]) / scale
        rows.append([f"tool-point uncertainty (k = 2) over the workspace "
                     f"({u.size} configurations)",
                     f"RMS {_num(float(np.sqrt(np.mean(u**2))))}, max "
                     f"{_num(float(np.max(u)))} {html.escape(units)}"])
    return rows


def _residual_stats(summary, scale: float) -> list[str]:
    """Mean, RMS and max before and after of one set (identification or validation)."""
    return [_num(summary.before.mean / scale), _num(summary.before.rms / scale),
            _num(summary.before.max / scale), _num(summary.after.mean / scale),
            _num(summary.after.rms / scale), _num(summary.after.max / scale)]


def _residual_parts(result, figures: dict, scale: float, units: str,
                    gravity: dict | None) -> list[str]:
    """Residual statistics, the gravity deflection beside them, per axis, the worst rows and
    the residual figures."""
    stats = [["identification", *_residual_stats(result, scale)]]
    if result.validation is not None:
        stats.append(["validation", *_residual_stats(result.validation, scale)])
    parts = [f"<h2>Residuals [{html.escape(units)}]</h2>" + _table(
        ["set", "mean before", "RMS before", "max before", "mean after", "RMS after",
         "max after"], stats, "stats")]
    parts.append("<p>Error of one observation: the distance between the measured and the "
                 "predicted tool point (point and pose measurements), the bar-length error "
                 "(ball-bar), the height error (probe) or the joint-space distance to the "
                 "commanded path (machined part). <i>Before</i>: the nominal machine with the "
                 "set-up parameters fitted alone; <i>after</i>: the identified machine.</p>")
    if gravity is not None:
        parts.append(gravity_html(gravity, scale, units))
    axes = _axis_rows(result, scale)
    if axes:
        parts.append("<h3>Residuals per axis (RMS)</h3>" + _table(
            ["axis", "unit", "before", "after", "max |after|"], axes, "axes"))
    parts.append(_worst_rows(result, scale, units))
    for name, caption in _residual_captions(result):
        if name in figures:
            parts.append(_figure(figures[name], caption, name))
    return parts


def _residual_captions(result) -> tuple[tuple[str, str], ...]:
    """(figure name, caption) of the residual figures, in page order."""
    return (("residuals", "Error of each observation (log scale)"),
            ("histograms", "Distribution of the errors"),
            ("maps", "Over the workspace (seen from above): error before and "
                     "after at the measured configurations, and the identified "
                     "machine's tool-point uncertainty (k = 2) from the "
                     "joint covariance of the machine and set-up parameters"
                     " there and at configurations drawn over the machine's "
                     "workspace"
                     + ("; the rigid motion the set-up absorbs (frame, "
                        "pivots, bed, part placement) is removed, as the "
                        "workpiece set-up "
                        "does" if result.tool_uncertainty_rigid_removed
                        else "")))


def _parameter_rows(result, data: dict, scale: float) -> list[list[str]]:
    """One row per identified machine parameter: value, σ, unit, tolerance, |value|/σ."""
    esc = html.escape
    rows = []
    for i, n in enumerate(result.names):
        unit = data["parameter_units"][n]
        v, s = data["parameters"][n], data["std"][n]
        tol = result.tolerance[i] if result.tolerance is not None else np.nan
        tol_out = (tol / scale if result.units[i] == "m" else
                   np.degrees(tol) if result.units[i] == "rad" else tol)
        ratio = abs(v) / s if s > 0 else float("nan")
        rows.append([f"<code>{esc(n)}</code>", _num(v, 5), _num(s, 3), esc(unit),
                     _num(tol_out, 3), _num(ratio, 3)])
    return rows


def _parameter_parts(result, data: dict, figures: dict, scale: float,
                     units: str) -> list[str]:
    """The identified machine parameters, the set-up parameters and the measurement frame."""
    esc = html.escape
    parts = [f"<h2>Identified machine parameters ({len(result.names)})</h2>",
             _table(["parameter", "value", "std (1σ)", "unit", "tolerance", "|value|/σ"],
                    _parameter_rows(result, data, scale), "params")]
    if "parameters" in figures:
        parts.append(_figure(figures["parameters"], "Identified parameters ± 2σ", "parameters"))
    if result.setup_names:
        rows = [[f"<code>{esc(n)}</code>", _num(data["setup"][n], 7),
                 _num(data["setup_std"][n], 3),
                 esc(units if u == "m" else ("deg" if u == "rad" else "1"))]
                for n, u in zip(result.setup_names, result.setup_units, strict=True)]
        parts.append("<h2>Set-up parameters</h2>" + _table(["parameter", "value", "std", "unit"],
                                                           rows, "setup"))
    if "frame" in data:
        fr = data["frame"]
        parts.append("<h3>Measurement frame → machine frame</h3>"
                     f"<p>rotation vector {esc(_vec(fr['rotation_vector_deg']))} deg, "
                     f"translation {esc(_vec(fr['translation']))} {esc(units)}</p>")
    return parts


def _identifiability_parts(result, figures: dict, scale: float, units: str) -> list[str]:
    """The identifiability section (singular values, parameters left nominal) and outliers."""
    esc = html.escape
    parts = ["<h2>Identifiability</h2>",
             f"<p>{result.rank} parameters identified out of {result.candidates} "
             "candidates. The singular values below are those of the identified problem "
             "with each column scaled by its tolerance and each row divided by its noise σ: "
             "a value of 1 means that a tolerance-sized change of that combination moves "
             "the readings by one σ.</p>"]
    if "identifiability" in figures:
        parts.append(_figure(figures["identifiability"], "Singular values and correlations",
                             "identifiability"))
    rows = [[f"<code>{esc(n)}</code>", esc(r)] for n, r in sorted(result.unidentifiable.items())]
    parts.append(f"<h3>Parameters left at their nominal value ({len(rows)})</h3>")
    parts.append(_table(["parameter", "why"], rows, "unidentifiable") if rows else
                 "<p>None.</p>")
    if result.outliers:
        rows = [[esc(lab), _num(err / scale), _num(w, 3)] for lab, err, w in result.outliers]
        parts.append(f"<h2>Outliers ({len(rows)})</h2><p>Observations beyond 3 robust standard "
                     "deviations, down-weighted by the robust loss.</p>"
                     + _table(["row", f"error [{units}]", "weight"], rows, "outliers"))
    return parts

def _view_section(result, units: str) -> str:
    """The report's 3-D view: the nominal machine with one slider per actuator and the tool
    error of the identified machine against it as vectors over the workspace."""
    from pkmkit.exceptions import PkmError
    from pkmkit.export.view import view_fragment

    head = ("<h2 id='view'>3-D view</h2><p>The machine drawn from its geometry, a slider per "
            "actuator moving it through pkmkit's model; the arrows are the tool error the "
            "calibration corrects (identified machine − nominal, magnified) over the middle "
            "of the workspace.</p>")
    try:
        fragment, content = view_fragment(result.nominal, calibrated=result.machine,
                                          steps=REPORT_VIEW_STEPS,
                                          rigid_free=result.tool_uncertainty_rigid_removed)
    except PkmError as exc:
        return head + f"<p class='meta'>Not drawn: {html.escape(str(exc))}</p>"
    return head + fragment + f"<p class='meta'>{_view_note(result, content, units)}</p>"


def _view_note(result, content, units: str) -> str:
    """The view's figures judged: the largest tool error shown (with the free rigid motion
    removed when the set-up absorbs one, the size of that gauge motion stated) against the
    verdict's bound on a plausible error (:data:`~pkmkit.calibration.verdict.SIZE_FRACTION`
    of the machine's size) and the largest error measured."""
    from pkmkit.calibration.divergence import machine_size
    from pkmkit.calibration.verdict import SIZE_FRACTION

    s = length_scale(units)
    u = html.escape(units)
    note = f"{content.error_vectors} vectors."
    if content.error_max is None:
        return note
    note += f" Largest tool error shown: {_num(content.error_max / s)} {u}"
    if content.error_max_with_rigid is not None:
        note += (f" (the best rigid motion of the vectors removed, as the set-up removes it: "
                 f"with it {_num(content.error_max_with_rigid / s)} {u}, a motion these "
                 "measurements do not see)")
    note += "."
    bound = SIZE_FRACTION * machine_size(result.nominal)
    measured = result.before.max
    if content.error_max > bound:
        note += (f" <b>Beyond a plausible error</b> ({_num(bound / s)} {u}, the verdict's "
                 "bound): the identified machine is not a built machine's geometry there.")
    elif np.isfinite(measured) and content.error_max > 3 * measured:
        note += (f" <b>More than 3× the largest error measured</b> ({_num(measured / s)} {u}): "
                 "the identified machine extrapolates beyond the measured configurations "
                 "(see the tool-point uncertainty over the workspace).")
    return note


#: Slider positions per actuator in the report's 3-D view (fewer than ``pkmkit view``'s: the
#: report is written by every calibration).
REPORT_VIEW_STEPS = 11


def _verdict_html(verdict) -> str:
    """The verdict block (green or red) at the top of the report."""
    esc = html.escape
    cls = "passed" if verdict.passed else "failed"
    title = ("Verdict: passed" if verdict.passed else
             "Verdict: FAILED — do not use this calibration")
    items = []
    for c in verdict.checks:
        mark = "✗" if not c.passed else ("!" if c.warning else "✓")
        items.append(f"<li>{mark} <b>{esc(c.name)}</b>: {esc(c.reason)}</li>")
    causes = "".join(f"<li><b>{esc(c.cause)}</b>: {esc(c.message)}</li>"
                     for c in verdict.causes)
    out = (f"<div class='verdict {cls}' id='verdict'><h2>{esc(title)}</h2><ul>"
           + "".join(items) + "</ul>")
    if causes:
        out += f"<p>Likely cause:</p><ul>{causes}</ul>"
    if any(c.name == "convergence" for c in verdict.failed):
        out += ("<p>The identification did not converge: no calibrated machine file is "
                "written (not even with --write-anyway; the exit status is 3).</p>")
    elif not verdict.passed:
        out += ("<p>No calibrated machine file is written for a failed verdict (pkmkit "
                "calibrate --write-anyway writes it; the exit status is 3 either way).</p>")
    return out + "</div>"


#: Names of the residual rows of each measurement type (pose rotations in degrees).
AXES = {"point": ("x", "y", "z"), "pose": ("x", "y", "z", "rx", "ry", "rz"),
        "ballbar": ("length",), "height": ("z",)}


def _axis_rows(result, scale: float) -> list[list[str]]:
    if result.residuals is None or result.residuals_before is None:
        return []
    before, after = np.asarray(result.residuals_before), np.asarray(result.residuals)
    names = AXES.get(result.kind) or tuple(result.nominal.actuator_names)
    rows = []
    for k, name in enumerate(names[:after.shape[1]]):
        angle = result.kind == "pose" and k >= 3
        f = np.degrees(1.0) if angle else 1.0 / scale
        unit = "deg" if angle else ""
        rows.append([esc_code(name), unit or "length",
                     _num(float(np.sqrt(np.mean(before[:, k] ** 2))) * f),
                     _num(float(np.sqrt(np.mean(after[:, k] ** 2))) * f),
                     _num(float(np.max(np.abs(after[:, k]))) * f)])
    return rows


def esc_code(text: str) -> str:
    return f"<code>{html.escape(text)}</code>"


def _worst_rows(result, scale: float, units: str) -> str:
    err = result.after.per_pose
    if err.size == 0:
        return ""
    order = np.argsort(-err)[:WORST_ROWS]
    rows = [[html.escape(result.after.labels[i]), _num(result.before.per_pose[i] / scale),
             _num(err[i] / scale)] for i in order]
    return (f"<h3>Worst observations after identification ({len(rows)})</h3>"
            + _table(["row (file:line)", f"before [{units}]", f"after [{units}]"], rows,
                     "worst"))


def _vec(values) -> str:
    return "(" + ", ".join(f"{v:.6g}" for v in values) + ")"


def _figure(png: bytes, caption: str, name: str) -> str:
    data = base64.b64encode(png).decode("ascii")
    return (f"<figure id='fig-{name}'><img alt='{html.escape(caption)}' "
            f"src='data:image/png;base64,{data}'><figcaption>{html.escape(caption)}"
            "</figcaption></figure>")


def residuals_csv(result, *, units: str = "mm") -> str:
    """Per-observation errors before and after (and the robust weights)."""
    scale = length_scale(units)
    lines = [f"# units: {units}", "row,set,before,after,weight"]
    w = result.weights if result.weights is not None else np.ones(result.after.per_pose.size)
    for lab, b, a, wi in zip(result.after.labels, result.before.per_pose, result.after.per_pose,
                             w, strict=True):
        lines.append(f"{_csv_cell(lab)},identification,{b / scale:.9g},{a / scale:.9g},"
                     f"{wi:.6g}")
    if result.validation is not None:
        v = result.validation
        for lab, b, a in zip(v.after.labels, v.before.per_pose, v.after.per_pose, strict=True):
            lines.append(f"{_csv_cell(lab)},validation,{b / scale:.9g},{a / scale:.9g},1")
    return "\n".join(lines) + "\n"


def _csv_cell(text: str) -> str:
    return '"' + text.replace('"', '""') + '"' if ("," in text or '"' in text) else text


def _sha256(path) -> str:
    """SHA-256 of a file's bytes ('' when it cannot be read)."""
    import hashlib

    try:
        return hashlib.sha256(Path(path).read_bytes()).hexdigest()
    except OSError:
        return ""


def _now() -> str:
    from datetime import UTC, datetime

    return datetime.now(UTC).strftime("%Y-%m-%d %H:%M:%S UTC")


def metadata(result, sources: dict[str, str] | None) -> dict[str, Any]:
    """Machine, files with their SHA-256, date and pkmkit version of a calibration."""
    return {"machine": result.nominal.id, "pkmkit": __version__, "date": _now(),
            "files": {k: {"path": str(v), "sha256": _sha256(v)}
                      for k, v in (sources or {}).items()}}


def write_calibration_outputs(result, out_dir: str | Path, *, machine_source: str | Path,
                              units: str = "mm", sources: dict[str, str] | None = None,
                              machine_file: bool = True, measurements=None,
                              view: bool = True) -> dict[str, str]:
    """Write the calibrated machine file (unless ``machine_file`` is False: a failed
    verdict), ``calibration.json``, ``residuals.csv``, the figures and ``report.html`` into
    ``out_dir`` (created if needed). Returns name → path. With the ``measurements``
    (a :class:`~pkmkit.model.measurement_set.MeasurementSet`), the gravity deflection predicted
    at their configurations is shown beside the residual
    (:func:`pkmkit.calibration.gravity.gravity_beside_residual`; JSON key ``gravity``).
    ``view``: embed the 3-D view in the report (:func:`report_html`).

    Everything is rendered in memory first; each file is then written atomically.
    """
    out = Path(out_dir)
    suffix = Path(machine_source).suffix or ".toml"
    machine_name = f"{result.nominal.id}-calibrated{suffix}"
    note = (f"identified by pkmkit {__version__} calibrate from {result.kind} measurements: "
            f"RMS {result.before.rms / length_scale(units):.6g} -> "
            f"{result.after.rms / length_scale(units):.6g} {units}")
    if result.verdict is not None and not result.verdict.passed:
        note += (" -- VERDICT FAILED (" + ", ".join(c.name for c in result.verdict.failed)
                 + "), written on request (--write-anyway): see report.html")
    texts = {}
    if machine_file:
        texts[machine_name] = machine_text_with_defects(machine_source, result.nominal,
                                                        result.defects, note=note)
    payload = result.to_json(units)
    payload["metadata"] = metadata(result, sources)
    workspace = result.workspace_uncertainty()
    if workspace is not None and payload.get("tool_uncertainty_k2") is not None:
        u = np.asarray(workspace["uncertainty"]) / length_scale(units)
        payload["tool_uncertainty_k2"]["workspace"] = {
            "configurations": int(u.size), "rms": float(np.sqrt(np.mean(u**2))),
            "max": float(np.max(u))}
    payload["files"] = {"machine": machine_name if machine_file else None,
                        "report": "report.html"}
    from pkmkit.calibration.gravity import gravity_beside_residual

    gravity = gravity_beside_residual(result, measurements)
    if gravity is not None:
        payload["gravity"] = gravity_json(gravity, length_scale(units))
    texts["calibration.json"] = json.dumps(to_jsonable(payload), indent=2) + "\n"
    texts["residuals.csv"] = residuals_csv(result, units=units)
    figures = figure_pngs(result, units=units, workspace=workspace)
    texts["report.html"] = report_html(result, units=units, figures=figures, sources=sources,
                                       workspace=workspace, gravity=gravity, view=view)
    try:
        out.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        from pkmkit.exceptions import InputError

        raise InputError(f"cannot create {out}: {exc.strerror or exc}") from None
    files: dict[Path, bytes | str] = {out / f"{name}.png": png for name, png in figures.items()}
    files.update({out / name: text for name, text in texts.items()})
    write_files_atomic(files)  # all or none: a failure leaves no machine file without its report
    written = {path.name: str(path) for path in files}
    stale = out / machine_name
    if not machine_file and stale.exists():  # an earlier run's file must not pass for this one
        stale.unlink()
        written["removed"] = str(stale)
    return written


def summary_for_json(result, units: str) -> dict[str, Any]:
    """The JSON summary (as written to ``calibration.json``)."""
    return to_jsonable(result.to_json(units))
