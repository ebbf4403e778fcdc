r"""The studies of the node-placement chapter (notebook 04): Sundman-spaced nodes (Wolf & Jones Eqs. 37-39), the
accuracy of the first-order-hold affine model between them (Eqs. 27-33), and the node thrust bounds (Eqs. 40-41).

What is here:

* :func:`reference_arcs`: the two references, the test-case-1 observer DRO (corrected Table 2 row) over two periods
  and, beyond the paper, the 9:2 NRHO over one period.
* :func:`node_sweep`: Sundman nodes for every arc and exponent, with the longest/shortest interval ratio.
* :func:`linearisation_error`, :func:`linearisation_sweep`: the largest one-interval position error of the affine
  model under random smooth controls of size :math:`a_{max}`, per arc and exponent, and on the DRO for further
  random-draw seeds.
* :func:`eq40_residual`: how well the minimum-norm node bounds of Eq. 41 satisfy Eq. 40.
* :func:`moon_distance_km` and ``figure_*``: the chapter's figures.

Units: non-dimensional (LU, TU, LU/TU^2) unless a name says ``_km`` or ``_d``; Earth-Moon rotating frame.
"""

from __future__ import annotations

from dataclasses import dataclass

import matplotlib.pyplot as plt
import numpy as np

from cislunar.cr3bp import orbits, propagation
from cislunar.cr3bp.dynamics import CR3BP, check_system
from cislunar.guidance import discretization as D
from cislunar.papers.wolf_jones import _checks, reference
from cislunar.publish import plotting
from cislunar.utils import validation
from cislunar.utils.montecarlo import map_tasks

__all__ = [
    "A_MAX_KM_S2",
    "LinearisationSweep",
    "NodeSweep",
    "eq40_residual",
    "figure_linearisation_error",
    "figure_node_bounds",
    "figure_node_spacing",
    "figure_nodes_on_orbits",
    "linearisation_error",
    "linearisation_sweep",
    "moon_distance_km",
    "node_sweep",
    "reference_arcs",
]

#: Wolf & Jones Table 3: largest thrust acceleration, km/s^2.
A_MAX_KM_S2 = 1e-6
DRO_ARC = "W&J observer DRO (2 periods)"
NRHO_ARC = "9:2 NRHO (1 period)"


def reference_arcs(system: CR3BP) -> dict:
    """``{name: (x0, tf)}``: the corrected Table 2 observer DRO over two periods, the 9:2 NRHO over one (LU, TU)."""
    check_system(system)
    row = next(r for r in reference.load_wolf_jones_table() if r.table == 2 and r.label == "observer_t0")
    dro = reference.verify_table_row(system, row).corrected
    nrho = orbits.nrho_9_2(system)
    return {DRO_ARC: (dro.x0, 2 * dro.period), NRHO_ARC: (nrho.x0, nrho.period)}


@dataclass(frozen=True)
class NodeSweep:
    """Sundman node times ``nodes[(arc, sigma)]`` (TU) of ``n_nodes`` nodes per arc for each exponent."""

    arcs: dict
    sigmas: tuple
    n_nodes: int
    nodes: dict

    @property
    def spread(self) -> dict:
        """Longest over shortest interval, per (arc, sigma)."""
        return {k: float(np.diff(t).max() / np.diff(t).min()) for k, t in self.nodes.items()}


def node_sweep(system: CR3BP, arcs: dict, sigmas, n_nodes: int) -> NodeSweep:
    """Sundman nodes (Eqs. 37-39) for every arc of ``arcs`` and every exponent of ``sigmas``."""
    check_system(system)
    arcs = _arcs(arcs)
    n = validation.integer(n_nodes, "n_nodes", minimum=3)
    sigmas = tuple(validation.positive(s, f"sigmas[{i}]", allow_zero=True)
                   for i, s in enumerate(_checks.sequence(sigmas, "sigmas")))
    nodes = {(name, s): D.sundman_nodes(system, x0, tf, n, s)[0] for name, (x0, tf) in arcs.items() for s in sigmas}
    return NodeSweep(dict(arcs), sigmas, n, nodes)


