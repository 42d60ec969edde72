"""Random streams and the per-tick random inputs (SPEC §4.5): the one place numbers are drawn.

Run ``i`` of master seed ``S`` owns independent generators
``np.random.default_rng(np.random.SeedSequence(S, spawn_key=(i, k)))``:

==  ==========  =============================================================
k   stream      draws
==  ==========  =============================================================
0   scene       the initial scene (``swarmtag.sim.model.scene``), never the policy
1   motion      per tick ``standard_normal((N, 4))``: columns 0-1 a random-walk
                direction, 2-3 a sidestep direction (each normalised)
2   breakdown   per tick ``random(N)``: robot ``r`` breaks down if < p
3   radio       per tick ``random((N, C))``: robot ``r`` misses carrier ``c``'s
                advertisement if < p
4   camera      per tick ``standard_normal((N, C, 2))``: detection noise,
                times sigma, added to carrier ``c``'s position as seen by ``r``
5   walk        per tick ``random(N)``: robot ``r``'s walk turn angle
                ``(2u - 1) * a`` for the largest turn ``a`` (a curved walk:
                its largest turn per tick), as the unit vector ``(cos, sin)``
                (the one place an angle meets a transcendental function,
                outside every kernel)
6   sight       per tick ``random((N, C))``: with a camera fade, robot ``r``
                sees carrier ``c`` only within ``far - u * fade``
                (``camera_far``: the range plus half the fade), a linear
                detection ramp centred on the camera range
7   rssi        per tick ``standard_normal((N, C))``: with BLE-led search,
                the distance robot ``r`` reads from carrier ``c``'s RSSI is
                the true one times ``10 ** (g * rssi_sigma)`` (``rssi_factors``,
                outside every kernel like the walk's turns)
8   odometry    per tick ``standard_normal((N, 2))``: with odometry drift,
                robot ``r``'s odometry error grows by ``g * drift *
                sqrt(moved)`` (``moved``: metres driven since last tick)
9   allocation  per tick ``random((N, C + N))``: under an allocator that draws
                (``swarmtag.sim.allocators``), columns ``0 .. C-1`` robot
                ``r``'s draw for carrier ``c`` (the response threshold's),
                ``C + j`` for its message to robot ``j`` (CBAA's loss)
==  ==========  =============================================================

Every tick draws the full block of each stream, used or not, so no number
depends on what other robots did. Streams 2-9 are only drawn when their
option is on; being separate streams, switching one on changes no other
number. Blocks for many ticks are drawn at once (``chunk``), which gives the
same numbers as drawing tick by tick. A normalised direction is
``(g0, g1) / sqrt(g0*g0 + g1*g1)`` (``(1, 0)`` in the measure-zero case
g0 = g1 = 0).
"""

from __future__ import annotations

from dataclasses import dataclass
from enum import IntEnum
from typing import Final

import numpy as np
from numpy.typing import ArrayLike, NDArray

from swarmtag._checks import MAX_SEED, check_int
from swarmtag.errors import ConfigError
from swarmtag.sim.config.parts import Reprioritisation
from swarmtag.sim.model.geometry import Float, length
from swarmtag.sim.model.params import Params

__all__ = [
    "RandomSource",
    "Stream",
    "TickInputs",
    "check_seed",
    "due_writes",
    "rssi_factors",
    "rssi_on",
    "stream",
    "unit_vectors",
    "walk_drawn",
    "walk_turns",
]

_BLOCK_BYTES: Final = 16 * 2**20
"""Pre-draw at most about this many bytes per run and stream (a memory bound, not a result)."""
_MAX_CHUNK: Final = 256


class Stream(IntEnum):
    """The second element of a run's spawn key: which purpose a generator serves."""

    SCENE = 0
    MOTION = 1
    BREAKDOWN = 2
    RADIO = 3
    CAMERA = 4
    WALK = 5
    SIGHT = 6
    RSSI = 7
    ODOMETRY = 8
    ALLOCATION = 9


def check_seed(seed: object) -> int:
    """A master seed: an integer in 0 .. 2**63 - 1 (stored as int64 in logs and the store)."""
    return check_int("seed", seed, low=0, high=MAX_SEED)


def stream(seed: int, run: int, purpose: Stream) -> np.random.Generator:
    """The generator of ``purpose`` for global run ``run`` of master seed ``seed``.

    >>> float(stream(0, 3, Stream.SCENE).random()) == float(stream(0, 3, Stream.SCENE).random())
    True
    """
    return np.random.default_rng(np.random.SeedSequence(seed, spawn_key=(run, int(purpose))))


