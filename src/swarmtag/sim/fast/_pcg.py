"""numpy's PCG64 generator and its Gaussian ziggurat in compiled code, bit for bit.

The tick's random numbers (``_draws``) were drawn through numba's typed
``np.random.Generator``: every number is a call through the bit generator's
function pointer, and the ziggurat negates on a branch that goes either way
at random. Here the generator's 128-bit state lives in registers while a
loop draws (LLVM's ``i128`` arithmetic, emitted by ``numba.extending.intrinsic``),
the step is inlined, and the sign is a multiplication by +-1 (exact):
9.2 -> 4.4 ns a Gaussian number and 2.8 -> 2.3 ns a uniform one on this
project's two-core machine, the same bits (``tests/sim/fast/test_pcg.py``
checks millions of numbers against numpy's own).

The algorithms are numpy's: PCG64 (XSL-RR output of the 128-bit LCG, one
step per 64-bit number), ``random()`` as the top 53 bits times 2**-53, and
``standard_normal`` as numpy's 256-layer ziggurat (``_ziggurat_tables``). A
generator's state is four ``uint64``
words (``STATE_WORDS``): the LCG state's high and low halves, then the
increment's; ``states_of`` reads them off numpy generators.
"""

# numba's intrinsic and code-generation interfaces are untyped: their arguments are Any here.
# ruff: noqa: ANN401

from __future__ import annotations

import math
from collections.abc import Sequence
from importlib import resources
from typing import Any, Final

import numpy as np
from llvmlite import ir  # type: ignore[import-untyped]
from numba import types
from numba.extending import intrinsic

from swarmtag.sim.fast._jit import inlined, jit

__all__ = ["STATE_WORDS", "next_uint64", "standard_normal", "states_of", "uniform"]

STATE_WORDS: Final = 4
"""uint64 words of a generator's state: LCG state high, low; increment high, low."""
_MULTIPLIER: Final = (2549297995355413924 << 64) + 4865540595714422341
"""PCG's default 128-bit LCG multiplier (numpy's ``PCG_DEFAULT_MULTIPLIER_128``)."""
_LOW: Final = (1 << 64) - 1
_pair_type: Any = types.UniTuple
_ZIGGURAT_FILE: Final = "ziggurat.npz"
"""The ziggurat's tables, package data beside this module (see ``_ziggurat_tables``)."""


def _ziggurat_tables() -> dict[str, np.ndarray]:
    """The tables of numpy's ziggurat for the standard normal, read from ``ziggurat.npz``.

    The numbers are numpy's (``ki_double``, ``wi_double``, ``fi_double``,
    ``ziggurat_nor_r`` and ``ziggurat_nor_inv_r`` of its
    ``random/src/distributions/ziggurat_constants.h``, as numba copies them
    for its own ``standard_normal``): the 256-layer ziggurat of Marsaglia and
    Tsang ("The Ziggurat Method for Generating Random Variables", Journal of
    Statistical Software 5(8), 2000) for 52-bit magnitudes. ``ki`` (256
    ``uint64``): a layer's acceptance bound on the magnitude; ``wi`` (256
    ``float64``): its width, the magnitude's scale; ``fi`` (256 ``float64``):
    the density at its edge; ``r`` (0-d): where the tail starts, ``inv_r`` its
    inverse. Copied once from numba's copy; ``tests/sim/fast/test_pcg.py``
    checks draws made with them against numpy's own, bit for bit.
    """
    data = resources.files("swarmtag.sim.fast") / _ZIGGURAT_FILE
    with data.open("rb") as file, np.load(file, allow_pickle=False) as tables:
        return {name: tables[name] for name in tables.files}


_TABLES: Final = _ziggurat_tables()
_KI: Final = _TABLES["ki"].astype(np.int64)
"""The ziggurat's acceptance bounds (below 2**52: signed, a cheaper conversion)."""
_WI: Final = np.asarray(_TABLES["wi"], dtype=np.float64)
_FI: Final = np.asarray(_TABLES["fi"], dtype=np.float64)
_R: Final = float(_TABLES["r"])
_INV_R: Final = float(_TABLES["inv_r"])
_TO_UNIT: Final = 1.0 / 9007199254740992.0
"""2**-53: ``random()`` from the top 53 bits."""


def states_of(generators: Sequence[np.random.Generator]) -> np.ndarray:
    """The states of numpy PCG64 generators, shape (len, ``STATE_WORDS``) ``uint64``.

    Drawing from the array leaves the generators where they were; the array
    carries on from their place.
    """
    states = np.zeros((len(generators), STATE_WORDS), dtype=np.uint64)
    for row, generator in enumerate(generators):
        state = generator.bit_generator.state
        if state["bit_generator"] != "PCG64":
            msg = f"the compiled kernel draws from PCG64 generators, not {state['bit_generator']}"
            raise ValueError(msg)
        lcg, increment = int(state["state"]["state"]), int(state["state"]["inc"])
        states[row] = (lcg >> 64, lcg & _LOW, increment >> 64, increment & _LOW)
    return states


