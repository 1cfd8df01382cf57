"""Screenshots of docs/export.md's 3-D view: ``python docs/make_view_figures.py``.

Writes the hexapod's view (``pkmkit view gough-stewart --workspace``) and opens it in headless
Chromium at the last position of q1's slider (``view.html#q1:20``), as the page's own address
does; saves ``docs/figures/view-gough-stewart.png``. Needs ``chromium`` on the PATH.
"""

from __future__ import annotations

import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

import pkmkit
from pkmkit.export.view import view_html

FIGURES = Path(__file__).parent / "figures"


def main() -> int:
    browser = shutil.which("chromium") or shutil.which("chromium-browser")
    if browser is None:
        print("chromium is not installed", file=sys.stderr)
        return 1
    html, _ = view_html(pkmkit.machine("gough-stewart"), workspace=True)
    with tempfile.TemporaryDirectory() as tmp:
        page = Path(tmp) / "view.html"
        page.write_text(html, encoding="utf-8")
        target = FIGURES / "view-gough-stewart.png"
        subprocess.run([browser, "--headless", "--no-sandbox", "--disable-gpu",
                        "--virtual-time-budget=8000", "--window-size=1000,900",
                        f"--screenshot={target}", f"file://{page}#q1:20"],
                       check=True, capture_output=True, timeout=180)
    print(f"wrote {target}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
