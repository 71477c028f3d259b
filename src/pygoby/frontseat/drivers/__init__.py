"""Frontseat drivers shipped with pygoby (loaded through pygoby.frontseat.plugins)."""
