"""Frontseat drivers shipped with pygoby (loaded through pygoby.frontseat.plugins)."""

from pygoby.frontseat.drivers.abc import AbcFrontSeat

__all__ = ["AbcFrontSeat"]
