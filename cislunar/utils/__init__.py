"""Utilities that know no domain type: validation, Monte Carlo executors, progress output, paths."""
