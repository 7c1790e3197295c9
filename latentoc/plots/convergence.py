"""How Ipopt converged: its per-iteration log of every phase and exchange round (result.json's
``convergence``), one after the other on a common iteration axis.

Panels: the objective; the primal (constraint violation) and dual infeasibility; the barrier
parameter mu; the primal and dual step sizes alpha. Dotted lines separate the runs.
"""
from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np
from matplotlib.figure import Figure

from latentoc.plots.figure import panel_axes

__all__ = ["plot_convergence", "run_label"]


def run_label(entry: Mapping[str, Any], runs: int) -> str:
    """A run's name in the figure: its phase, and its round when there are several."""
    phase = str(entry["phase"])
    name = f"phase {phase}" if phase.isdigit() else phase
    return name + (f", round {entry['round']}" if runs > 1 else "")


def plot_convergence(convergence: Sequence[Mapping[str, Any]], title: str | None = None,
                     axes: Any = None) -> Figure:
    """Ipopt's history of each run (``[{"phase", "round", "history"}]``, result.json's
    ``convergence``) against the iteration, the runs in order."""
    if not convergence:
        raise ValueError("no convergence history (a result saved before it was recorded?)")
    fig, (ax_obj, ax_inf, ax_mu, ax_step) = panel_axes(axes, "convergence", 4, ncols=1)
    start = 0
    for k, run in enumerate(convergence):
        h = {key: np.asarray(v, dtype=float) for key, v in run["history"].items()}
        it = start + np.arange(len(h["objective"]))
        c = f"C{k % 10}"
        ax_obj.plot(it, h["objective"], "-", color=c, lw=1.5, label=run_label(run, len(convergence)))
        positive = {key: np.where(h[key] > 0, h[key], np.nan) for key in ("inf_pr", "inf_du")}  # 0 has no log
        ax_inf.semilogy(it, positive["inf_pr"], "-", color=c, lw=1.5, label="primal (constraints)" if k == 0 else None)
        ax_inf.semilogy(it, positive["inf_du"], "--", color=c, lw=1.2, label="dual (optimality)" if k == 0 else None)
        ax_mu.semilogy(it, h["mu"], "-", color=c, lw=1.5)
        ax_step.plot(it, h["alpha_pr"], "-", color=c, lw=1.5, label="primal" if k == 0 else None)
        ax_step.plot(it, h["alpha_du"], "--", color=c, lw=1.2, label="dual" if k == 0 else None)
        if k:
            for ax in (ax_obj, ax_inf, ax_mu, ax_step):
                ax.axvline(start, color="0.5", ls=":", lw=1)
        start = int(it[-1]) + 1 if len(it) else start
    ax_obj.set_ylabel("objective")
    ax_inf.set_ylabel("infeasibility")
    ax_mu.set_ylabel("barrier $\\mu$")
    ax_step.set_ylabel("step size $\\alpha$")
    ax_step.set_xlabel("Ipopt iteration (runs one after the other)")
    ax_obj.legend(fontsize=7, ncol=2)
    for ax in (ax_inf, ax_step):
        ax.legend(fontsize=7)
    for ax in (ax_obj, ax_inf, ax_mu, ax_step):
        ax.grid(True, alpha=0.3)
        ax.tick_params(labelsize=7)
    if title:
        ax_obj.set_title(title)
    if axes is None:
        fig.subplots_adjust(left=0.1, right=0.97, bottom=0.07, top=0.95, hspace=0.12)
    return fig
