import numpy as np
import ngsolve as ngs
import pytest
from netgen.geom2d import unit_square

from ngfrac.scene.expressions import Expression, ExpressionError


def test_numpy_and_ngsolve_agree():
    expr = Expression("0.5*(1 + 0.2*sin(20*(x+y))) + exp(-x)*t + max(x, y) - abs(x - y)")
    mesh = ngs.Mesh(unit_square.GenerateMesh(maxh=0.3))
    t = ngs.Parameter(0.7)
    cf = expr.to_coefficient(t)
    for px, py in [(0.1, 0.2), (0.5, 0.9), (0.8, 0.3)]:
        expected = expr.evaluate_numpy({"x": px, "y": py, "t": 0.7})
        assert cf(mesh(px, py)) == pytest.approx(float(expected), rel=1e-12)


@pytest.mark.parametrize("scale", [0.2, 0.001])
def test_tanh_is_finite_and_agrees_with_numpy_for_steep_steps(scale):
    """A steep tanh step (arguments up to 0.5/scale) is finite and numpy's on the mesh: the
    form (exp(2a) - 1)/(exp(2a) + 1) alone was NaN for a > 354 (the three-hole beam's pads)."""
    expr = Expression(f"tanh((x - 0.5)/{scale}) + tanh((0.3 - y)/{scale})")
    mesh = ngs.Mesh(unit_square.GenerateMesh(maxh=0.3))
    cf = expr.to_coefficient(ngs.Parameter(0.0))
    for px, py in [(0.0, 0.0), (1.0, 1.0), (0.499, 0.301), (0.5, 0.3), (0.9, 0.1)]:
        expected = float(expr.evaluate_numpy({"x": px, "y": py, "t": 0.0}))
        # 1e-12: the mesh point's x, y carry ~1e-16 of round-off, times 1/scale = 1000
        assert cf(mesh(px, py)) == pytest.approx(expected, rel=1e-12, abs=1e-12)


def test_constant_expression():
    expr = Expression.of(2.5)
    assert expr.is_constant and expr.value() == 2.5


@pytest.mark.parametrize("text", ["__import__('os')", "x.real", "[1, 2]", "lambda: 1", "x if y else t",
                                  "'a'", "sin(x, y)"])
def test_rejects_everything_outside_the_grammar(text):
    with pytest.raises(ExpressionError):
        Expression(text)


def test_time_needed():
    with pytest.raises(ExpressionError, match="uses t"):
        Expression("10*t").to_coefficient()
    assert np.isclose(Expression("10*t").evaluate_numpy({"t": 0.5}), 5.0)


@pytest.mark.parametrize("text, expected", [("1/0", np.inf), ("-1/0", -np.inf), ("10**400", np.inf),
                                            ("0/0", None), ("sqrt(-1)", None), ("log(0)", -np.inf)])
def test_numpy_evaluation_gives_inf_and_nan_instead_of_raising(text, expected):
    """The scene check evaluates expressions with numpy: constants too (Python's 1.0/0.0
    raised ZeroDivisionError, 10.0**400 OverflowError)."""
    value = float(Expression(text).evaluate_numpy({}))
    assert np.isnan(value) if expected is None else value == expected


def test_whole_powers_of_negative_values_integrate():
    # NGSolve's CoefficientFunction ** 2.0 integrated NaN where the base is negative
    # (a toughness "1 + (x - 4)**2" made the z-solve fail); whole exponents go as ints.
    import ngsolve as ngs
    from netgen.geom2d import unit_square

    mesh = ngs.Mesh(unit_square.GenerateMesh(maxh=0.3))
    value = ngs.Integrate(Expression("(x - 4)**2").to_coefficient(), mesh)
    assert abs(value - 37 / 3) < 1e-10  # int_0^1 (x - 4)^2 dx = (64 - 27)/3
    half = ngs.Integrate(Expression("(x + 4)**0.5").to_coefficient(), mesh)
    assert abs(half - 2 / 3 * (5 ** 1.5 - 8)) < 1e-9
