"""Design by root finding: the value of one scene parameter at which a run ends where you want it.

For a scalar parameter c over its valid range [lo, hi] and a measure m(c) of the run it gives
(each evaluation builds a new mesh and runs the whole schedule), solve m(c) = D with SciPy's brentq
on the bracket [lo, hi]. The ends are evaluated first: if D lies outside [m(lo), m(hi)] there is no
bracket and the closest end is reported instead. A new mesh per evaluation makes m piecewise smooth
(the mesh changes by jumps with c), which bracketing tolerates; the root is found to xtol in c.

The steering knob inverted: the chamber height cy at which the reference ramp ends at tip
deflection D (cy above the axis curls the beam down, below curls it up).
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field

from scipy.optimize import brentq

from ..errors import require, require_finite


@dataclass
class DesignResult:
    """value: the parameter found (or the closest end); measure: m there; found: whether m(value) = D
    was bracketed; evaluations: (parameter, measure) in the order evaluated; seconds: wall time."""

    value: float
    measure: float
    found: bool
    evaluations: list[tuple[float, float]] = field(default_factory=list)
    seconds: float = 0.0


def solve_design(measure, lo: float, hi: float, wanted: float, xtol: float = 1e-4) -> DesignResult:
    """Solve measure(c) = wanted for c in [lo, hi] (measure: a function of c, e.g. a whole ramp's tip deflection)."""
    require_finite("design target", wanted)
    require(lo < hi, f"design range [{lo:g}, {hi:g}] is empty")
    start, measured = time.perf_counter(), {}

    def evaluate(c: float) -> float:
        if c not in measured:
            measured[float(c)] = float(measure(c))
        return measured[c]

    m_lo, m_hi = evaluate(lo), evaluate(hi)
    found = (m_lo - wanted) * (m_hi - wanted) <= 0
    if found:
        value = float(brentq(lambda c: evaluate(c) - wanted, lo, hi, xtol=xtol))
    else:
        value = lo if abs(m_lo - wanted) < abs(m_hi - wanted) else hi
    return DesignResult(value, evaluate(value), found, list(measured.items()), time.perf_counter() - start)
