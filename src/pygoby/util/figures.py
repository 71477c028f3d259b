"""matplotlib for pygoby's figures (netsim reports and sweeps, `pygoby log plot`): drawn off
screen (Agg), saved as PNG. matplotlib comes with the `sim` extra, so import this module inside
`needs_extra("sim", "<feature>")`.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import matplotlib

matplotlib.use("Agg")  # files only: no display needed, none opened
import matplotlib.pyplot as plt  # after matplotlib.use: the backend is chosen first

__all__ = ["no_data_figure", "plt", "save_figure"]

DPI = 110


def save_figure(fig: Any, path: Path) -> Path:
    fig.tight_layout()
    fig.savefig(path, dpi=DPI)
    plt.close(fig)
    return path


def no_data_figure(path: Path, title: str, missing: str) -> Path:
    """A figure that says what it would show and why it is empty (a missing figure would
    leave the reader wondering whether the tool ran)."""
    fig, ax = plt.subplots(figsize=(8, 3))
    ax.set_axis_off()
    ax.set_title(title)
    ax.text(0.5, 0.5, f"no data: {missing}", ha="center", va="center", wrap=True)
    return save_figure(fig, path)
