"""The world state: robots, carriers and tags as arrays with a leading run axis.

``WorldState`` is what the step kernel maps to the next tick's state. Shapes
use R runs, N robots, C carriers and D the status-propagation delay. Robot
``i`` of a run is robot id ``i``; carrier ``c`` carries marker id ``c``.
Times are tick numbers, ``-1`` meaning never. A ``Scene`` holds one run's
start (sampled by ``swarmtag.sim.model.scene`` or written by hand in tests);
``initial_state`` stacks scenes into a batch.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, fields, replace
from enum import IntEnum
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from swarmtag.errors import ConfigError
from swarmtag.sim.model.geometry import Float, length
from swarmtag.sim.model.params import Params
from swarmtag.sim.world.predock import free_faces
from swarmtag.tag import TagStatus
from swarmtag.tag.advertising import phase_microseconds

__all__ = ["Int", "Mode", "Scene", "WorldState", "initial_state"]

Int = NDArray[np.int64]


class Mode(IntEnum):
    """A robot's behaviour (SPEC §3.2), one value per robot per tick."""

    WALK = 0
    """Random walk, looking for a carrier."""
    PREDOCK = 1
    """Driving to the chosen face's predock point and turning to face the carrier."""
    DOCK = 2
    """Driving in under the carrier, towards its centre."""
    CENTRE = 3
    """Centred under the carrier, aligning on its underside marker (dock duration)."""
    LIFT = 4
    """Carrier lifted (tag PICKED_UP), lifting mechanism rising (lift duration)."""
    TRANSPORT = 5
    """Carrying the carrier to the drop-off area."""
    RELEASE = 6
    """In the drop-off area, lowering the carrier (release duration)."""
    BROKEN = 7
    """Broken down for good; an obstacle, holding its carrier if it had one."""


