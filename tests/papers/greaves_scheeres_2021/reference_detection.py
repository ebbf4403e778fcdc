"""The detection Monte Carlo's trial path before the batched draws (2026-11-26): the test oracle of
``test_detection_pooled.py`` and the "old path" of ``benchmarks/bench_detection.py`` (not part of the package).

One trial at a time: the magnitude through ``scipy.stats.truncnorm.rvs``, the truth by
:func:`cislunar.papers.greaves_scheeres_2021.tracking.simulate_truth` (three propagations per burn trial), the
measurements and hand-off by the tracking module, then one batched OCBE call per lockstep group and the NEES
bookkeeping trial by trial.

:func:`unscreened_arc_check` runs the arc impact check of the OCBE transitions without its cheap first screen
(:func:`cislunar.cr3bp.propagation._check_arcs_outside_primaries` with ``screen=False``: the rigorous fall-time
bound on every sub-grid interval of every trial; the same decisions).
"""

import contextlib
import functools

import numpy as np

from cislunar.cr3bp import propagation
from cislunar.estimation import batched_ocbe
from cislunar.estimation.batched_ocbe import ocbe_batch
from cislunar.estimation.consistency import _nees
from cislunar.papers.greaves_scheeres_2021 import detection as det
from cislunar.papers.greaves_scheeres_2021 import tracking


def reference_draw_trial(rng, setup, policy=None, *, magnitude_m_s=None, direction=None, burn_offset_hours=0.0):
    """``detection.draw_trial`` as it was: the tracking module's functions, one trial."""
    em, sc = setup.system, setup.scenario
    t_burn = setup.t_maneuver + burn_offset_hours * 3600.0 / em.time_unit_s
    maneuvers, mag, az, el = [], 0.0, np.nan, np.nan
    if policy is not None or magnitude_m_s is not None:
        if policy is not None:
            mag, az, el = (float(v) for v in policy.sample(rng))
        else:
            az, el = (float(v) for v in det.StationKeepingPolicy.sample_pointing(rng))
        if magnitude_m_s is not None:
            mag = float(magnitude_m_s)
        if direction is not None:
            az, el = (float(v) for v in direction)
        dv = det.pointing_vector(az, el) * mag * 1e-3 / em.velocity_unit_km_s
        maneuvers = [(t_burn, dv)]
    truth = tracking.simulate_truth(em, sc.x_start, sc.t, maneuvers)
    y = tracking.simulate_measurements(sc, truth, rng)
    y = y[:, 0] if y.ndim == 3 else y
    x0, P0 = tracking.initial_estimate(em, truth[0], rng)
    return det.TrialInputs(mag, az, el, truth, y, x0, P0)


def _reference_result(setup, inputs, z_smooth, z_step, x_filt, P_filt, x_smooth, P_smooth):
    v = setup.system.velocity_unit_km_s * 1e3
    lim = det._NEES_LIMIT
    nf, ns = _nees(x_filt, P_filt, inputs.truth), _nees(x_smooth, P_smooth, inputs.truth)
    return det.TrialResult(float(z_smooth) * v, float(z_step) * v, inputs.magnitude_m_s, inputs.azimuth,
                           inputs.elevation, float(np.mean(nf > lim)), float(np.mean(ns > lim)), float(np.mean(nf)),
                           float(np.mean(ns)))


def reference_detection_batches(rngs, setup, policy, batch_size):
    """``detection._detection_batches`` as it was (per-trial draws and bookkeeping around one OCBE call)."""
    B = batch_size
    inputs = [reference_draw_trial(child, setup, policy) for rng in rngs for child in rng.spawn(B)]
    sc = setup.scenario
    res = ocbe_batch(setup.system, sc.t, np.array([i.y for i in inputs]), setup.observer_states, sc.model,
                     sc.meas_cov, np.array([i.x0 for i in inputs]), np.array([i.P0 for i in inputs]),
                     setup.control_weight, n_sub=setup.n_sub, tol=setup.tol)
    flat = [_reference_result(setup, inp, res.z_smooth[b], res.z_step[b], res.x_filt[b], res.P_filt[b],
                              res.x_smooth[b], res.P_smooth[b]) for b, inp in enumerate(inputs)]
    return [flat[k * B:(k + 1) * B] for k in range(len(rngs))]


def reference_monte_carlo(setup, policy, n_trials, seed, batch_size=8):
    """The Monte Carlo's results (list of TrialResult) on the old path, serial, seeded as
    ``run_detection_monte_carlo`` (batch ``i`` gets child ``i`` of ``SeedSequence(seed)``)."""
    n_batches = -(-n_trials // batch_size)
    rngs = [np.random.default_rng(s) for s in np.random.SeedSequence(seed).spawn(n_batches)]
    out = []
    for a in range(0, n_batches, det.LOCKSTEP_TRIALS // batch_size):
        out += [r for batch in reference_detection_batches(rngs[a:a + det.LOCKSTEP_TRIALS // batch_size], setup,
                                                           policy, batch_size) for r in batch]
    return out[:n_trials]


@contextlib.contextmanager
def unscreened_arc_check():
    """Within the block, the batched OCBE checks its arcs with the unscreened test (``screen=False``): the path
    before the screen, for the tests and ``benchmarks/bench_detection.py`` (not thread-safe: it patches a module)."""
    screened = batched_ocbe._check_arcs_outside_primaries
    batched_ocbe._check_arcs_outside_primaries = functools.partial(propagation._check_arcs_outside_primaries,
                                                                   screen=False)
    try:
        yield
    finally:
        batched_ocbe._check_arcs_outside_primaries = screened


def reference_arc_statistics(task):
    """``detection._arc_statistics`` as it was before 2026-11-26d: the filter and smoother rerun on every growing
    arc (``filter_trials(n_epochs=e + 1)`` for each end epoch ``e``) and once on the whole track.  Same task and
    return value as today's (``(setup, inputs, ends)`` -> ``(z of each arc (B, E), z of the track (B,), squared
    whitened innovations (B, N))``, z in m/s); patch it in for ``detection.health_lead_study``'s old path."""
    setup, inputs, ends = task
    v = setup.system.velocity_unit_km_s * 1e3
    z_arc = np.stack([det.filter_trials(setup, inputs, n_epochs=int(e) + 1).z_smooth * v for e in ends], axis=-1)
    full = det.filter_trials(setup, inputs)
    return z_arc, full.z_smooth * v, full.residual_norms**2
