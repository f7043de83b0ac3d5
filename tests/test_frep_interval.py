"""Interval arithmetic and interval extensions: enclosures checked by brute-force sampling."""

import numpy as np
import pytest

from algorithms.frep.interval import Interval
from algorithms.frep.objects import FUNCTIONS, blobs, demo_object, from_expression, perturbed, sphere, torus
from algorithms.frep.sampling import quadtree_columns

rng = np.random.default_rng(7)


def _random_interval(n, scale=3.0):
    a = rng.uniform(-scale, scale, n)
    b = rng.uniform(-scale, scale, n)
    return Interval(np.minimum(a, b), np.maximum(a, b))


def _inside(iv, vals):
    return np.all((vals >= iv.lo[None] - 1e-12) & (vals <= iv.hi[None] + 1e-12))


def _samples(iv, k=41):
    t = np.linspace(0, 1, k)[:, None]
    return iv.lo[None] + t * (iv.hi - iv.lo)[None]


@pytest.mark.parametrize("op", ["add", "sub", "mul", "div", "sq", "cube", "pow4", "sqrt", "exp", "sin", "cos", "abs",
                                "min", "max", "pos3", "r_and", "r_or"])
def test_operations_enclose_all_values(op):
    x, y = _random_interval(200), _random_interval(200)
    xs = _samples(x)[:, None, :]
    ys = _samples(y)[None, :, :]
    f = {
        "add": (lambda a, b: a + b, lambda a, b: a + b),
        "sub": (lambda a, b: a - b, lambda a, b: a - b),
        "mul": (lambda a, b: a * b, lambda a, b: a * b),
        "div": (lambda a, b: a / b, lambda a, b: a / b),
        "sq": (lambda a, b: a**2, lambda a, b: a**2),
        "cube": (lambda a, b: a**3, lambda a, b: a**3),
        "pow4": (lambda a, b: a**4, lambda a, b: a**4),
        "sqrt": (lambda a, b: np.sqrt(np.abs(a)), lambda a, b: abs(a).sqrt()),
        "exp": (lambda a, b: np.exp(a), lambda a, b: a.exp()),
        "sin": (lambda a, b: np.sin(a), lambda a, b: a.sin()),
        "cos": (lambda a, b: np.cos(a), lambda a, b: a.cos()),
        "abs": (lambda a, b: np.abs(a), lambda a, b: abs(a)),
        "min": (lambda a, b: np.minimum(a, b), lambda a, b: a.minimum(b)),
        "max": (lambda a, b: np.maximum(a, b), lambda a, b: a.maximum(b)),
        "pos3": (lambda a, b: FUNCTIONS["pos3"].numeric(a), lambda a, b: FUNCTIONS["pos3"].interval(a)),
        "r_and": (FUNCTIONS["r_and"].numeric, FUNCTIONS["r_and"].interval),
        "r_or": (FUNCTIONS["r_or"].numeric, FUNCTIONS["r_or"].interval),
    }[op]
    with np.errstate(divide="ignore", invalid="ignore"):
        vals = f[0](xs, ys).reshape(-1, 200)
    iv = f[1](x, y)
    vals = np.where(np.isfinite(vals), vals, np.nan)
    ok = np.isnan(vals) | ((vals >= iv.lo[None] - 1e-9) & (vals <= iv.hi[None] + 1e-9))
    assert ok.all()


def test_square_is_exact_and_tighter_than_product():
    x = Interval(-1.0, 2.0)
    assert (x**2).lo <= 0 and (x**2).hi == pytest.approx(4.0)
    assert (x * x).lo == pytest.approx(-2.0)  # the naive product suffers the dependency problem


@pytest.mark.parametrize("obj", [sphere(), torus(), blobs(), perturbed(), demo_object("boxsphere")],
                         ids=["sphere", "torus", "blob", "perturbed", "boxsphere"])
def test_extension_never_excludes_a_box_that_holds_surface(obj):
    # random boxes of all sizes; brute force: F on a 9^3 grid inside each box
    n = 300
    size = rng.uniform(0.01, 0.8, (n, 3))
    lo = rng.uniform(-1, 1 - size)
    t = np.linspace(0, 1, 9)
    g = np.stack(np.meshgrid(t, t, t, indexing="ij"), -1).reshape(-1, 3)
    pts = lo[:, None, :] + g[None] * size[:, None, :]
    vals = obj.value(pts.reshape(-1, 3)).reshape(n, -1)
    iv = obj.interval(Interval(lo[:, 0], lo[:, 0] + size[:, 0]), Interval(lo[:, 1], lo[:, 1] + size[:, 1]),
                      Interval(lo[:, 2], lo[:, 2] + size[:, 2]))
    assert np.all(iv.lo <= vals.min(axis=1) + 1e-12)
    assert np.all(iv.hi >= vals.max(axis=1) - 1e-12)
    has_surface = (vals.min(axis=1) < 0) & (vals.max(axis=1) >= 0)
    assert has_surface.sum() > 20  # the test does look at boxes with surface
    assert np.all(iv.hi[has_surface] >= 0)  # never proven outside


@pytest.mark.parametrize("obj", [torus(), perturbed()], ids=["torus", "perturbed"])
def test_quadtree_keeps_every_column_with_surface(obj):
    qlev = 5
    cols, levels, _ = quadtree_columns(obj, qlev)
    n = 2**qlev
    kept = np.zeros((n, n), bool)
    kept[cols[:, 0], cols[:, 1]] = True
    # brute force: a dense grid of points in every cell's column
    k = 6
    t = (np.arange(k) + 0.5) / k
    ii, jj = np.meshgrid(np.arange(n), np.arange(n), indexing="ij")
    x = -1 + 2 * (ii[..., None] + t) / n
    y = -1 + 2 * (jj[..., None] + t) / n
    z = np.linspace(-1, 1, 81)
    X = np.broadcast_to(x[:, :, :, None, None], (n, n, k, k, 81))
    Y = np.broadcast_to(y[:, :, None, :, None], (n, n, k, k, 81))
    Z = np.broadcast_to(z, (n, n, k, k, 81))
    v = obj.value(np.stack([X, Y, Z], -1).reshape(-1, 3)).reshape(n, n, -1)
    inside_somewhere = v.max(axis=2) >= 0
    assert inside_somewhere.sum() > 50
    assert np.all(kept[inside_somewhere])
    assert kept.sum() < n * n  # and it does cull
    assert len(levels) == qlev + 1


def test_expression_objects_reject_unsafe_text():
    from algorithms.io import InputError

    with pytest.raises(InputError):
        from_expression("__import__('os').system('true')")
    with pytest.raises(InputError):
        from_expression("x.real + 1")
