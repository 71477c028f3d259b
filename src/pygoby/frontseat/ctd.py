"""Sea-water properties a CTD sample lacks, by the UNESCO algorithms goby3 uses.

Sources: Fofonoff & Millard (1983), "Algorithms for computation of fundamental properties of
seawater", UNESCO Tech. Pap. Mar. Sci. 44 (practical salinity PSS-78, Perkin & Lewis 1980; depth,
Saunders & Fofonoff 1976); the one-atmosphere and high-pressure equation of state EOS-80
(Millero & Poisson 1981; Millero et al. 1980; UNESCO Tech. Pap. Mar. Sci. 38); sound speed by
Mackenzie (1981). Temperatures are taken as given (the algorithms are defined on IPTS-68, as in
goby3); pressures are sea (gauge) pressures.

CTDSample units: conductivity S/m, temperature deg C, pressure Pa, density kg/m^3.
"""

from __future__ import annotations

import logging
import math
from typing import Any

from pygoby.util.ocean import mackenzie_1981

PASCAL_PER_DECIBAR = 1.0e4
# C(35, 15 degC, 0) in mS/cm: the conductivity of standard seawater, the PSS-78 reference
STANDARD_CONDUCTIVITY_MS_PER_CM = 42.914
MS_PER_CM_PER_S_PER_M = 10.0

# Mackenzie (1981) validity ranges: temperature (deg C), salinity, depth (m)
MACKENZIE_RANGES = ((-2.0, 30.0), (25.0, 40.0), (0.0, 8000.0))

_log = logging.getLogger(__name__)


def _poly(x: float, coefficients: tuple[float, ...]) -> float:
    """c0 + c1 x + c2 x^2 + ... (Horner)."""
    result = 0.0
    for c in reversed(coefficients):
        result = result * x + c
    return result


# --- PSS-78 ---------------------------------------------------------------------------------

_PSS_A = (0.0080, -0.1692, 25.3851, 14.0941, -7.0261, 2.7081)
_PSS_B = (0.0005, -0.0056, -0.0066, -0.0375, 0.0636, -0.0144)
_PSS_K = 0.0162
_RT35 = (0.6766097, 2.00564e-2, 1.104259e-4, -6.9698e-7, 1.0031e-9)  # rt(T) = C(35,T,0)/C(35,15,0)
_RP_E = (0.0, 2.070e-5, -6.370e-10, 3.989e-15)  # pressure polynomial of Rp
_RP_D = (1.0, 3.426e-2, 4.464e-4)  # temperature polynomial of Rp's denominator
_RP_D3, _RP_D4 = 4.215e-1, -3.107e-3
MIN_CONDUCTIVITY_RATIO = 5e-4  # below it PSS-78 returns 0 (UNESCO 44 zero trap)


def practical_salinity(
    conductivity_ratio: float, temperature: float, pressure_dbar: float
) -> float:
    """PSS-78 salinity from R = C(S,T,p)/C(35,15,0), temperature (deg C) and sea pressure (dbar)."""
    r, t, p = conductivity_ratio, temperature, pressure_dbar
    if r <= MIN_CONDUCTIVITY_RATIO:
        return 0.0
    rp = 1.0 + _poly(p, _RP_E) / (_poly(t, _RP_D) + (_RP_D3 + _RP_D4 * t) * r)
    rt = r / (rp * _poly(t, _RT35))
    root = math.sqrt(abs(rt))
    dt = t - 15.0
    return _poly(root, _PSS_A) + dt / (1.0 + _PSS_K * dt) * _poly(root, _PSS_B)


def conductivity_ratio(conductivity: float) -> float:
    """R of a conductivity in S/m."""
    return conductivity * MS_PER_CM_PER_S_PER_M / STANDARD_CONDUCTIVITY_MS_PER_CM


# --- depth ----------------------------------------------------------------------------------


def depth_from_pressure(pressure_dbar: float, latitude: float) -> float:
    """Depth (m) of a sea pressure (dbar) at a latitude (deg), UNESCO 1983 (standard ocean)."""
    p = pressure_dbar
    x = math.sin(latitude / 57.29578) ** 2
    gravity = 9.780318 * (1.0 + (5.2788e-3 + 2.36e-5 * x) * x) + 1.092e-6 * p
    return _poly(p, (0.0, 9.72659, -2.2512e-5, 2.279e-10, -1.82e-15)) / gravity


# --- EOS-80 ---------------------------------------------------------------------------------

