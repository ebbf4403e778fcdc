"""cislunar: a literate reproduction of four cislunar navigation and tracking papers.

Modules
-------
dynamics      CR3BP constants, units, vector field, Jacobian, Jacobi constant, libration points
propagation   heyoka.py propagation of states, STMs and second-order STTs; events; scipy cross-check path
orbits        symmetric periodic orbits: shooting, continuation, monodromy, stability; reference orbits
plotting      packaged matplotlib style, ``save_figure``, rotating-frame plot helpers
report        paper-vs-reproduction tables gathered into ``build/report.md``
notebooks     command-line runner executing ``notebooks/NN_*.py`` with papermill
"""

from .dynamics import CR3BP, EARTH_MOON

__all__ = ["CR3BP", "EARTH_MOON"]
__version__ = "0.1.0"
