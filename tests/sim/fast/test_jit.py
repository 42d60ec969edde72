"""The kernel's numba decorators: one compilation per argument type, no Python calls inside."""

import pytest
from numba.core import types

from swarmtag.sim.fast._events import emit
from swarmtag.sim.fast._grid import table_bits
from swarmtag.sim.fast._jit import entry, inlined, jit


@jit
def _doubled(value: int) -> int:
    return 2 * value


@inlined
def _tripled(value: int) -> int:
    return 3 * value


@entry
def _sum_of(value: int) -> int:
    return _doubled(value) + _tripled(value)


def test_constants_passed_as_arguments_compile_once_as_their_plain_type():
    for dispatcher in (_doubled, _tripled):
        for constant in (1, 2, 7):
            dispatcher.compile((types.literal(constant),))
        assert dispatcher.signatures == [(types.int64,)]


def test_entry_points_are_called_from_python_and_call_compiled_functions():
    assert _sum_of(4) == 20
    assert table_bits(1000) == 6


@pytest.mark.parametrize("compiled_only", [_doubled, _tripled, emit])
def test_functions_without_a_python_wrapper_refuse_python_calls(compiled_only):
    with pytest.raises(TypeError, match="compiled code only"):
        compiled_only(1)
