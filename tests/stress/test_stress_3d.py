"""The 3D stress case (issue 6, item 5): a unit cube pulled apart, P1, ramp and hold.

The monitor of :mod:`ngfrac.testing.stress_cases` checks after every step: u and z finite, z
in [0, 1] and non-decreasing at the nodes, E_total non-increasing while the load is held. The
case's load sampler walks the six faces of the box (``box_load_sampler``).
"""
import math

import pytest

from ngfrac.testing import stress_cases as sc

pytestmark = pytest.mark.stress


def test_3d_case_is_stable():
    result = sc.run_case(sc.BOX_3D)
    found = sc.problems(result)
    assert not found, sc.summary(result) + "\n" + "\n".join(found)
    # the load did something: the cube damaged and carries less than its sound stiffness
    last = result.records[-1]
    assert last.dz_max >= 0 and last.crack_length > 0.01, sc.summary(result)
    sound = 50.0 * 0.1 * 1.0  # E * strain * area, the uniaxial estimate of the force
    assert 0 < last.forces["Fy_top"] < 2 * sound and math.isfinite(last.E_total)