def _arcs(arcs) -> dict:
    """Check ``{name: (x0 (6,), tf > 0)}`` and return it as a dict of ``(ndarray, float)``."""
    validation.instance(arcs, "arcs", dict, "a dict {name: (x0, tf)}")
    if not arcs:
        raise ValueError("arcs must hold at least one arc")
    out = {}
    for name, arc in arcs.items():
        if not isinstance(arc, (tuple, list)) or len(arc) != 2:
            raise validation.ArgumentTypeError(f"arcs[{name!r}] must be a pair (x0, tf); got {type(arc).__name__}")
        out[name] = (validation.as_state(arc[0], f"arcs[{name!r}] x0", batch=False),
                     validation.positive(arc[1], f"arcs[{name!r}] tf"))
    return out


def _draw_profiles(rng: np.random.Generator, draws: int) -> list:
    """``draws`` random control profiles ``(phase (3,), cycles)``, drawn from ``rng`` in a fixed order (phases, then
    the number of cycles, per draw)."""
    return [(rng.uniform(0, 2 * np.pi, 3), rng.integers(1, 4)) for _ in range(draws)]


def _error_of_profiles(system: CR3BP, x0, t_nodes, profiles, a_max: float) -> float:
    """Median over ``profiles`` of the largest one-interval affine-model position error, km (unchecked kernel)."""
    t_nodes = np.asarray(t_nodes, dtype=float)
    x_ref = propagation.propagate(system, x0, t_nodes).x
    model = D.foh_discretize(system, t_nodes, x_ref, np.zeros((t_nodes.size, 3)))
    worst = []
    for phase, cycles in profiles:
        du = a_max * np.sin(2 * np.pi * t_nodes[:, None] / t_nodes[-1] * cycles + phase)
        nonlinear = D.foh_discretize(system, t_nodes, x_ref, du).x_next
        worst.append(np.max(np.linalg.norm((model.predict(x_ref, du) - nonlinear)[:, :3], axis=1)))  # position
    return float(np.median(worst) * system.length_unit_km)


def _error_task(task) -> float:
    """One (arc, sigma) cell of the sweep, for :func:`cislunar.utils.montecarlo.map_tasks` (module level: picklable)."""
    return _error_of_profiles(*task)


def linearisation_error(system: CR3BP, x0, t_nodes, draws: int, rng: np.random.Generator, a_max: float) -> float:
    """Median over ``draws`` random control profiles of the largest one-interval affine-model position error, km.

    Each profile is a sinusoid of amplitude ``a_max`` (LU/TU^2) per axis with a random phase and 1-3 cycles over the
    arc.  Each interval starts from its reference node (multiple shooting, as SCvx linearises); the nonlinear flow
    with the perturbed controls is compared with the affine prediction of Eq. 28 about the ballistic reference.
    """
    check_system(system)
    x0 = validation.as_state(x0, "x0", batch=False)
    t_nodes = validation.time_grid(t_nodes, "t_nodes", increasing=True)
    n = validation.integer(draws, "draws", minimum=1)
    validation.instance(rng, "rng", np.random.Generator)
    a_max = validation.positive(a_max, "a_max", allow_zero=True)
    return _error_of_profiles(system, x0, t_nodes, _draw_profiles(rng, n), a_max)


@dataclass(frozen=True)
class LinearisationSweep:
    """``errors[(arc, sigma)]``: linearisation error (km) with the main generator; ``extra[seed][sigma]``: the DRO
    arc again with generators seeded ``seed``."""

    errors: dict
    extra: dict

    def gain(self, arc: str, sigma: float) -> float:
        """Uniform-node error over the error at ``sigma``."""
        return self.errors[arc, 0.0] / self.errors[arc, sigma]

    def best_gain(self, arc: str) -> tuple:
        """(largest gain over the sweep, its sigma)."""
        sigmas = [s for a, s in self.errors if a == arc]
        best = min(sigmas, key=lambda s: self.errors[arc, s])
        return self.gain(arc, best), best

    def dro_gains(self, sigma: float) -> list:
        """Gain at ``sigma`` on the DRO for the main draws then each extra seed."""
        return [self.gain(DRO_ARC, sigma)] + [e[0.0] / e[sigma] for e in self.extra.values()]


