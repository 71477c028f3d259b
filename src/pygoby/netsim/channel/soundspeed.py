"""Sound speed in sea water and depth -> pressure.

Units: T in deg C, S in ppt (PSU), D depth in metres (positive down), P in dbar, c in m/s.
TEOS-10 functions take Absolute Salinity SA (g/kg) and Conservative Temperature CT (deg C).
"""

from __future__ import annotations

import math
from collections.abc import Callable

from pygoby.util.extras import needs_extra
from pygoby.util.ocean import mackenzie_1981

SoundSpeedProfile = Callable[[float], float]  # depth (m) -> sound speed (m/s)


def medwin_1975(T: float, S: float, D: float) -> float:
    """Medwin (1975), a simpler near-surface formula."""
    return (
        1449.2 + 4.6 * T - 0.055 * T**2 + 0.00029 * T**3 + (1.34 - 0.010 * T) * (S - 35) + 0.016 * D
    )


def t68_from_t90(T90: float) -> float:
    return 1.00024 * T90


# UNESCO 1983 (Chen & Millero 1977) coefficients, indexed [power of P][power of T].
_CW = (
    (1402.388, 5.03711, -5.80852e-2, 3.3420e-4, -1.47800e-6, 3.1464e-9),
    (0.153563, 6.8982e-4, -8.1788e-6, 1.3621e-7, -6.1185e-10),
    (3.1260e-5, -1.7107e-6, 2.5974e-8, -2.5335e-10, 1.0405e-12),
    (-9.7729e-9, 3.8504e-10, -2.3643e-12),
)
_A = (
    (1.389, -1.262e-2, 7.164e-5, 2.006e-6, -3.21e-8),
    (9.4742e-5, -1.2580e-5, -6.4885e-8, 1.0507e-8, -2.0122e-10),
    (-3.9064e-7, 9.1041e-9, -1.6002e-10, 7.988e-12),
    (1.100e-10, 6.649e-12, -3.389e-13),
)
_B = ((-1.922e-2, -4.42e-5), (7.3637e-5, 1.7945e-7))
_D = (1.727e-3, -7.9836e-6)


def _poly2(coefficients: tuple[tuple[float, ...], ...], T: float, P: float) -> float:
    return sum(
        P**i * sum(c * T**j for j, c in enumerate(row)) for i, row in enumerate(coefficients)
    )


def unesco_1983(S: float, T68: float, P_dbar: float) -> float:
    """UNESCO 1983 / Chen & Millero; T on IPTS-68 (use t68_from_t90 for ITS-90 input)."""
    P = P_dbar / 10.0  # the coefficients are for bar
    return (
        _poly2(_CW, T68, P)
        + _poly2(_A, T68, P) * S
        + _poly2(_B, T68, P) * S**1.5
        + (_D[0] + _D[1] * P) * S**2
    )


def _gsw():
    """The gsw package (numpy-based: loaded only when TEOS-10 is used)."""
    with needs_extra("sim", "TEOS-10 sound speed"):
        import gsw
    return gsw


def teos10(SA: float, CT: float, P_dbar: float) -> float:
    """TEOS-10 (IOC, SCOR & IAPSO 2010) via `gsw.sound_speed`, which uses the 75-term
    specific-volume polynomial of Roquet et al. (2015); P is sea pressure in dbar."""
    return float(_gsw().sound_speed(SA, CT, P_dbar))


def saunders_pressure(depth: float, lat: float) -> float:
    """Saunders (1981): pressure in dbar at `depth` metres and latitude `lat` degrees."""
    c1 = 5.92e-3 + 5.25e-3 * math.sin(math.radians(lat)) ** 2
    return ((1 - c1) - math.sqrt((1 - c1) ** 2 - 8.84e-6 * depth)) / 4.42e-6


def teos10_pressure(depth: float, lat: float) -> float:
    """TEOS-10 `gsw.p_from_z` (dbar) at `depth` metres below the sea surface and latitude `lat`.

    gsw counts height positive up, so z = -depth; the dynamic-height terms are left at zero.
    """
    return float(_gsw().p_from_z(-depth, lat))


def harmonic_mean_speed(profile: SoundSpeedProfile, z1: float, z2: float, steps: int = 16) -> float:
    """Effective speed along a path between depths z1 and z2: (z2 - z1) / integral(dz / c(z)).

    Simpson's rule over `steps` (even) intervals; a level path gives c at that depth.
    """
    if z1 == z2:
        return profile(z1)
    h = (z2 - z1) / steps
    total = 1 / profile(z1) + 1 / profile(z2)
    for i in range(1, steps):
        total += (4 if i % 2 else 2) / profile(z1 + i * h)
    return (z2 - z1) / (total * h / 3)


def teos10_in_situ(T: float, SP: float, depth: float, lat: float, lon: float) -> float:
    """TEOS-10 sound speed from the practical salinity and in-situ temperature a user knows:
    pressure from depth (`gsw.p_from_z`), then Absolute Salinity and Conservative Temperature."""
    gsw = _gsw()
    p = teos10_pressure(depth, lat)
    SA = gsw.SA_from_SP(SP, p, lon, lat)
    return teos10(float(SA), float(gsw.CT_from_t(SA, T, p)), p)


def water_profile(
    formula: str, T: float, S: float, lat: float = 0.0, lon: float = 0.0
) -> SoundSpeedProfile:
    """c(depth) for water of temperature T (deg C, ITS-90) and practical salinity S by the named
    formula: MACKENZIE_1981, MEDWIN_1975, UNESCO_1983 or TEOS_10 (the last two need the
    latitude for pressure; TEOS-10 also the longitude for Absolute Salinity)."""
    if formula == "MACKENZIE_1981":
        return lambda depth: mackenzie_1981(T, S, depth)
    if formula == "MEDWIN_1975":
        return lambda depth: medwin_1975(T, S, depth)
    if formula == "UNESCO_1983":
        T68 = t68_from_t90(T)
        return lambda depth: unesco_1983(S, T68, saunders_pressure(depth, lat))
    if formula == "TEOS_10":
        return lambda depth: teos10_in_situ(T, S, depth, lat, lon)
    raise ValueError(f"unknown sound speed formula {formula!r}")
