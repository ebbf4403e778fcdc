"""Refusals of the pooled detection functions that the reliability sweep (one bad value per argument) cannot
express: a value that is bad only with another argument, and bad values that must be refused before any Monte
Carlo runs."""

import numpy as np
import pytest

from cislunar.cr3bp import orbits
from cislunar.cr3bp.dynamics import EARTH_MOON as em
from cislunar.papers.greaves_scheeres_2021 import detection as det


@pytest.fixture(scope="module")
def short_setup():
    """A short, coarse track (0.6 period from periapsis, 8-hour cadence)."""
    return det.make_setup(em, orbits.nrho_9_2(em), det.window_control_weight(det.ACTIVE_POLICY), 1e-18,
                          cadence_hours=8.0, window_hours=16.0, periods=0.6)


def test_a_direction_without_a_burn_is_refused_not_ignored(short_setup):
    """With no policy and no magnitude no burn is drawn, so a direction would be silently dropped (an H0 trial)."""
    for draw in (lambda **kw: det.draw_trials([np.random.default_rng(0)], short_setup, **kw),
                 lambda **kw: det.draw_trial(np.random.default_rng(0), short_setup, **kw)):
        with pytest.raises(ValueError, match="^direction is given but no burn is drawn"):
            draw(policy=None, direction=(0.3, 0.2))
    # with a burn the direction is flown: the same draw as a policy-free burn of that size along it
    a = det.draw_trials([np.random.default_rng(0)], short_setup, magnitude_m_s=0.5, direction=(0.3, 0.2))[0]
    assert (a.magnitude_m_s, a.azimuth, a.elevation) == (0.5, 0.3, 0.2)
    b = det.draw_trials([np.random.default_rng(0)], short_setup, det.QUIET_POLICY, direction=(0.3, 0.2))[0]
    assert (b.azimuth, b.elevation) == (0.3, 0.2) and b.magnitude_m_s > 0
    h0 = det.draw_trials([np.random.default_rng(0)], short_setup)[0]
    assert h0.magnitude_m_s == 0 and np.isnan(h0.azimuth)


@pytest.mark.parametrize("kwargs, name", [
    (dict(bandwidth="nope"), "bandwidth"), (dict(bandwidth=-1.0), "bandwidth"), (dict(bandwidth=np.nan), "bandwidth"),
    (dict(bandwidth=True), "bandwidth"), (dict(desc=None), "desc"), (dict(desc=3), "desc"),
    (dict(batch_size=0), "batch_size"), (dict(progress="yes"), "progress"),
])
def test_policy_studies_refuse_bad_options_before_any_monte_carlo(short_setup, kwargs, name, monkeypatch):
    def no_monte_carlo(*a, **k):
        raise AssertionError("a Monte Carlo ran before the options were checked")

    monkeypatch.setattr(det, "run_detection_monte_carlos", no_monte_carlo)
    with pytest.raises((ValueError, TypeError), match=f"^{name} must"):
        det.run_policy_studies([(short_setup, det.QUIET_POLICY, 2, 2, 0, 1)], **kwargs)


@pytest.mark.parametrize("desc", [None, 3, b"x"])
def test_pooled_monte_carlo_refuses_a_non_string_label(short_setup, desc):
    with pytest.raises(TypeError, match="^desc must be"):
        det.run_detection_monte_carlos([(short_setup, None, 2, 1)], batch_size=2, progress=True, desc=desc)
