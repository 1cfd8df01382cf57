"""Conversion of results to JSON-compatible values."""

from __future__ import annotations

import math
from typing import Any

import numpy as np


def to_jsonable(value: Any) -> Any:
    """Nested lists/dicts of plain Python values; NaN and ±inf become ``None`` (JSON null), and
    −0.0 becomes 0.0."""
    if isinstance(value, dict):
        return {str(k): to_jsonable(v) for k, v in value.items()}
    if isinstance(value, list | tuple):
        return [to_jsonable(v) for v in value]
    if isinstance(value, np.ndarray):
        return to_jsonable(value.tolist())
    if isinstance(value, np.generic):
        return to_jsonable(value.item())
    if isinstance(value, float):
        return value + 0.0 if math.isfinite(value) else None
    return value
