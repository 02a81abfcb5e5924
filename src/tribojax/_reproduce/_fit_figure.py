"""Figure of the full-chain fits per cell: measured, paper theory, plain and robust fit."""

from __future__ import annotations

import numpy as np

from .._plot import figure, save_figure
from .._tables import wang2022_table
from ._chain_result import TABLES, measured_slips, paper_theory_slips, rms_relative


def plot_fit_measured(plain_nm, robust_nm, flagged, path=None, *, files=True):
    """|phase slip| (nm) per cell of wang2022 Tables 4–7 against the vacuum level: measured,
    the paper's theory, the plain (relative least-squares) fit and the robust fit; flagged cells
    are ringed. One panel per table.

    Args:
        plain_nm, robust_nm: (6, 4) model slips (nm) of the two fits (`ChainFit.model_nm`,
            `RobustChainFit.model_nm`).
        flagged: (6, 4) bool, the robust fit's flagged cells.
        path: PNG to write. files: ignored (kept for old calls; the figure is a plain
            `Figure`, the user's matplotlib backend is never changed).
    Returns:
        the figure, or None without matplotlib.
    """
    fig = figure("fit_measured figure", figsize=(14, 3.8), constrained_layout=True)
    if fig is None:
        return None
    vac = np.asarray(wang2022_table(3)["vacuum_kPa"])
    y, paper = measured_slips(), paper_theory_slips()
    plain_nm, robust_nm = np.asarray(plain_nm), np.asarray(robust_nm)
    flagged = np.asarray(flagged, dtype=bool)
    axes = fig.subplots(1, 4, sharex=True)
    for j, (ax, n) in enumerate(zip(axes, TABLES)):
        ax.plot(vac, np.abs(y[:, j]), "ko", label="measured")
        ax.plot(vac, np.abs(paper[:, j]), "C7s--", mfc="none", label="paper theory")
        ax.plot(vac, np.abs(plain_nm[:, j]), "C3v-", label="plain fit (relative LS)")
        ax.plot(vac, np.abs(robust_nm[:, j]), "C0^-", label="robust fit")
        flag = flagged[:, j]
        if np.any(flag):
            ax.plot(
                vac[flag],
                np.abs(y[flag, j]),
                "o",
                ms=14,
                mfc="none",
                mec="C1",
                mew=2,
                label="flagged",
            )
        ax.set_xscale("log")
        ax.set_yscale("log")
        # a function is wrapped in a FuncFormatter by matplotlib
        ax.yaxis.set_major_formatter(lambda v, _: f"{v:g}")
        ax.yaxis.set_minor_formatter(  # label 2 and 5 times a power of ten
            lambda v, _: f"{v:g}" if f"{v:e}"[0] in "25" else ""
        )
        ax.set_title(f"Table {n} (T{n})")
        ax.set_xlabel("vacuum (kPa)")
    axes[0].set_ylabel("|phase slip| (nm)")
    entries = {}  # the legend entries of all panels, once
    for ax in axes:
        for h, lab in zip(*ax.get_legend_handles_labels()):
            entries.setdefault(lab, h)
    axes[0].legend(list(entries.values()), list(entries), fontsize=7)
    fig.suptitle(
        f"wang2022 Tables 4–7: rms relative residual over the unflagged cells — robust "
        f"{rms_relative(robust_nm, y, ~flagged):.3f}, plain "
        f"{rms_relative(plain_nm, y, ~flagged):.3f}, paper theory "
        f"{rms_relative(paper, y, ~flagged):.3f}"
    )
    if path is not None:
        save_figure(fig, path)
    return fig
