"""Figure of the full-chain fits per cell: measured, paper theory, plain and robust fit."""

from __future__ import annotations

import numpy as np

from .._io._tables import wang2022_table
from .._plot import pyplot, save_figure
from ._chain import TABLES, ChainFit, paper_theory_slips
from ._robust import RobustChainFit, rms_relative_masked


def plot_fit_measured(plain: ChainFit, robust: RobustChainFit, path=None, *, files=True):
    """|phase slip| (nm) per cell of wang2022 Tables 4–7 against the vacuum level: measured,
    the paper's theory, the plain (relative least-squares) fit and the robust fit; flagged cells
    are ringed. One panel per table. Written to `path` if given; returns the figure (None
    without matplotlib)."""
    plt = pyplot("fit_measured figure", files=files)
    if plt is None:
        return None
    vac = np.asarray(wang2022_table(3)["vacuum_kPa"])
    y, paper = robust.target_nm, paper_theory_slips()
    fig, axes = plt.subplots(1, 4, figsize=(14, 3.8), sharex=True, constrained_layout=True)
    for j, (ax, n) in enumerate(zip(axes, TABLES)):
        ax.plot(vac, np.abs(y[:, j]), "ko", label="measured")
        ax.plot(vac, np.abs(paper[:, j]), "C7s--", mfc="none", label="paper theory")
        ax.plot(vac, np.abs(plain.model_nm[:, j]), "C3v-", label="plain fit (relative LS)")
        ax.plot(vac, np.abs(robust.model_nm[:, j]), "C0^-", label="robust fit")
        flag = robust.flagged[:, j]
        if np.any(flag):
            ax.plot(vac[flag], np.abs(y[flag, j]), "o", ms=14, mfc="none", mec="C1", mew=2,
                    label="flagged")  # fmt: skip
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.set_title(f"Table {n} (T{n})")
        ax.set_xlabel("vacuum (kPa)")
    axes[0].set_ylabel("|phase slip| (nm)")
    handles, labels = [], []
    for ax in axes:  # the legend entries of all panels, once
        for h, lab in zip(*ax.get_legend_handles_labels()):
            if lab not in labels:
                handles.append(h)
                labels.append(lab)
    axes[0].legend(handles, labels, fontsize=7)
    fig.suptitle(
        f"wang2022 Tables 4–7: rms relative residual over the unflagged cells — robust "
        f"{robust.rms_relative_residual_unflagged:.3f}, plain "
        f"{rms_relative_masked(plain.model_nm, y, ~robust.flagged):.3f}, paper theory "
        f"{rms_relative_masked(paper, y, ~robust.flagged):.3f}"
    )
    if path is not None:
        save_figure(fig, path)
    return fig