def unit_vectors(gaussians: Float) -> Float:
    """Normalise pairs of Gaussian numbers (last axis 2) into unit vectors.

    >>> unit_vectors(np.array([[3.0, 4.0], [0.0, 0.0]]))
    array([[0.6, 0.8],
           [1. , 0. ]])
    """
    norm = length(gaussians)
    zero = norm == 0
    safe = np.where(zero, 1.0, norm)
    unit = gaussians / safe[..., None]
    return np.where(zero[..., None], np.array([1.0, 0.0]), unit)


def walk_drawn(params: Params) -> bool:
    """Whether runs of ``params`` draw the walk stream: a turning or a curved walk."""
    return params.walk_turn_ticks > 0 or params.walk_curve > 0


def walk_turns(uniform: Float, params: Params) -> Float:
    """Walk turns ``(cos, sin)`` (last axis) from the walk stream's uniform numbers.

    The angle is ``(2u - 1) * walk_turn_angle`` (a curved walk:
    ``walk_curve``, a turn per tick); every backend takes its turns from
    here, so the one transcendental step is the same numpy call.
    """
    largest = params.walk_curve if params.walk_curve > 0 else params.walk_turn_angle
    angle = (2.0 * uniform - 1.0) * largest
    turns: Float = np.stack((np.cos(angle), np.sin(angle)), axis=-1)
    return turns


def rssi_on(params: Params) -> bool:
    """Whether runs of ``params`` draw the RSSI stream: BLE-led search with shadowing."""
    return params.radio_search and params.rssi_sigma > 0


def rssi_factors(gaussians: Float, params: Params) -> Float:
    """Error factors of RSSI distances from the rssi stream's Gaussian numbers.

    ``10 ** (g * rssi_sigma)``: log-normal shadowing of ``shadowing`` dB in
    the log-distance path-loss model. Every backend takes its factors from
    here (one numpy call, as for the walk's turns).
    """
    factors: Float = np.power(10.0, gaussians * params.rssi_sigma)
    return factors


@dataclass(frozen=True, eq=False)
class TickInputs:
    """The random numbers of one tick, already turned into what the kernel uses.

    ``walk`` and ``sidestep`` are unit vectors (R, N, 2); ``breakdown`` (R, N)
    says who breaks down; ``heard`` (R, N, C) who receives whose advertisement
    (``None``: everyone hears everything in range); ``noise`` (R, N, C, 2) is
    the detection error in metres (``None``: exact); ``turn`` (R, N, 2) is
    each robot's walk turn as ``(cos, sin)`` (``None``: the walk does not turn);
    ``sight`` (R, N, C) how far each robot sees each carrier this tick
    (``None``: ``camera_range``, a hard disc); ``rssi`` (R, N, C) the error
    factor of the distance each robot reads from each tag's RSSI (``None``:
    exact, or no BLE-led search); ``odometry`` (R, N, 2) the Gaussian
    numbers of each robot's odometry error this tick (``None``: no drift);
    ``allocation`` (R, N, C + N) an allocator's uniform numbers (``None``:
    none drawn).
    """

    walk: Float
    sidestep: Float
    breakdown: NDArray[np.bool_]
    heard: NDArray[np.bool_] | None = None
    noise: Float | None = None
    turn: Float | None = None
    sight: Float | None = None
    rssi: Float | None = None
    odometry: Float | None = None
    allocation: Float | None = None
    writes: tuple[Reprioritisation, ...] = ()

    @classmethod
    def fixed(
        cls,
        runs: int,
        robots: int,
        *,
        walk: ArrayLike = (1.0, 0.0),
        sidestep: ArrayLike = (0.0, 1.0),
        breakdown: ArrayLike = False,
        writes: tuple[Reprioritisation, ...] = (),
    ) -> TickInputs:
        """Inputs with given values broadcast to the batch (hand-built tests and examples).

        ``writes`` are the operator writes due this tick (see ``due_writes``).

        >>> TickInputs.fixed(1, 2, walk=(0.0, -1.0)).walk
        array([[[ 0., -1.],
                [ 0., -1.]]])
        """
        shape = (runs, robots)
        return cls(
            walk=np.broadcast_to(np.asarray(walk, dtype=np.float64), (*shape, 2)).copy(),
            sidestep=np.broadcast_to(np.asarray(sidestep, dtype=np.float64), (*shape, 2)).copy(),
            breakdown=np.broadcast_to(np.asarray(breakdown, dtype=bool), shape).copy(),
            writes=writes,
        )


def due_writes(params: Params, tick: int) -> tuple[Reprioritisation, ...]:
    """The scenario's operator writes scheduled for ``tick``, in schedule order."""
    return tuple(w for w in params.scenario.reprioritisations if w.tick == tick)


