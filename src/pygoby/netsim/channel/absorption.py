"""Absorption of sound in sea water, alpha in dB/km with f in kHz."""

from __future__ import annotations

import math


def thorp(f_khz: float) -> float:
    """Thorp, in the form used by Stojanovic 2007, ns-3 and DESERT."""
    f2 = f_khz * f_khz
    if f_khz >= 0.4:
        return 0.11 * f2 / (1 + f2) + 44 * f2 / (4100 + f2) + 2.75e-4 * f2 + 0.003
    return 0.002 + 0.11 * f2 / (1 + f2) + 0.011 * f2


def thorp_coa(f_khz: float) -> float:
    """Thorp, in the form of Jensen et al., "Computational Ocean Acoustics" (one branch).

    A different published fit from `thorp` (6.12073 against 6.10481 dB/km at 25 kHz): pick one.
    """
    f2 = f_khz * f_khz
    return 3.3e-3 + 0.11 * f2 / (1 + f2) + 44 * f2 / (4100 + f2) + 3.0e-4 * f2


def francois_garrison(f_khz: float, T: float, S: float, D: float, pH: float = 8.0) -> float:
    """Francois & Garrison (1982): boric acid + magnesium sulphate + pure water terms."""
    f2 = f_khz * f_khz
    c = 1412 + 3.21 * T + 1.19 * S + 0.0167 * D
    a1 = 8.86 / c * 10 ** (0.78 * pH - 5)
    f1 = 2.8 * math.sqrt(S / 35) * 10 ** (4 - 1245 / (T + 273))
    a2 = 21.44 * S / c * (1 + 0.025 * T)
    p2 = 1 - 1.37e-4 * D + 6.2e-9 * D * D
    f2_relax = 8.17 * 10 ** (8 - 1990 / (T + 273)) / (1 + 0.0018 * (S - 35))
    if T < 20:
        a3 = 4.937e-4 - 2.59e-5 * T + 9.11e-7 * T**2 - 1.5e-8 * T**3
    else:
        a3 = 3.964e-4 - 1.146e-5 * T + 1.45e-7 * T**2 - 6.5e-10 * T**3
    p3 = 1 - 3.83e-5 * D + 4.9e-10 * D * D
    boric = a1 * f1 * f2 / (f1 * f1 + f2)
    magnesium = a2 * p2 * f2_relax * f2 / (f2_relax * f2_relax + f2)
    return boric + magnesium + a3 * p3 * f2
