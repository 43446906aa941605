"""One JSON-ready conversion for results: numpy arrays and scalars, complex numbers, non-finite floats."""

from __future__ import annotations

import math

import numpy as np


def plain(obj: object, *, nonfinite_as_string: bool = False) -> object:
    """JSON-ready copy of ``obj``: arrays → lists, complex → ``[re, im]``, numpy scalars → Python.

    Non-finite floats become ``None`` (JSON ``null``), or their ``str`` (``"inf"``, ``"nan"``) with
    ``nonfinite_as_string=True`` where an infinite value carries meaning (e.g. a gain margin of ∞).
    """
    def rec(o: object) -> object:
        if isinstance(o, dict):
            return {str(k): rec(v) for k, v in o.items()}
        if isinstance(o, list | tuple):
            return [rec(v) for v in o]
        if isinstance(o, np.ndarray):
            return rec(o.tolist())
        if isinstance(o, complex | np.complexfloating):
            return [rec(float(o.real)), rec(float(o.imag))]
        if isinstance(o, bool | np.bool_):
            return bool(o)
        if isinstance(o, np.integer):
            return int(o)
        if isinstance(o, float | np.floating):
            f = float(o)
            if math.isfinite(f):
                return f
            return str(f) if nonfinite_as_string else None
        return o

    return rec(obj)