@dataclass(frozen=True, eq=False)
class WorldState:
    """Everything that changes during a batch of runs, after ``tick`` ticks.

    The dataclass is frozen and ``step`` never modifies the arrays of the
    state it is given; treat them as read-only.
    """

    tick: int
    run_ids: Int
    """(R,) global run index of each row."""
    # robots
    robot_pos: Float
    """(R, N, 2) centre, metres."""
    heading: Float
    """(R, N, 2) unit vector the robot faces."""
    walk: Float
    """(R, N, 2) unit random-walk direction."""
    speed: Float
    """(R, N) metres per tick (nominal step times the robot's speed factor)."""
    mode: NDArray[np.int8]
    """(R, N) ``Mode``."""
    target: Int
    """(R, N) carrier pursued, carried or being released; -1 none."""
    face: Int
    """(R, N) predock face of the pursuit (0 E, 1 N, 2 W, 3 S); -1 none."""
    pursuit_start: Int
    """(R, N) tick the pursuit began."""
    timer: Int
    """(R, N) ticks left in CENTRE, LIFT or RELEASE."""
    ghost: Int
    """(R, N) carrier the robot may overlap (it is under it, docking or driving out); -1 none."""
    redirect: NDArray[np.bool_]
    """(R, N) pick a new random-walk direction at the next decision."""
    contact: Float
    """(R, N, 2) how far collision resolution moved the robot last tick (contact normal)."""
    stuck: Int
    """(R, N) consecutive ticks a loaded robot made too little progress."""
    sidestep: Int
    """(R, N) ticks of random sidestep left."""
    sidestep_dir: Float
    """(R, N, 2) unit direction of the current sidestep."""
    goal: Float
    """(R, N, 2) transport goal in the drop-off area."""
    blocked_until: Int
    """(R, N, C) first tick at which the robot may select the carrier again (cool-down).

    This and the other (R, N, C) arrays below have no carriers on their last
    axis in the compiled backend's states where it keeps its robots' tag
    caches as lists (``params.sparse_tag_cache``).
    """
    known_status: NDArray[np.int8]
    """(R, N, C) status last heard from each tag; -1 never heard."""
    known_urgency: NDArray[np.int8]
    """(R, N, C) urgency last heard from each tag (0 if never heard)."""
    heard_tick: Int
    """(R, N, C) tick in which the robot last heard each tag; -1 never (the cache's age)."""
    seen_tick: Int
    """(R, N, C) tick in which the robot's camera last saw each carrier; -1 never."""
    seen_pos: Float
    """(R, N, C, 2) where the camera saw each carrier then (true position plus camera noise)."""
    rssi: Float
    """(R, N, C) each robot's running distance estimate to each tag from its RSSI (BLE-led
    search; meaningful once the tag was heard, 0 before)."""
    walk_clock: Int
    """(R, N) ticks since the walking robot last took a new heading (correlated walk)."""
    seek: Int
    """(R, N) the tag a walking robot seeks by its signal (BLE-led search); -1 none."""
    seek_ref: Float
    """(R, N) the seeker's estimate of its tag's distance when it last compared one."""
    curve: Float
    """(R, N, 2) a curved walk's turn per tick on the current leg as ``(cos, sin)``; ``(0, 0)``
    before the first is drawn."""
    look: Int
    """(R, N) the tick a walking robot began to look round (it stands and turns); -1 not."""
    odometry: Float
    """(R, N, 2) the robot's odometry error: where it believes it is minus where it is."""
    odometry_at: Float
    """(R, N, 2) where the robot was when its odometry error last grew (the last tick)."""
    # carriers and their tags
    carrier_pos: Float
    """(R, C, 2) centre, metres."""
    status: NDArray[np.int8]
    """(R, C) the tag's true status (``TagStatus``)."""
    urgency: NDArray[np.int8]
    """(R, C) the tag's true urgency."""
    present: NDArray[np.bool_]
    """(R, C) still in the arena (False once delivered)."""
    carried_by: Int
    """(R, C) robot holding the carrier; -1 none."""
    w0: Float
    """(R, C) growing model's initial waiting time; NaN once growth stops or if it never grows."""
    urgency0: NDArray[np.int8]
    """(R, C) urgency at run start."""
    order_time: Float
    """(R, C) order (target) time, ticks, <= 0."""
    free_face: NDArray[np.bool_]
    """(R, C, 4) usable predock faces."""
    advert_phase: Int
    """(R, C) microseconds into the advertising interval at which each tag advertises."""
    adv_status: NDArray[np.int8]
    """(R, D + 1, C) tag status at the end of recent ticks, slot ``t % (D + 1)`` for tick t."""
    adv_urgency: NDArray[np.int8]
    """(R, D + 1, C) tag urgency, same slots."""
    pickup_time: Int
    """(R, C) tick of the lift; -1 never."""
    delivery_time: Int
    """(R, C) tick of the release in the drop-off area; -1 never."""
    deliverer: Int
    """(R, C) robot that delivered it; -1 none."""
    delivery_urgency: NDArray[np.int8]
    """(R, C) the tag's urgency when it was delivered; -1 not delivered."""
    ended_at: Int
    """(R,) tick at which the run ended (all carriers delivered or time limit); -1 running."""
    operator_counter: Int
    """(R,) the last counter the run's operator (WMS) signed a write with; -1 none yet."""
    # orders (warehouses; in the lab every carrier is due at 0, destination 0, no slot)
    due: Int
    """(R, C) tick at which the order enters the pick-up queue (0: waiting at the start)."""
    arrival_time: Int
    """(R, C) tick at which the carrier was placed in the pick-up area; -1 not yet."""
    destination: Int
    """(R, C) the drop-off area to deliver to, as an index into the floor map's destinations."""
    slot: Int
    """(R, C) pick-up slot the carrier was placed on; -1 none (the lab places freely)."""
    slot_pick: Float
    """(R, C) uniform number in [0, 1) choosing the order's slot among the free ones."""

    @property
    def runs(self) -> int:
        """Number of runs in the batch."""
        return int(self.run_ids.shape[0])

    def copy(self, **changes: Any) -> WorldState:  # noqa: ANN401 - any field's value
        """The same state with fresh copies of every array; the fields in ``changes`` set instead.

        One construction, and no copy of an array that ``changes`` replaces:
        the reference copies the state once a tick.
        """
        values: dict[str, Any] = {
            name: value.copy() if isinstance(value, np.ndarray) else value
            for name in _FIELD_NAMES
            if name not in changes
            for value in (getattr(self, name),)
        }
        return WorldState(**values, **changes)

    def select_runs(self, rows: ArrayLike) -> WorldState:
        """The state of some runs only (by position in the batch), as a new batch."""
        index = np.asarray(rows)
        arrays = {
            f.name: getattr(self, f.name)[index].copy()
            for f in fields(self)
            if isinstance(getattr(self, f.name), np.ndarray)
        }
        return replace(self, **arrays)


_FIELD_NAMES: tuple[str, ...] = tuple(f.name for f in fields(WorldState))
"""``WorldState``'s fields, in order (``fields`` walks the class on every call)."""


def _array(name: str, value: ArrayLike, shape: tuple[int, ...], dtype: type) -> NDArray[Any]:
    array: NDArray[Any] = np.array(value, dtype=dtype)
    if array.shape != shape:
        msg = f"{name}: shape {array.shape} is not {shape}"
        raise ConfigError(msg)
    return array