class RandomSource:
    """The per-tick inputs of a batch of seeded runs, drawn from the runs' own streams.

    Call ``inputs(t)`` for t = 1, 2, ... in order. Blocks are pre-drawn
    ``chunk`` ticks at a time per run (same numbers as tick by tick). The
    inputs also carry the scenario's operator writes due at each tick.
    """

    def __init__(
        self, params: Params, *, seed: int, run_ids: ArrayLike, chunk: int | None = None
    ) -> None:
        self._params = params
        self._runs = [int(run) for run in np.asarray(run_ids, dtype=np.int64).reshape(-1)]
        seed = check_seed(seed)
        n, c = params.robots, params.carriers
        self._purposes: dict[Stream, tuple[int, ...]] = {Stream.MOTION: (n, 4)}
        if params.breakdown > 0:
            self._purposes[Stream.BREAKDOWN] = (n,)
        if params.advertisement_loss > 0:
            self._purposes[Stream.RADIO] = (n, c)
        if params.detection_noise > 0:
            self._purposes[Stream.CAMERA] = (n, c, 2)
        if walk_drawn(params):
            self._purposes[Stream.WALK] = (n,)
        if params.camera_fade > 0:
            self._purposes[Stream.SIGHT] = (n, c)
        if rssi_on(params):
            self._purposes[Stream.RSSI] = (n, c)
        if params.odometry_drift > 0:
            self._purposes[Stream.ODOMETRY] = (n, 2)
        if getattr(params.policy, "draws", False):
            self._purposes[Stream.ALLOCATION] = (n, c + n)
        if chunk is None:
            largest = max(int(np.prod(shape)) for shape in self._purposes.values())
            chunk = max(1, min(_MAX_CHUNK, _BLOCK_BYTES // (8 * largest)))
        if chunk < 1:
            msg = f"chunk: {chunk} is not an integer >= 1"
            raise ConfigError(msg)
        self._chunk = chunk
        self._generators = {
            purpose: [stream(seed, run, purpose) for run in self._runs]
            for purpose in self._purposes
        }
        self._blocks: dict[Stream, NDArray[np.float64]] = {}
        self._first = 1  # tick of the first block row
        self._next = 1

    def _draw(self, ticks: int) -> None:
        for purpose, shape in self._purposes.items():
            uniform = purpose in (
                Stream.BREAKDOWN,
                Stream.RADIO,
                Stream.WALK,
                Stream.SIGHT,
                Stream.ALLOCATION,
            )
            blocks = [
                g.random((ticks, *shape)) if uniform else g.standard_normal((ticks, *shape))
                for g in self._generators[purpose]
            ]
            # (ticks, R, ...) so that one tick's rows are one slice
            self._blocks[purpose] = np.stack(blocks, axis=1)

    def inputs(self, tick: int) -> TickInputs:
        """The inputs of tick ``tick`` (1-based; ticks must be asked for in order)."""
        if tick != self._next:
            msg = f"tick: asked for {tick}, the next tick of this source is {self._next}"
            raise ConfigError(msg)
        self._next += 1
        row = tick - self._first
        if not self._blocks or row >= self._chunk:
            self._draw(self._chunk)
            self._first, row = tick, 0
        motion = self._blocks[Stream.MOTION][row]
        params = self._params
        heard = noise = turn = sight = rssi = odometry = allocation = None
        breakdown = np.zeros(motion.shape[:2], dtype=bool)
        if Stream.BREAKDOWN in self._blocks:
            breakdown = self._blocks[Stream.BREAKDOWN][row] < params.breakdown
        if Stream.RADIO in self._blocks:
            heard = ~(self._blocks[Stream.RADIO][row] < params.advertisement_loss)
        if Stream.CAMERA in self._blocks:
            noise = self._blocks[Stream.CAMERA][row] * params.detection_noise
        if Stream.WALK in self._blocks:
            turn = walk_turns(self._blocks[Stream.WALK][row], params)
        if Stream.SIGHT in self._blocks:
            sight = params.camera_far - self._blocks[Stream.SIGHT][row] * params.camera_fade
        if Stream.RSSI in self._blocks:
            rssi = rssi_factors(self._blocks[Stream.RSSI][row], params)
        if Stream.ODOMETRY in self._blocks:
            odometry = self._blocks[Stream.ODOMETRY][row]
        if Stream.ALLOCATION in self._blocks:
            allocation = self._blocks[Stream.ALLOCATION][row]
        return TickInputs(
            walk=unit_vectors(motion[..., 0:2]),
            sidestep=unit_vectors(motion[..., 2:4]),
            breakdown=breakdown,
            heard=heard,
            noise=noise,
            turn=turn,
            sight=sight,
            rssi=rssi,
            odometry=odometry,
            allocation=allocation,
            writes=due_writes(params, tick),
        )
