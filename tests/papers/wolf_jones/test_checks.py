"""The argument checks shared by the Wolf & Jones studies: valid input passes unchanged, bad input is refused by name."""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np
import pytest

from cislunar.papers.wolf_jones import _checks


def test_sequences_and_integers_refuse_text_and_scalars_by_name():
    assert _checks.sequence((1, 2), "xs") == [1, 2] and _checks.sequence([], "xs", allow_empty=True) == []
    assert _checks.integers([3, 4.0], "n_nodes", minimum=3) == (3, 4)
    for bad in (None, "abc", 3.0, {"a": 1}):
        with pytest.raises(TypeError, match="xs"):
            _checks.sequence(bad, "xs")
    with pytest.raises(ValueError, match="xs"):
        _checks.sequence([], "xs")
    with pytest.raises(ValueError, match=r"n_nodes\[1\]"):
        _checks.integers([6, 2], "n_nodes", minimum=3)


def test_vector_checks_length_and_finiteness():
    v = _checks.vector([1.0, 2.0], "alphas", n=2)
    assert v.dtype == float and np.array_equal(v, [1.0, 2.0])
    for bad, exc in (([1.0, np.nan], ValueError), ([[1.0]], ValueError), ([], ValueError), ("ab", TypeError)):
        with pytest.raises(exc, match="alphas"):
            _checks.vector(bad, "alphas")
    with pytest.raises(ValueError, match="3 values"):
        _checks.vector([1.0, 2.0], "alphas", n=3)


def test_plan_needs_node_states_and_controls_of_one_grid():
    good = SimpleNamespace(x=np.zeros((4, 6)), u=np.zeros((4, 3)))
    assert _checks.plan(good, "res", n=4) is good
    assert _checks.plan(SimpleNamespace(x=np.zeros((4, 6))), "a", controls=False) is not None
    for bad in (None, 3.0, SimpleNamespace(x=np.zeros((4, 6))), SimpleNamespace(x=np.zeros((4, 6)), u=np.zeros((3, 3))),
                SimpleNamespace(x=np.full((4, 6), np.nan), u=np.zeros((4, 3)))):
        with pytest.raises((TypeError, ValueError), match="res"):
            _checks.plan(bad, "res")
    with pytest.raises(ValueError, match="5 node states"):
        _checks.plan(good, "res", n=5)


def test_executor_is_none_or_has_submit():
    from concurrent.futures import ThreadPoolExecutor

    assert _checks.executor(None) is None
    with ThreadPoolExecutor(1) as pool:
        assert _checks.executor(pool) is pool
    with pytest.raises(TypeError, match="executor"):
        _checks.executor("pool")