def linearisation_sweep(system: CR3BP, sweep: NodeSweep, draws: int, rng: np.random.Generator, extra_seeds,
                        a_max: float, *, executor=None) -> LinearisationSweep:
    """:func:`linearisation_error` for every (arc, sigma) of ``sweep`` (drawing from ``rng`` in that order), then on
    the DRO arc for every sigma with a fresh generator per seed of ``extra_seeds``.  Needs sigma = 0 in the sweep.

    The random control profiles are all drawn here, in that order, before any cell is computed; the cells then run
    through ``executor`` (:func:`cislunar.utils.montecarlo.map_tasks`; ``None``: serially), so the result does not
    depend on the executor.
    """
    check_system(system)
    validation.instance(sweep, "sweep", NodeSweep)
    if 0.0 not in sweep.sigmas:
        raise ValueError("the sweep must contain sigma = 0 (uniform nodes), the reference of every gain")
    n = validation.integer(draws, "draws", minimum=1)
    validation.instance(rng, "rng", np.random.Generator)
    a_max = float(validation.positive(a_max, "a_max", allow_zero=True))
    extra_seeds = [validation.integer(seed, f"extra_seeds[{i}]", minimum=0)
                   for i, seed in enumerate(_checks.sequence(extra_seeds, "extra_seeds", allow_empty=True))]
    _checks.executor(executor)
    keys = list(sweep.nodes)
    tasks = [(system, sweep.arcs[name][0], sweep.nodes[name, s], _draw_profiles(rng, n), a_max) for name, s in keys]
    x0 = sweep.arcs[DRO_ARC][0]
    extra_keys = [(seed, s) for seed in extra_seeds for s in sweep.sigmas]
    tasks += [(system, x0, sweep.nodes[DRO_ARC, s], _draw_profiles(np.random.default_rng(seed), n), a_max)
              for seed, s in extra_keys]
    values = map_tasks(_error_task, tasks, executor=executor, progress=False, desc="linearisation sweep")
    errors = dict(zip(keys, values[:len(keys)]))
    extra = {seed: {} for seed in extra_seeds}
    for (seed, s), v in zip(extra_keys, values[len(keys):]):
        extra[seed][s] = v
    return LinearisationSweep(errors, extra)


def eq40_residual(t_nodes, a_max: float) -> float:
    """Largest relative residual of Eq. 40, ``(u_k + u_{k+1}) / (2 dt_k) = a_max``, for the minimum-norm bounds of
    Eq. 41 on ``t_nodes``."""
    t = validation.time_grid(t_nodes, "t_nodes", increasing=True)
    a_max = validation.positive(a_max, "a_max")
    u = D.max_control_per_node(t, a_max)
    return float(np.max(np.abs((u[:-1] + u[1:]) / (2 * np.diff(t)) - a_max)) / a_max)


def moon_distance_km(system: CR3BP, x0, tf: float, n: int = 1500) -> np.ndarray:
    """Distance to the Moon along the arc from ``x0`` over ``[0, tf]`` at ``n`` equally spaced times, km."""
    check_system(system)
    x0 = validation.as_state(x0, "x0", batch=False)
    tf = validation.positive(tf, "tf")
    n = validation.integer(n, "n", minimum=2)
    dense = propagation.propagate(system, x0, np.linspace(0, tf, n)).x
    return np.linalg.norm(dense[:, :3] - system.secondary_position, axis=1) * system.length_unit_km


# ---------------------------------------------------------------------------------------------------------------
# Figures
# ---------------------------------------------------------------------------------------------------------------


def figure_node_spacing(system: CR3BP, sweep: NodeSweep):
    """Node spacing (hours) against time, one panel per arc, one curve per sigma."""
    check_system(system)
    validation.instance(sweep, "sweep", NodeSweep)
    em = system
    fig, axes = plt.subplots(1, 2, figsize=(12, 4.6), layout="constrained")
    for ax, name in zip(axes, sweep.arcs):
        for s in sweep.sigmas:
            t = sweep.nodes[name, s]
            ax.plot(em.tu_to_days(0.5 * (t[1:] + t[:-1])), em.tu_to_days(np.diff(t)) * 24, ".-",
                    label=rf"$\sigma$ = {s:g}")
        ax.set_xlabel("time [days]")
        ax.set_ylabel("node spacing [hours]")
        ax.set_title(name)
    # the DRO's spacing varies by a factor of about two: a linear axis; the NRHO's by orders of magnitude: a log axis
    # with plain numbers (0.1, 1, 10 hours)
    axes[1].set_yscale("log")
    axes[1].yaxis.set_major_formatter(plt.FormatStrFormatter("%g"))
    axes[1].yaxis.set_minor_formatter(plt.NullFormatter())
    handles, labels = axes[0].get_legend_handles_labels()
    fig.legend(handles, labels, loc="outside lower center", ncol=len(sweep.sigmas), fontsize=9, frameon=False)
    fig.suptitle(f"Sundman-spaced nodes ({sweep.n_nodes} per arc)")
    return fig


