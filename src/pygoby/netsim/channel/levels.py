"""Transmission loss, ambient noise (Stojanovic 2007) and the SNR / SINR budget.

Levels in dB re 1 uPa (source level at 1 m); noise spectral density in dB re 1 uPa^2/Hz;
f in kHz, r in metres, alpha in dB/km.
"""

from __future__ import annotations

import math
from collections.abc import Iterable
from dataclasses import dataclass


def transmission_loss(r_m: float, alpha_db_per_km: float, k: float = 1.5) -> float:
    """TL = k * 10 log10(r / 1 m) + alpha * r / 1000 (k: 1 cylindrical, 1.5, 2 spherical)."""
    return k * 10 * math.log10(max(r_m, 1.0)) + alpha_db_per_km * r_m / 1000


@dataclass(frozen=True)
class NoiseComponents:
    """The four Stojanovic/Coates terms at one frequency, dB re 1 uPa^2/Hz."""

    turbulence: float
    shipping: float
    wind: float
    thermal: float

    @property
    def total(self) -> float:
        return power_sum_db((self.turbulence, self.shipping, self.wind, self.thermal))


def stojanovic_noise(f_khz: float, shipping: float = 0.5, wind: float = 5.0) -> NoiseComponents:
    """Ambient noise PSD components; shipping activity in [0, 1], wind speed in m/s."""
    log_f = math.log10(f_khz)
    return NoiseComponents(
        turbulence=17 - 30 * log_f,
        shipping=40 + 20 * (shipping - 0.5) + 26 * log_f - 60 * math.log10(f_khz + 0.03),
        wind=50 + 7.5 * math.sqrt(wind) + 20 * log_f - 40 * math.log10(f_khz + 0.4),
        thermal=-15 + 20 * log_f,
    )


def noise_level_flat(fc_khz: float, bandwidth_hz: float, shipping=0.5, wind=5.0) -> float:
    """In-band noise level: PSD at the centre frequency times the bandwidth."""
    return stojanovic_noise(fc_khz, shipping, wind).total + 10 * math.log10(bandwidth_hz)


def noise_level_integrated(
    fc_khz: float, bandwidth_hz: float, shipping=0.5, wind=5.0, steps: int = 200
) -> float:
    """In-band noise level: the PSD integrated over fc +- B/2 (Simpson's rule, df in Hz)."""
    steps += steps % 2
    low = fc_khz - bandwidth_hz / 2000
    h = bandwidth_hz / 1000 / steps  # kHz

    def psd(f: float) -> float:
        return 10 ** (stojanovic_noise(f, shipping, wind).total / 10)

    total = psd(low) + psd(low + steps * h)
    for i in range(1, steps):
        total += (4 if i % 2 else 2) * psd(low + i * h)
    return 10 * math.log10(total * h * 1000 / 3)


def power_sum_db(levels_db: Iterable[float]) -> float:
    """Incoherent sum of levels in dB."""
    return 10 * math.log10(sum(10 ** (level / 10) for level in levels_db))


def received_level(source_level: float, tl: float) -> float:
    return source_level - tl


def snr(rl: float, noise_level: float, directivity_index: float = 0.0) -> float:
    return rl - noise_level + directivity_index


def sinr(rl: float, noise_level: float, interferers_db: Iterable[float] = ()) -> float:
    """RL against ambient noise plus every interfering reception, summed incoherently."""
    return rl - power_sum_db((noise_level, *interferers_db))
