"""cislunar: a literate reproduction of four cislunar navigation and tracking papers.

The package is built in wings.  Methods, by family, know nothing of the papers or of publishing:

cr3bp        dynamics (constants, units, vector field), propagation (heyoka STMs/STTs, events, impacts), periodic
             orbits (shooting, continuation, reference orbits), quasi-periodic tori
sensing      observer sites, measurement models, covariance (CRLB) recursions, mutual information
estimation   square-root information filter/smoother, the OCBE (single-trial and batched), the adaptive OCBE,
             filter consistency (NEES), LPV models, H2 / H-infinity observer LMIs and observers
guidance     first-order-hold discretisation, successive convexification, SSAT and MMD guidance

One package per paper holds its set-ups, studies, claims and figures; papers never import each other:

papers.wolf_jones              Wolf & Jones: MI trajectory planning, test cases 1 and 2
papers.greaves_scheeres_2021   Greaves & Scheeres (JAS 2021): optical NRHO tracking, OCBE, maneuver detection
papers.greaves_scheeres_2023   Greaves & Scheeres (AMOS 2023): SSAT, informed station keeping on a QPO
papers.nychka_bhattacharya     Nychka & Bhattacharya: LPV CR3BP, sensing-precision LMIs, observers

publish      claims and their status rule, comparison tables, the matplotlib style and ``save_figure``, the notebook
             runner (``python -m cislunar.publish.notebooks``) and the book (``python -m cislunar.publish.book``)
utils        argument validation, Monte Carlo through any executor, progress output, repository paths

``tests/architecture/test_import_rules.py`` holds these rules against the source.
"""

__all__ = ["CR3BP", "EARTH_MOON"]
__version__ = "0.1.0"


def __getattr__(name):
    """``cislunar.CR3BP`` and ``cislunar.EARTH_MOON``, imported on first use (PEP 562).

    Importing ``cislunar`` alone (as the notebook runner, each of its child processes and the book builder do)
    then costs nothing: the dynamics module pulls in ``scipy.optimize``, about a second and a half.
    """
    if name in __all__:
        from cislunar.cr3bp import dynamics

        return getattr(dynamics, name)
    raise AttributeError(f"module 'cislunar' has no attribute {name!r}")


def __dir__():
    return sorted([*globals(), *__all__])
