import dataclasses

import pytest

from algorithms.params import FieldParams


def test_defaults_are_valid_and_round_trip():
    p = FieldParams()
    assert p.mode == "light" and not p.shielding
    assert FieldParams.from_dict(p.as_dict()) == p
    assert dataclasses.replace(p, mode="full").shielding


@pytest.mark.parametrize("kw,name", [
    ({"mode": "medium"}, "mode"), ({"ki": -1}, "ki"), ({"kt": 1.0}, "kt"), ({"kt": 0}, "kt"),
    ({"lc": -2}, "lc"), ({"tracer": "rk4"}, "tracer"), ({"max_steps": 0}, "max_steps"),
    ({"threshold": 2}, "threshold"), ({"ki": float("nan")}, "ki"), ({"q1_kernel": "box"}, "q1_kernel"),
])
def test_invalid_values_name_the_parameter(kw, name):
    with pytest.raises(ValueError, match=f"parameter {name}="):
        FieldParams(**kw)


def test_unknown_keys_rejected():
    with pytest.raises(ValueError, match="unknown parameters: colour"):
        FieldParams.from_dict({"colour": 1})
