"""Run every benchmark: ``python -m benchmarks [name ...]`` (``make bench``).

Each ``benchmarks/bench_*.py`` module exposes ``main() -> dict`` that prints its measurements and returns them.
"""

import importlib
import pkgutil
import sys
from pathlib import Path


def main(argv=None):
    names = (argv if argv is not None else sys.argv[1:]) or [
        m.name for m in pkgutil.iter_modules([str(Path(__file__).parent)]) if m.name.startswith("bench_")
    ]
    for name in sorted(names):
        mod = importlib.import_module(f"benchmarks.{name if name.startswith('bench_') else 'bench_' + name}")
        print(f"== {mod.__name__}", flush=True)
        mod.main()


if __name__ == "__main__":
    main()
