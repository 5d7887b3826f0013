"""Stability stress cases (issue 6, item 5): every step keeps u and z finite, z in [0, 1] and
non-decreasing at the nodes, and E_total non-increasing while the load is held on an unchanged
mesh; each case also shows one physical fact. The cases are in ngfrac/testing/stress_cases.py;
benchmarks/stress_table.py prints the measured table of docs/stress.md."""
import functools

import pytest

from ngfrac.testing import stress_cases as sc

pytestmark = [pytest.mark.stress, pytest.mark.usefixtures("one_thread")]


@functools.lru_cache(maxsize=None)
def result_of(name):
    """One run per case and session (the energy test below reuses the runs)."""
    return sc.run_case(sc.CASE_BY_NAME[name])


def _param(case):
    return pytest.param(case.name, id=case.name, marks=[pytest.mark.slow] if case.slow else [])


@pytest.mark.parametrize("name", [_param(case) for case in sc.CASES])
def test_case_is_stable(name):
    result = result_of(name)
    found = sc.problems(result)
    assert not found, sc.summary(result) + "\n" + "\n".join(found)


@pytest.mark.xfail(strict=True, reason=sc.ENERGY_PROJECTION)
@pytest.mark.parametrize("name", [_param(case) for case in sc.CASES if case.energy_known])
def test_energy_never_rises_while_the_load_is_held(name):
    result = result_of(name)
    found = sc.energy_problems(result)
    assert not found, sc.summary(result) + "\n" + "\n".join(found)
