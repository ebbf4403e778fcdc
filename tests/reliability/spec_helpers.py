"""What several ``reliability_specs_*`` plugins share: a figure-closing wrapper and the cached 9:2 NRHO and
detection set-up that their valid calls use.

The plugins are loaded by file path (``test_reliability.py``, ``tests/utils/test_every_executor_on_dask.py``); both
loaders put this folder on ``sys.path`` first, so ``from spec_helpers import ...`` works from any plugin.
"""

from __future__ import annotations

import functools

from cislunar.cr3bp import orbits
from cislunar.cr3bp.dynamics import EARTH_MOON as em
from cislunar.papers.greaves_scheeres_2021 import detection


def closed(draw):
    """``draw`` wrapped so that the figure it returns is closed at once (the sweep draws many)."""

    def call(**kwargs):
        import matplotlib.pyplot as plt

        fig = draw(**kwargs)
        plt.close(fig)
        return fig

    return call


@functools.lru_cache(maxsize=None)
def nrho():
    """The 9:2 NRHO, built once per process."""
    return orbits.nrho_9_2(em)


@functools.lru_cache(maxsize=None)
def detection_setup():
    """Quiet window tuning (f = 0.1) on a short, coarse track: 0.8 period from periapsis, 8-hour cadence."""
    return detection.make_setup(em, nrho(), 0.1 * detection.window_control_weight(detection.QUIET_POLICY), 1e-18,
                                cadence_hours=8.0, window_hours=16.0, periods=0.8, n_sub=3)
