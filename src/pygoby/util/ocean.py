"""Sea-water formulas shared by the translator algorithms and the netsim channel."""

from __future__ import annotations


def mackenzie_1981(T: float, S: float, D: float) -> float:
    """Sound speed (m/s) by Mackenzie (1981): T deg C, S ppt, D metres.

    Valid for T in [-2, 30], S in [25, 40], D in [0, 8000]; evaluated as is outside them."""
    return (
        1448.96
        + 4.591 * T
        - 5.304e-2 * T**2
        + 2.374e-4 * T**3
        + 1.340 * (S - 35)
        + 1.630e-2 * D
        + 1.675e-7 * D**2
        - 1.025e-2 * T * (S - 35)
        - 7.139e-13 * T * D**3
    )
