import os

import matplotlib

matplotlib.use("Agg")
os.environ.setdefault("JUPYTER_PREFER_ENV_PATH", "1")

try:
    from hypothesis import settings

    settings.register_profile("ci", deadline=None, max_examples=40, derandomize=True)
    settings.load_profile("ci")
except ImportError:  # pragma: no cover
    pass