_RHO_W = (999.842594, 6.793952e-2, -9.095290e-3, 1.001685e-4, -1.120083e-6, 6.536332e-9)
_RHO_S = (8.24493e-1, -4.0899e-3, 7.6438e-5, -8.2467e-7, 5.3875e-9)
_RHO_S15 = (-5.72466e-3, 1.0227e-4, -1.6546e-6)
_RHO_S2 = 4.8314e-4
_K_W = (19652.21, 148.4206, -2.327105, 1.360477e-2, -5.155288e-5)
_K_S = (54.6746, -0.603459, 1.09987e-2, -6.1670e-5)
_K_S15 = (7.944e-2, 1.6483e-2, -5.3009e-4)
_A_W = (3.239908, 1.43713e-3, 1.16092e-4, -5.77905e-7)
_A_S = (2.2838e-3, -1.0981e-5, -1.6078e-6)
_A_S15 = 1.91075e-4
_B_W = (8.50935e-5, -6.12293e-6, 5.2787e-8)
_B_S = (-9.9348e-7, 2.0816e-8, 9.1697e-10)


def density_anomaly(salinity: float, temperature: float, pressure_dbar: float) -> float:
    """In-situ density minus 1000 kg/m^3 by EOS-80 (UNESCO 1981): S (PSS-78), T (deg C),
    sea pressure (dbar)."""
    s, t = salinity, temperature
    p = pressure_dbar / 10.0  # the secant bulk modulus is fitted in bars
    s15 = abs(s) ** 1.5
    rho0 = _poly(t, _RHO_W) + _poly(t, _RHO_S) * s + _poly(t, _RHO_S15) * s15 + _RHO_S2 * s * s
    k0 = _poly(t, _K_W) + _poly(t, _K_S) * s + _poly(t, _K_S15) * s15
    a = _poly(t, _A_W) + _poly(t, _A_S) * s + _A_S15 * s15
    b = _poly(t, _B_W) + _poly(t, _B_S) * s
    bulk_modulus = k0 + (a + b * p) * p
    return rho0 / (1.0 - p / bulk_modulus) - 1000.0


# --- sound speed ----------------------------------------------------------------------------


def mackenzie_sound_speed(temperature: float, salinity: float, depth: float) -> float:
    """Mackenzie (1981) sound speed (m/s), NaN outside its validity ranges (T -2..30 deg C,
    S 25..40, depth 0..8000 m; NaN inputs are out of range)."""
    values = (temperature, salinity, depth)
    if all(low <= v <= high for v, (low, high) in zip(values, MACKENZIE_RANGES, strict=True)):
        return mackenzie_1981(temperature, salinity, depth)
    return math.nan


# --- CTDSample ------------------------------------------------------------------------------


def compute_missing_ctd(ctd: Any, log: logging.Logger = _log) -> None:
    """Fill in, in place, what a CTDSample lacks: salinity (PSS-78, from conductivity,
    temperature and pressure), global_fix.depth (from pressure and global_fix.lat), sound speed
    (Mackenzie 1981; NaN out of its ranges) and density (EOS-80 anomaly + 1000 kg/m^3, i.e. the
    in-situ density); the matching *_algorithm fields are set for what was computed. Values
    already present are kept."""
    pressure_dbar = ctd.pressure / PASCAL_PER_DECIBAR
    if not ctd.HasField("salinity"):
        if ctd.HasField("conductivity"):
            ratio = conductivity_ratio(ctd.conductivity)
            ctd.salinity = practical_salinity(ratio, ctd.temperature, pressure_dbar)
            ctd.salinity_algorithm = type(ctd).UNESCO_44_PREKIN_AND_LEWIS_1980
        else:
            log.warning("CTD sample has neither salinity nor conductivity: salinity is NaN")
            ctd.salinity = math.nan
    fix = ctd.global_fix
    if not fix.HasField("depth"):
        fix.depth = depth_from_pressure(pressure_dbar, fix.lat)
    if not ctd.HasField("sound_speed"):
        speed = mackenzie_sound_speed(ctd.temperature, ctd.salinity, fix.depth)
        if math.isnan(speed):
            log.warning(
                "sound speed out of the Mackenzie (1981) range (T %s degC, S %s, depth %s m): NaN",
                ctd.temperature,
                ctd.salinity,
                fix.depth,
            )
        ctd.sound_speed = speed
        ctd.sound_speed_algorithm = type(ctd).MACKENZIE_1981
    if not ctd.HasField("density"):
        anomaly = density_anomaly(ctd.salinity, ctd.temperature, pressure_dbar)
        ctd.density = anomaly + 1000.0
        ctd.density_algorithm = type(ctd).UNESCO_38_MILLERO_AND_POISSON_1981