@dataclass(frozen=True, eq=False)
class Scene:
    """One run's initial conditions: where robots and carriers are and how urgent.

    Positions are metres, ``heading`` unit vectors (default +x), ``speed_factor``
    multiplies the nominal speed (default 1). ``w0`` is the growing model's
    initial waiting time (NaN: the urgency does not grow); ``status`` defaults
    to AWAITING_PICKUP; ``advert_phase`` (default 0) is where in its
    advertising interval each tag advertises, as a fraction in [0, 1).
    Shapes are checked by ``initial_state``.
    """

    robot_pos: Float
    carrier_pos: Float
    urgency0: NDArray[np.int8]
    order_time: Float
    w0: Float
    heading: Float
    speed_factor: Float
    status: NDArray[np.int8]
    advert_phase: Float
    due: Int | None = None
    """Warehouse orders: tick each enters the pick-up queue (None: all 0, present at start)."""
    destination: Int | None = None
    """Drop-off area of each carrier, an index into the floor's destinations (None: all 0)."""
    slot: Int | None = None
    """Pick-up slot of each carrier present at the start (None or -1: placed freely)."""
    slot_pick: Float | None = None
    """Uniform numbers choosing each later order's slot (None: all 0)."""

    @classmethod
    def build(
        cls,
        *,
        robots: ArrayLike,
        carriers: ArrayLike,
        urgency: ArrayLike | None = None,
        order_time: ArrayLike | None = None,
        w0: ArrayLike | None = None,
        heading: ArrayLike | None = None,
        speed_factor: ArrayLike | None = None,
        status: ArrayLike | None = None,
        advert_phase: ArrayLike | None = None,
    ) -> Scene:
        """A scene from lists, with defaults for what is left out (tests, examples).

        >>> s = Scene.build(robots=[(1.0, 1.0)], carriers=[(0.5, 2.0)], urgency=[7])
        >>> s.robot_pos.shape, s.urgency0, s.order_time, s.heading
        ((1, 2), array([7], dtype=int8), array([0.]), array([[1., 0.]]))
        """
        robot_pos = np.array(robots, dtype=np.float64).reshape(-1, 2)
        carrier_pos = np.array(carriers, dtype=np.float64).reshape(-1, 2)
        n, c = robot_pos.shape[0], carrier_pos.shape[0]
        default_heading = np.tile([1.0, 0.0], (n, 1))
        return cls(
            robot_pos=robot_pos,
            carrier_pos=carrier_pos,
            urgency0=_array("urgency", np.zeros(c) if urgency is None else urgency, (c,), np.int8),
            order_time=_array(
                "order_time", np.zeros(c) if order_time is None else order_time, (c,), np.float64
            ),
            w0=_array("w0", np.full(c, np.nan) if w0 is None else w0, (c,), np.float64),
            heading=_array(
                "heading", default_heading if heading is None else heading, (n, 2), np.float64
            ),
            speed_factor=_array(
                "speed_factor",
                np.ones(n) if speed_factor is None else speed_factor,
                (n,),
                np.float64,
            ),
            status=_array(
                "status",
                np.full(c, TagStatus.AWAITING_PICKUP) if status is None else status,
                (c,),
                np.int8,
            ),
            advert_phase=_array(
                "advert_phase",
                np.zeros(c) if advert_phase is None else advert_phase,
                (c,),
                np.float64,
            ),
        )


def _check_scene(scene: Scene, params: Params, position: int) -> None:
    n, c = params.robots, params.carriers
    where = f"scene {position}"
    for name, shape in (
        ("robot_pos", (n, 2)),
        ("heading", (n, 2)),
        ("speed_factor", (n,)),
        ("carrier_pos", (c, 2)),
        ("urgency0", (c,)),
        ("order_time", (c,)),
        ("w0", (c,)),
        ("status", (c,)),
        ("advert_phase", (c,)),
    ):
        actual = np.shape(getattr(scene, name))
        if actual != shape:
            msg = f"{where}: {name} has shape {actual}, the scenario needs {shape}"
            raise ConfigError(msg)
    for name in ("due", "destination", "slot", "slot_pick"):
        given = getattr(scene, name)
        if given is not None and np.shape(given) != (c,):
            msg = f"{where}: {name} has shape {np.shape(given)}, the scenario needs {(c,)}"
            raise ConfigError(msg)
    if not np.all(np.abs(length(scene.heading) - 1.0) < 1e-9):
        msg = f"{where}: heading must hold unit vectors"
        raise ConfigError(msg)
    if np.any((scene.urgency0 < 0) | (scene.urgency0 > 9)):
        msg = f"{where}: urgency0 must be integers 0-9"
        raise ConfigError(msg)
    phase = np.asarray(scene.advert_phase)
    if not np.all((phase >= 0.0) & (phase < 1.0)):
        msg = f"{where}: advert_phase must be fractions in [0, 1)"
        raise ConfigError(msg)


