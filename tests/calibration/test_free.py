"""Free parameters: ``NAME=LO:HI[:log]``, the unit-cube mapping, rounding within bounds."""

from __future__ import annotations

import math

import pytest

from swarmtag.calibration import MAX_FREE, FreeParameter, parse_free, parse_free_list
from swarmtag.calibration.free import round_significant
from swarmtag.errors import CalibrationError


def test_linear_and_log_specs():
    assert parse_free("camera.range=0.5:3") == FreeParameter("camera.range", 0.5, 3.0)
    assert parse_free(" tick = 0.02 : 0.2 : log ") == FreeParameter("tick", 0.02, 0.2, log=True)
    assert parse_free("x=-1:1e1").spec == "x=-1.0:10.0"
    assert parse_free("tick=0.02:0.2:log").spec == "tick=0.02:0.2:log"


@pytest.mark.parametrize(
    ("text", "message"),
    [
        ("tick", "is not NAME=LO:HI"),
        ("=1:2", "is not NAME=LO:HI"),
        ("tick=1", "is not NAME=LO:HI"),
        ("tick=1:2:3:4", "is not NAME=LO:HI"),
        ("tick=1:2:ln", "scale 'ln' is not 'log'"),
        ("tick=a:2", "bound 'a' is not a number"),
        ("tick=0.2:0.1", "the bounds 0.2:0.1 are empty (need LO < HI)"),
        ("tick=0.1:0.1", "are empty"),
        ("tick=0:1:log", "a log scale needs LO > 0"),
        ("tick=nan:1", "bound nan is not finite"),
        ("tick=0:inf", "bound inf is not finite"),
    ],
)
def test_refusals(text, message):
    with pytest.raises(CalibrationError) as error:
        parse_free(text)
    assert message in str(error.value)
    assert "\n" not in str(error.value)


def test_lists_refuse_none_duplicates_and_too_many():
    with pytest.raises(CalibrationError, match="no free parameters"):
        parse_free_list([])
    with pytest.raises(CalibrationError, match="--free tick: given twice"):
        parse_free_list(["tick=0.1:0.2", "tick=0.1:0.3"])
    with pytest.raises(CalibrationError, match=f"at most {MAX_FREE}"):
        parse_free_list([f"k{i}=0:1" for i in range(MAX_FREE + 1)])


@pytest.mark.parametrize("log", [False, True])
def test_unit_mapping_spans_the_bounds_and_inverts(log):
    parameter = FreeParameter("p", 0.05, 5.0, log=log)
    assert parameter.from_unit(0.0) == 0.05
    assert parameter.from_unit(1.0) == 5.0
    assert parameter.from_unit(-0.5) == 0.05
    assert parameter.from_unit(1.5) == 5.0
    for u in (0.1, 0.37, 0.5, 0.9):
        assert math.isclose(parameter.to_unit(parameter.from_unit(u)), u, abs_tol=1e-12)
    middle = parameter.from_unit(0.5)
    expected = math.sqrt(0.05 * 5.0) if log else (0.05 + 5.0) / 2
    assert math.isclose(middle, expected)


def test_rounding_keeps_four_digits_and_stays_inside():
    assert round_significant(3.579599, 4) == 3.58
    assert round_significant(0.000123456, 4) == 0.0001235
    parameter = FreeParameter("p", 0.12344, 0.5)
    assert parameter.clamp_round(0.123441, 4) == 0.12344  # rounds to 0.1234 < LO: the bound
    assert parameter.clamp_round(0.3333333, 4) == 0.3333
    upper = FreeParameter("p", 0.1, 0.45678)
    assert upper.clamp_round(0.456779, 4) == 0.45678  # rounds to 0.4568 > HI: the bound
