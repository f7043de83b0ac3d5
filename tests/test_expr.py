import numpy as np
import pytest

from algorithms.expr import ExpressionError, Function, compile_defs, compile_expr


class Iv:
    """A minimal interval type for the test (lo <= hi)."""

    def __init__(self, lo, hi):
        self.lo, self.hi = float(lo), float(hi)

    @staticmethod
    def of(x):
        return x if isinstance(x, Iv) else Iv(x, x)

    def __add__(self, o):
        o = Iv.of(o)
        return Iv(self.lo + o.lo, self.hi + o.hi)

    __radd__ = __add__

    def __sub__(self, o):
        o = Iv.of(o)
        return Iv(self.lo - o.hi, self.hi - o.lo)

    def __rsub__(self, o):
        return Iv.of(o) - self

    def __neg__(self):
        return Iv(-self.hi, -self.lo)

    def __mul__(self, o):
        o = Iv.of(o)
        p = [self.lo * o.lo, self.lo * o.hi, self.hi * o.lo, self.hi * o.hi]
        return Iv(min(p), max(p))

    __rmul__ = __mul__

    def __pow__(self, n):
        assert n == 2
        lo, hi = sorted((abs(self.lo), abs(self.hi)))
        return Iv(0 if self.lo <= 0 <= self.hi else lo * lo, hi * hi)

    def sqrt(self):
        return Iv(np.sqrt(max(self.lo, 0)), np.sqrt(self.hi))


def test_numeric_on_arrays():
    e = compile_expr("0.16 - y**2 - z**2 + 2*pi*0")
    y = np.array([0.0, 0.4, 1.0])
    np.testing.assert_allclose(e(x=0, y=y, z=0), [0.16, 0.0, -0.84], atol=1e-15)
    assert e.used == frozenset({"y", "z"})


def test_builtins_and_custom_functions():
    r_and = Function(lambda a, b: a + b - np.sqrt(a * a + b * b), None, 2)
    e = compile_expr("r_and(x, y) + max(x, y, 0) + abs(-x)", functions={"r_and": r_and})
    assert e(x=1.0, y=1.0) == pytest.approx(2 - np.sqrt(2) + 1 + 1)


@pytest.mark.parametrize("text,msg", [
    ("__import__('os')", "unknown function"),
    ("x.real", "Attribute is not allowed"),
    ("(lambda: 1)()", "only plain function names"),
    ("x[0]", "Subscript is not allowed"),
    ("'abc'", "only numbers"),
    ("x if y else z", "IfExp is not allowed"),
    ("w + 1", "unknown name 'w'"),
    ("sqrt(x, y)", "takes 1 argument"),
    ("sqrt(x=1)", "keyword"),
    ("x // 2", "not allowed"),
    ("x +", "syntax error"),
    ("sqrt", "is a function"),
    ("True", "only numbers"),
])
def test_rejected(text, msg):
    with pytest.raises(ExpressionError, match=msg):
        compile_expr(text)


def test_interval_mode_encloses_samples():
    e = compile_expr("sqrt(x**2 + y**2) - 0.5")
    box = e.interval(x=Iv(0.1, 0.3), y=Iv(-0.2, 0.4), z=Iv(0, 1))
    xs, ys = np.meshgrid(np.linspace(0.1, 0.3, 21), np.linspace(-0.2, 0.4, 21))
    vals = e(x=xs, y=ys, z=0)
    assert box.lo <= vals.min() + 1e-12 and vals.max() <= box.hi + 1e-12


def test_function_without_interval_form_refuses_interval_mode():
    e = compile_expr("f(x)", functions={"f": Function(np.sin, None, 1)})
    with pytest.raises(ExpressionError, match="no interval extension"):
        e.interval(x=Iv(0, 1))


def test_defs_chain_and_fold_constants():
    d = compile_defs({"r": "0.4", "r2": "r*r", "hole": "y**2 + z**2 - r2", "keep": "-hole"})
    assert d["r2"]() == pytest.approx(0.16)
    assert d["keep"](x=0, y=0.0, z=0.0) == pytest.approx(0.16)
    with pytest.raises(ExpressionError, match="hide a variable"):
        compile_defs({"x": "1"})


def test_missing_variable_value():
    with pytest.raises(ExpressionError, match="needs a value for z"):
        compile_expr("x + z")(x=1)
