"""A scenario's parameters, declared once: a value is taken only inside its declared type and
range, the defaults fill what is not given, and an unknown name is refused naming the declared ones."""

import math

import pytest
from hypothesis import given
from hypothesis import strategies as st

from racf.experiments.scenarios import Param, Scenario
from racf.plugins import SCENARIOS

CARS = Param("cars", 1, 1, 4, unit="cars")
GAP = Param("gap_s", 0.0, -5.0, 5.0, unit="s")


@given(st.one_of(st.integers(-10, 10), st.floats(allow_nan=True, allow_infinity=True), st.booleans(), st.text()))
def test_an_accepted_value_has_the_declared_type_and_lies_in_range(value):
    for param in (CARS, GAP):
        try:
            taken = param.check(value, "s")
        except ValueError as err:
            assert param.name in str(err) and param.allowed() in str(err)
            continue
        assert type(taken) is param.type and param.low <= taken <= param.high and math.isfinite(taken)
        assert not isinstance(value, bool)


def test_values_fill_the_defaults_and_refuse_an_unknown_name():
    cross = SCENARIOS["cross_traffic"]
    assert cross.values({"gap_s": 1}) == {"cars": 1, "gap_s": 1.0, "speed": 1.0}
    with pytest.raises(ValueError, match=r"has no parameter\(s\) \['lanes'\]; its parameters: \['cars', 'gap_s', 'speed'\]"):
        cross.values({"lanes": 2})
    with pytest.raises(ValueError, match="its parameters: none"):
        Scenario.values({"x": 1})