def initial_state(
    params: Params, scenes: Sequence[Scene], run_ids: ArrayLike, *, dense_caches: bool = True
) -> WorldState:
    """The state at time 0 of a batch: one scene per run, ``run_ids`` their global indices.

    Robots start in random walk along their heading, knowing no tag; tags
    advertise their initial state. Without ``dense_caches`` the arrays per
    robot and carrier are empty (no carriers on their last axis): for the
    compiled kernel's sparse tag caches (``Params.sparse_tag_cache``).
    """
    for position, scene in enumerate(scenes):
        _check_scene(scene, params, position)
    runs, n, c = len(scenes), params.robots, params.carriers
    pairs = (runs, n, c if dense_caches else 0)
    ids = np.array(run_ids, dtype=np.int64).reshape(-1)
    if ids.shape != (runs,):
        msg = f"run_ids: {ids.shape[0]} ids for {runs} scenes"
        raise ConfigError(msg)

    def stack(name: str, dtype: type) -> NDArray[Any]:
        return np.stack([np.asarray(getattr(s, name), dtype=dtype) for s in scenes])

    def orders(name: str, default: float, dtype: type) -> NDArray[Any]:
        rows: list[NDArray[Any]] = [
            np.full(c, default, dtype=dtype)
            if getattr(s, name) is None
            else np.asarray(getattr(s, name), dtype=dtype)
            for s in scenes
        ]
        return np.stack(rows).reshape(runs, c)

    carrier_pos = stack("carrier_pos", np.float64).reshape(runs, c, 2)
    status = stack("status", np.int8).reshape(runs, c)
    urgency0 = stack("urgency0", np.int8).reshape(runs, c)
    heading = stack("heading", np.float64).reshape(runs, n, 2)
    robot_pos = stack("robot_pos", np.float64).reshape(runs, n, 2)
    due = orders("due", 0, np.int64)
    present = due == 0
    slots = params.status_delay + 1

    def robots(value: int) -> Int:
        return np.full((runs, n), value, dtype=np.int64)

    return WorldState(
        tick=0,
        run_ids=ids,
        robot_pos=robot_pos,
        heading=heading,
        walk=heading.copy(),
        speed=params.step * stack("speed_factor", np.float64).reshape(runs, n),
        mode=np.full((runs, n), Mode.WALK, dtype=np.int8),
        target=robots(-1),
        face=robots(-1),
        pursuit_start=robots(-1),
        timer=robots(0),
        ghost=robots(-1),
        redirect=np.zeros((runs, n), dtype=bool),
        contact=np.zeros((runs, n, 2)),
        stuck=robots(0),
        sidestep=robots(0),
        sidestep_dir=np.zeros((runs, n, 2)),
        goal=np.zeros((runs, n, 2)),
        blocked_until=np.zeros(pairs, dtype=np.int64),
        known_status=np.full(pairs, -1, dtype=np.int8),
        known_urgency=np.zeros(pairs, dtype=np.int8),
        heard_tick=np.full(pairs, -1, dtype=np.int64),
        seen_tick=np.full(pairs, -1, dtype=np.int64),
        seen_pos=np.zeros((*pairs, 2)),
        rssi=np.zeros(pairs),
        walk_clock=robots(0),
        seek=robots(-1),
        seek_ref=np.zeros((runs, n)),
        curve=np.zeros((runs, n, 2)),
        look=robots(-1),
        odometry=np.zeros((runs, n, 2)),
        odometry_at=robot_pos.copy(),
        carrier_pos=carrier_pos,
        status=status,
        urgency=urgency0.copy(),
        present=present,
        carried_by=np.full((runs, c), -1, dtype=np.int64),
        w0=stack("w0", np.float64).reshape(runs, c),
        urgency0=urgency0,
        order_time=stack("order_time", np.float64).reshape(runs, c),
        free_face=free_faces(carrier_pos, present, params),
        advert_phase=phase_microseconds(
            stack("advert_phase", np.float64).reshape(runs, c), params.advert_us
        ),
        adv_status=np.repeat(status[:, None, :], slots, axis=1),
        adv_urgency=np.repeat(urgency0[:, None, :], slots, axis=1),
        pickup_time=np.full((runs, c), -1, dtype=np.int64),
        delivery_time=np.full((runs, c), -1, dtype=np.int64),
        deliverer=np.full((runs, c), -1, dtype=np.int64),
        delivery_urgency=np.full((runs, c), -1, dtype=np.int8),
        ended_at=np.full(runs, -1, dtype=np.int64),
        operator_counter=np.full(runs, -1, dtype=np.int64),
        due=due,
        arrival_time=np.where(present, 0, -1).astype(np.int64),
        destination=orders("destination", 0, np.int64),
        slot=orders("slot", -1, np.int64),
        slot_pick=orders("slot_pick", 0.0, np.float64),
    )
