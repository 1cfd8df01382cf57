"""The 3-D view's page (``pkmkit view``, the calibration report's view): the page built with
every slider frame through Plotly's validation (``view_figure(...)`` then ``to_html``, the
way before session 35) against :func:`pkmkit.export.view.view_fragment` / ``view_html``
(frames built as the dictionaries the validation makes), in one process, CPU time per page,
best of ``--repeat``; the two pages are checked equal byte for byte first.

    python bench/view_page.py [--repeat 5]
"""

from __future__ import annotations

import argparse
import time

import numpy as np

import pkmkit
from pkmkit.export import view
from pkmkit.plot.calibration_report import REPORT_VIEW_STEPS


def _cpu(fn, repeat: int) -> float:
    best = np.inf
    for _ in range(repeat):
        t = time.process_time()
        fn()
        best = min(best, time.process_time() - t)
    return best


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--repeat", type=int, default=5)
    args = parser.parse_args()
    nominal = pkmkit.machine("linear-delta")
    calibrated = nominal.with_params(R=0.7002, r=0.1499)  # 0.2 mm and 0.1 mm off
    cases = [
        ("calibration report's view (linear-delta, calibrated, "
         f"{REPORT_VIEW_STEPS} steps, fragment)", nominal,
         {"calibrated": calibrated, "steps": REPORT_VIEW_STEPS}, False),
        ("pkmkit view linear-delta (21 steps, page)", nominal, {}, True),
        ("pkmkit view gough-stewart (21 steps, page)", pkmkit.machine("gough-stewart"), {},
         True),
        ("pkmkit view tripteor-x7 (21 steps, page)", pkmkit.machine("tripteor-x7"), {}, True),
    ]
    view.view_html(nominal, steps=3)  # imports, Plotly's templates
    print(f"{'page':<72} {'validated':>10} {'pkmkit':>9} {'ratio':>6}")
    for label, machine, options, full in cases:
        def validated(machine=machine, options=options, full=full):
            fig, _ = view.view_figure(machine, **options)
            return view._page(fig, full_html=full)

        def fast(machine=machine, options=options, full=full):
            page = view.view_html if full else view.view_fragment
            return page(machine, **options)[0]

        if validated() != fast():
            raise SystemExit(f"{label}: the two pages differ")
        a, b = _cpu(validated, args.repeat), _cpu(fast, args.repeat)
        print(f"{label:<72} {a * 1e3:8.0f} ms {b * 1e3:6.0f} ms {a / b:5.1f}x")


if __name__ == "__main__":
    main()
