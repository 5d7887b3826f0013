"""The u-sub-step with a frozen smooth z converges at the optimal rates for orders 1-3.

Manufactured solution u = sin(pi x) sin(pi y), z = (x + y)/4 (exactly representable in P1/P2),
f = -div(((1-z)^2 + eta) mu grad u), u = 0 on all four edges.
"""
import numpy as np
import pytest

from ngfrac.testing.manufactured import u_errors as errors


@pytest.mark.parametrize("order", [1, 2, 3])
def test_u_solve_rates(order):
    sizes = [0.2, 0.1, 0.05, 0.025] if order < 3 else [0.25, 0.125, 0.0625]
    table = np.array([errors(order, h) for h in sizes])
    rate_l2 = np.polyfit(np.log(sizes), np.log(table[:, 0]), 1)[0]
    rate_h1 = np.polyfit(np.log(sizes), np.log(table[:, 1]), 1)[0]
    report = "\n".join(f"h={h:<7} L2={e[0]:.3e} H1={e[1]:.3e}" for h, e in zip(sizes, table))
    message = f"order {order}: L2 rate {rate_l2:.2f}, H1 rate {rate_h1:.2f}\n{report}"
    print(message)
    assert rate_l2 > order + 1 - 0.2, message
    assert rate_h1 > order - 0.2, message
