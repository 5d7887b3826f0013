"""Marking strategies on hand-made indicator arrays."""

import itertools

import numpy as np
import pytest

from estimators import limit_marks, mark_coarsening, mark_doerfler, mark_maximum


def brute_force_min_bulk(eta, theta):
    squares = np.asarray(eta) ** 2
    for size in range(1, len(eta) + 1):
        for subset in itertools.combinations(range(len(eta)), size):
            if squares[list(subset)].sum() >= theta * squares.sum():
                return size
    raise AssertionError("unreachable")


def test_doerfler_marks_largest_until_bulk_reached():
    eta = np.sqrt([1.0, 4.0, 2.0, 3.0])  # squares sum to 10
    np.testing.assert_array_equal(mark_doerfler(eta, 0.4), [False, True, False, False])
    np.testing.assert_array_equal(mark_doerfler(eta, 0.41), [False, True, False, True])
    np.testing.assert_array_equal(mark_doerfler(eta, 0.7), [False, True, False, True])
    np.testing.assert_array_equal(mark_doerfler(eta, 1.0), [True, True, True, True])


@pytest.mark.parametrize("seed", range(5))
@pytest.mark.parametrize("theta", [0.1, 0.5, 0.9, 1.0])
def test_doerfler_set_is_minimal(seed, theta):
    eta = np.random.default_rng(seed).random(9)
    marked = mark_doerfler(eta, theta)
    assert (eta[marked] ** 2).sum() >= theta * (eta**2).sum()
    assert marked.sum() == brute_force_min_bulk(eta, theta)


def test_doerfler_ignores_zero_indicators_and_all_zero():
    np.testing.assert_array_equal(mark_doerfler([0.0, 1.0, 0.0], 1.0), [False, True, False])
    assert not mark_doerfler(np.zeros(4), 0.5).any()


def test_maximum_strategy():
    eta = np.array([0.1, 1.0, 0.5, 0.49])
    np.testing.assert_array_equal(mark_maximum(eta, 0.5), [False, True, True, False])
    np.testing.assert_array_equal(mark_maximum(eta, 1.0), [False, True, False, False])
    assert not mark_maximum(np.zeros(3), 0.5).any()


def test_coarsening_flags_small_indicators():
    eta = np.sqrt([0.1, 1.0, 2.0, 0.9])  # mean of squares = 1
    np.testing.assert_array_equal(mark_coarsening(eta, 0.5), [True, False, False, False])
    np.testing.assert_array_equal(mark_coarsening(eta, 1.0), [True, False, False, True])


def test_limit_marks_keeps_largest():
    eta = np.array([5.0, 1.0, 4.0, 3.0, 2.0])
    marked = np.array([True, True, False, True, True])
    np.testing.assert_array_equal(limit_marks(eta, marked, 2), [True, False, False, True, False])
    np.testing.assert_array_equal(limit_marks(eta, marked, 10), marked)
    assert not limit_marks(eta, marked, 0).any()
    assert marked.sum() == 4  # input untouched


@pytest.mark.parametrize("strategy", [mark_doerfler, mark_maximum, mark_coarsening])
@pytest.mark.parametrize("theta", [0.0, -0.1, 1.5, float("nan")])
def test_bad_theta_rejected(strategy, theta):
    with pytest.raises(ValueError, match=r"\(0, 1\]"):
        strategy([1.0, 2.0], theta)


@pytest.mark.parametrize("strategy", [mark_doerfler, mark_maximum, mark_coarsening])
def test_bad_indicators_rejected(strategy):
    with pytest.raises(ValueError, match="empty"):
        strategy([], 0.5)
    with pytest.raises(ValueError, match="nonnegative"):
        strategy([1.0, -1.0], 0.5)
    with pytest.raises(ValueError, match="1-D"):
        strategy(np.ones((2, 2)), 0.5)


def test_limit_marks_rejects_bad_arguments():
    eta = np.ones(3)
    with pytest.raises(ValueError, match="boolean"):
        limit_marks(eta, np.ones(3), 1)
    with pytest.raises(ValueError, match="shape"):
        limit_marks(eta, np.ones(2, dtype=bool), 1)
    with pytest.raises(ValueError, match="max_count"):
        limit_marks(eta, np.ones(3, dtype=bool), -1)
    with pytest.raises(ValueError, match="empty"):
        limit_marks([], np.ones(0, dtype=bool), 1)