def figure_nodes_on_orbits(system: CR3BP, sweep: NodeSweep):
    """Each arc (Moon-centred, DRO in x-y, NRHO in y-z) with its nodes for sigma = 0 and the largest sigma."""
    check_system(system)
    validation.instance(sweep, "sweep", NodeSweep)
    if 0.0 not in sweep.sigmas:
        raise ValueError("sweep must contain sigma = 0 (uniform nodes, drawn against the largest sigma)")
    em = system
    fig, axes = plt.subplots(1, 2, figsize=(12, 5.4), layout="constrained")
    for ax, name, plane in zip(axes, sweep.arcs, ("xy", "yz")):
        x0, tf = sweep.arcs[name]
        dense = propagation.propagate(em, x0, np.linspace(0, tf, 1500)).x
        plotting.plot_rotating(ax, dense, em, plane, moon_centred=True, units="km", color="0.6", lw=0.8)
        for s, marker in ((0.0, "o"), (max(sweep.sigmas), "x")):
            pts = propagation.propagate(em, x0, sweep.nodes[name, s]).x
            plotting.plot_rotating(ax, pts, em, plane, moon_centred=True, units="km", ls="none", marker=marker, ms=4,
                                   label=rf"nodes, $\sigma$ = {s:g}")
        plotting.plot_primaries(ax, em, plane, moon_centred=True, units="km", earth=False)
        ax.set_title(name)
        plotting.thousands_km_axes(ax, plane)
    handles, labels = axes[0].get_legend_handles_labels()  # the same entries in both panels: one legend below them
    fig.legend(handles, labels, loc="outside lower center", ncol=3, fontsize=9, frameon=False)
    return fig


def figure_linearisation_error(sweep: NodeSweep, lin: LinearisationSweep):
    """Linearisation error against sigma, one curve per arc."""
    validation.instance(sweep, "sweep", NodeSweep)
    validation.instance(lin, "lin", LinearisationSweep)
    fig, ax = plt.subplots()
    for name in sweep.arcs:
        ax.semilogy(sweep.sigmas, [lin.errors[name, s] for s in sweep.sigmas], "o-", label=name)
    ax.set_xlabel(r"Sundman exponent $\sigma$ [-]")
    ax.set_ylabel("largest one-step position error [km]")
    ax.set_title(f"FOH affine model vs nonlinear flow ({sweep.n_nodes} nodes, controls of size a_max)")
    ax.legend(loc="upper center", bbox_to_anchor=(0.5, -0.15), ncol=2, frameon=False)  # below the axes
    return fig


def figure_node_bounds(system: CR3BP, sweep: NodeSweep, arc: str, a_max: float):
    """Eq. 41 minimum-norm node bounds as printed (impulse units, m/s) on ``arc`` for every sigma."""
    check_system(system)
    validation.instance(sweep, "sweep", NodeSweep)
    validation.choice(arc, "arc", tuple(sweep.arcs))
    a_max = validation.positive(a_max, "a_max")
    em = system
    fig, ax = plt.subplots()
    for s in sweep.sigmas:
        t = sweep.nodes[arc, s]
        umax = D.max_control_per_node(t, a_max)
        ax.plot(em.tu_to_days(t), umax * em.velocity_unit_km_s * 1e3, ".-", label=rf"$\sigma$ = {s:g}")
    ax.set_xlabel("time [days]")
    ax.set_ylabel(r"$u_{max,k}$ as printed [m/s]")
    ax.set_title("Eq. 41 minimum-norm node bounds on the NRHO arc")
    ax.legend()
    return fig