def _step_typed(_typing: Any, high: Any, low: Any, inc_high: Any, inc_low: Any) -> Any:
    """The LCG's step ``state * multiplier + increment`` mod 2**128; returns (high, low)."""

    def codegen(context: Any, builder: Any, signature: Any, args: Any) -> Any:
        wide, word = ir.IntType(128), ir.IntType(64)
        shift = ir.Constant(wide, 64)

        def joined(upper: Any, lower: Any) -> Any:
            return builder.or_(
                builder.shl(builder.zext(upper, wide), shift), builder.zext(lower, wide)
            )

        state = joined(args[0], args[1])
        stepped = builder.add(builder.mul(state, ir.Constant(wide, _MULTIPLIER)), joined(*args[2:]))
        upper = builder.trunc(builder.lshr(stepped, shift), word)
        lower = builder.trunc(stepped, word)
        return context.make_tuple(builder, signature.return_type, [upper, lower])

    word_type = types.uint64
    return _pair_type(word_type, 2)(word_type, word_type, word_type, word_type), codegen


_step: Any = intrinsic(_step_typed)


@inlined
def next_uint64(
    high: np.uint64, low: np.uint64, inc_high: np.uint64, inc_low: np.uint64
) -> tuple[np.uint64, np.uint64, np.uint64]:
    """Numpy's ``pcg64_next64``: (number, new state high, new state low)."""
    high, low = _step(high, low, inc_high, inc_low)
    folded = high ^ low
    rotation = high >> np.uint64(58)
    left = (np.uint64(64) - rotation) & np.uint64(63)
    return (folded >> rotation) | (folded << left), high, low


@inlined
def uniform(
    high: np.uint64, low: np.uint64, inc_high: np.uint64, inc_low: np.uint64
) -> tuple[float, np.uint64, np.uint64]:
    """``Generator.random()``: (number in [0, 1), new state high, new state low)."""
    bits, high, low = next_uint64(high, low, inc_high, inc_low)
    return float(bits >> np.uint64(11)) * _TO_UNIT, high, low


@jit
def _beyond_the_layers(
    layer: np.int64,
    magnitude: np.int64,
    x: float,
    high: np.uint64,
    low: np.uint64,
    inc_high: np.uint64,
    inc_low: np.uint64,
) -> tuple[float, bool, np.uint64, np.uint64]:
    """The ziggurat's rare cases (0.7 % of draws): (number, accepted, new state high, low).

    The tail beyond r (layer 0) always gives a number; a wedge may reject
    ``x`` (then the caller draws again). A call rather than inlined: the
    kernels inline ``standard_normal`` at many places, and this part, with
    its logarithms and loop, is most of its code.
    """
    if layer == 0:  # the tail beyond r
        while True:
            first, high, low = uniform(high, low, inc_high, inc_low)
            second, high, low = uniform(high, low, inc_high, inc_low)
            xx = -_INV_R * math.log1p(-first)
            yy = -math.log1p(-second)
            if yy + yy > xx * xx:
                tail = _R + xx
                return (-tail if (magnitude >> 8) & 1 else tail), True, high, low
    height, high, low = uniform(high, low, inc_high, inc_low)
    accepted = (_FI[layer - 1] - _FI[layer]) * height + _FI[layer] < math.exp(-0.5 * x * x)
    return x, accepted, high, low


@inlined
def standard_normal(
    high: np.uint64, low: np.uint64, inc_high: np.uint64, inc_low: np.uint64
) -> tuple[float, np.uint64, np.uint64]:
    """``Generator.standard_normal()``: (number, new state high, new state low)."""
    while True:
        bits, high, low = next_uint64(high, low, inc_high, inc_low)
        layer = np.int64(bits & np.uint64(0xFF))
        magnitude = np.int64((bits >> np.uint64(9)) & np.uint64(0x000FFFFFFFFFFFFF))
        sign = 1.0 - 2.0 * float((bits >> np.uint64(8)) & np.uint64(1))
        x = float(magnitude) * _WI[layer] * sign  # times +-1: exact, and no branch to mispredict
        if magnitude < _KI[layer]:
            return x, high, low  # 99.3 % of the numbers
        number, accepted, high, low = _beyond_the_layers(
            layer, magnitude, x, high, low, inc_high, inc_low
        )
        if accepted:
            return number, high, low
