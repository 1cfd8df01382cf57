"""The closure residual a joint-chain direct model states in its message (mm, like the legs'
misses beside it) is the ``closure_residual`` the result reports in metres, times 1000."""

import re
import warnings

import numpy as np

from pkmkit import machine
from pkmkit.exceptions import StrokeWarning
from pkmkit.status import Status


def test_message_residual_in_mm_is_the_result_residual_in_m():
    m = machine("tripteor-x7")
    q = np.array([m.home_q, m.home_q])
    q[1, :2] = 3.0, 0.3  # no assembly
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", StrokeWarning)
        res = m.fk(q, full_output=True, strokes="ignore")
    assert res.status[0] == Status.OK and res.status[1] == Status.NO_ASSEMBLY
    residual_m = float(res.closure_residual[1])
    assert residual_m > 1e-3
    found = re.search(r"largest closure residual ([\d.e+-]+) mm", res.messages[1])
    assert found, res.messages[1]
    assert float(found.group(1)) == float(f"{residual_m * 1e3:.3g}")
