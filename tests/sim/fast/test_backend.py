"""Choosing the backend, threads, scenes, buffers: the compiled backend's surface."""

from __future__ import annotations

from concurrent.futures import ThreadPoolExecutor
from dataclasses import fields, replace

import numba
import numpy as np
import pytest

import swarmtag.sim.backends as sim_backends
import swarmtag.sim.fast._runner as fast_runner
from swarmtag.errors import ConfigError
from swarmtag.policy import Proximity, Urgency
from swarmtag.robot.sil import TreeController
from swarmtag.sim import (
    Realism,
    Reprioritisation,
    Scenario,
    WorldState,
    load_profile,
    make_params,
    simulate,
)
from swarmtag.sim.backends import FAST, REFERENCE, resolve_backend
from swarmtag.sim.control import rules
from swarmtag.sim.determinism import run_csv
from swarmtag.sim.fast import _docking, _scene
from swarmtag.sim.fast._index import index_robots
from swarmtag.sim.fast._layout import _KERNEL_ONLY, Constants, World, constants_of
from swarmtag.sim.fast._scratch import EVENT_SLOTS, Scratch
from swarmtag.sim.model import scene
from swarmtag.sim.runner import seeded_state
from tests.sim.fast.helpers import TAG_CACHES, assert_same

SCENARIO = replace(Scenario.default(3, 7), ticks=600)


def test_layout_mirrors_the_world_state():
    arrays = [f.name for f in fields(WorldState) if f.name != "tick"]
    assert [name for name in World._fields if name not in _KERNEL_ONLY] == arrays
    assert set(_KERNEL_ONLY) <= set(World._fields)
    params = make_params(SCENARIO, Urgency(alpha=0.7))
    constants = constants_of(params)
    for name in constants._fields:
        if hasattr(params, name):
            assert getattr(constants, name) == getattr(params, name), name
    assert (constants.policy_kind, constants.policy_parameter) == (1, 0.7)


def test_the_compiled_kernel_imports_the_reference_constants_rather_than_copying_them():
    assert _docking.STUCK_PROGRESS is rules.STUCK_PROGRESS
    assert _scene.PLACE_ATTEMPTS is scene.PLACE_ATTEMPTS
    assert _scene.PLACE_RESTARTS is scene.PLACE_RESTARTS


def test_default_backend_is_fast_where_numba_is_installed(monkeypatch):
    assert resolve_backend(None) is FAST
    assert resolve_backend(None, controller=TreeController()) is REFERENCE
    monkeypatch.setattr(sim_backends, "fast_available", lambda: False)
    assert resolve_backend(None) is REFERENCE
    with pytest.raises(ConfigError, match=r"backend: 'fast' needs numba .*swarmtag\[fast\]"):
        simulate(SCENARIO, Proximity(), seed=0, runs=1, backend="fast")


def test_bad_backends_are_refused():
    with pytest.raises(ConfigError, match="backend"):
        simulate(SCENARIO, Proximity(), seed=0, runs=1, backend="gpu")
    with pytest.raises(ConfigError, match="'fast' cannot run the 'bt' controller"):
        simulate(SCENARIO, Proximity(), seed=0, runs=1, backend="fast", controller="bt")
    with pytest.raises(ConfigError, match="threads"):
        simulate(SCENARIO, Proximity(), seed=0, runs=1, backend="fast", threads=0)


def test_threads_change_nothing():
    one = simulate(SCENARIO, Urgency(alpha=9.0), seed=4, runs=9, backend="fast", threads=1)
    three = simulate(SCENARIO, Urgency(alpha=9.0), seed=4, runs=9, backend="fast", threads=3)
    assert_same(one, three)


def test_a_run_is_the_same_alone_and_in_a_batch():
    batch = simulate(SCENARIO, Urgency(alpha=0.7), seed=6, runs=5, backend="fast")
    alone = simulate(SCENARIO, Urgency(alpha=0.7), seed=6, runs=1, run_offset=3, backend="fast")
    assert run_csv(batch, 3) == run_csv(alone, 3)


def test_full_event_buffers_pause_runs_without_changing_them(monkeypatch):
    busy = replace(SCENARIO, ticks=3000, realism=Realism(breakdown=0.0005))
    whole = simulate(busy, Urgency(alpha=0.7), seed=1, runs=3, backend="fast")
    # room for one tick's events only: a run pauses after every tick that had events
    room = lambda robots, slots: EVENT_SLOTS * (robots + slots)  # noqa: E731
    monkeypatch.setattr(fast_runner, "_capacity", room)
    paused = simulate(busy, Urgency(alpha=0.7), seed=1, runs=3, backend="fast")
    assert_same(whole, paused)
    for run in range(3):  # events in many ticks: every run paused again and again
        assert len(set(paused.events.time[paused.events.run == run].tolist())) > 5


@pytest.mark.parametrize(
    "scenario",
    [
        Scenario.default(3, 7),
        Scenario.default(20, 40),
        replace(Scenario.default(9, 12, profile="lab"), realism=Realism(speed_variation=0.3)),
        Scenario.default(40, 256),
    ],
    ids=["3x7", "20x40", "lab-speeds", "40x256"],
)
def test_compiled_scenes_are_the_reference_scenes(scenario):
    params = make_params(scenario, Proximity())
    reference = seeded_state(params, seed=7, runs=4, run_offset=11)
    fast = seeded_state(params, seed=7, runs=4, run_offset=11, backend="fast")
    for field in fields(WorldState):
        ours = getattr(reference, field.name)
        if params.sparse_tag_cache and field.name in TAG_CACHES:  # the kernel keeps lists
            assert getattr(fast, field.name).shape[:3] == (4, scenario.robots, 0)
        elif isinstance(ours, np.ndarray):
            assert np.array_equal(ours, getattr(fast, field.name), equal_nan=True), field.name


def test_scenes_too_crowded_for_random_placement_take_the_same_grid():
    crowded = Scenario.from_mapping({"robots": 30, "carriers": 7})  # fits a grid, not at random
    params = make_params(crowded, Proximity())
    reference = seeded_state(params, seed=0, runs=2)
    fast = seeded_state(params, seed=0, runs=2, backend="fast")
    assert np.array_equal(reference.robot_pos, fast.robot_pos)
    assert np.array_equal(reference.carrier_pos, fast.carrier_pos)
    pitch, low = 2 * params.robot_radius, params.dropoff_left + params.robot_radius
    cells = (reference.robot_pos - [low, params.robot_radius]) / pitch
    assert np.allclose(cells[0], np.round(cells[0]))  # run 0 on the grid,
    assert not np.allclose(cells[1], np.round(cells[1]))  # run 1 placed at random
    gaps = np.linalg.norm(reference.robot_pos[:, :, None] - reference.robot_pos[:, None], axis=-1)
    assert (gaps + 2 * np.eye(30) >= pitch - 1e-12).all()


def test_large_scenes_place_every_robot_apart():
    scenario = Scenario.from_mapping(
        {
            "robots": 1500,
            "carriers": 20,
            "arena": {"size": 40.0, "pickup_width": 8.0, "dropoff_width": 16.0},
        }
    )
    state = seeded_state(make_params(scenario, Proximity()), seed=3, runs=1, backend="fast")
    pos = state.robot_pos[0]
    gaps = np.sqrt(((pos[:, None, :] - pos[None, :, :]) ** 2).sum(axis=-1))
    np.fill_diagonal(gaps, np.inf)
    assert gaps.min() >= 0.25


def test_machine_code_from_other_sources_is_discarded(tmp_path):
    from types import SimpleNamespace

    from swarmtag.sim.fast._jit import _STAMP, _sources_digest, discard_stale_machine_code

    entry = SimpleNamespace(_cache=SimpleNamespace(_cache_path=str(tmp_path)))
    cached = [tmp_path / "_tick.advance-1.py311.nbi", tmp_path / "_tick.advance-1.py311.1.nbc"]
    keep = tmp_path / "_tick.cpython-311.pyc"
    for path in (*cached, keep):
        path.write_bytes(b"x")
    (tmp_path / _STAMP).write_text("an older digest")
    discard_stale_machine_code(entry)  # the sources changed: the machine code goes
    assert not any(path.exists() for path in cached)
    assert keep.exists()
    assert (tmp_path / _STAMP).read_text() == _sources_digest()
    for path in cached:
        path.write_bytes(b"x")
    discard_stale_machine_code(entry)  # the same sources: it stays
    assert all(path.exists() for path in cached)


def _count_splits(monkeypatch: pytest.MonkeyPatch) -> list[int]:
    """Make every batch of one run split its robots; the runs that did, as they step."""
    monkeypatch.setattr(fast_runner, "SPLIT_FROM", 1)
    stepped: list[int] = []
    original = fast_runner._Batch._split_run

    def counted(self: object, r: int, *rest: object) -> None:
        stepped.append(r)
        original(self, r, *rest)  # type: ignore[arg-type]

    monkeypatch.setattr(fast_runner._Batch, "_split_run", counted)
    return stepped


def _wide(robots: int, carriers: int, ticks: int, **extra: object) -> Scenario:
    """A paper-sim run of many robots in an arena wide enough to place them."""
    arena = {"size": 14.0, "pickup_width": 5.0, "dropoff_width": 5.0}
    base = {"robots": robots, "carriers": carriers, "ticks": ticks, "arena": arena}
    return load_profile("paper-sim").scenario({**base, **extra})


@pytest.mark.parametrize(
    ("scenario", "runs"),
    [
        (_wide(150, 40, 600), 1),  # the robots' grid and the active collision passes
        (_wide(60, 100, 1500, **{"camera.occlusion": "carriers+robots", "walk.turn_interval": 0.4,
                                 "realism.breakdown": 0.0002, "realism.detection_noise": 0.02,
                                 "realism.advertisement_loss": 0.1}), 1),
        (replace(Scenario.default(5, 10), ticks=400), 1),
    ],
    ids=["grids", "realism", "small"],
)  # fmt: skip
def test_one_run_split_over_threads_gives_the_same_bytes(scenario, runs, monkeypatch):
    whole = simulate(scenario, Urgency(alpha=0.7), seed=4, runs=runs, backend="fast", threads=1)
    splits = _count_splits(monkeypatch)
    split = simulate(scenario, Urgency(alpha=0.7), seed=4, runs=runs, backend="fast", threads=2)
    assert_same(whole, split)
    assert splits, "the run did not take the split path"
    assert whole.delivered.sum() + (whole.events.kind == "select").sum() > 0


def _record_split_calls(monkeypatch: pytest.MonkeyPatch) -> list[tuple[int, int]]:
    """Every thread's call of ``split_ticks``: its part and the parts."""
    calls: list[tuple[int, int]] = []
    original = fast_runner.split_ticks

    def recorded(part: int, parts: int, *rest: object) -> None:
        calls.append((part, parts))
        original(part, parts, *rest)

    monkeypatch.setattr(fast_runner, "split_ticks", recorded)
    return calls


def test_a_split_run_on_three_threads_gives_the_same_bytes(monkeypatch):
    scenario = _wide(150, 40, 300)
    whole = simulate(scenario, Urgency(alpha=0.7), seed=5, runs=1, backend="fast", threads=1)
    splits = _count_splits(monkeypatch)
    calls = _record_split_calls(monkeypatch)
    split = simulate(scenario, Urgency(alpha=0.7), seed=5, runs=1, backend="fast", threads=3)
    assert_same(whole, split)
    assert splits
    assert set(calls) == {(0, 3), (1, 3), (2, 3)}


def test_a_split_run_whose_first_thread_fails_to_start_releases_the_others(monkeypatch):
    # the other threads wait at a barrier for it: told, they return instead of spinning on
    _count_splits(monkeypatch)
    original = fast_runner.split_ticks
    returned: list[int] = []

    def failing(part: int, *rest: object) -> None:
        if part == 0:
            raise RuntimeError("part 0 never starts")
        original(part, *rest)
        returned.append(part)

    monkeypatch.setattr(fast_runner, "split_ticks", failing)
    scenario = _wide(150, 40, 300)
    with ThreadPoolExecutor(1) as pool:  # a hang fails the test instead of the whole suite
        future = pool.submit(
            simulate, scenario, Urgency(alpha=0.7), seed=5, runs=1, backend="fast", threads=3
        )
        with pytest.raises(RuntimeError, match="part 0 never starts"):
            future.result(timeout=120)
    assert sorted(returned) == [1, 2]


def test_a_split_run_paused_every_tick_draws_each_ticks_numbers_once(monkeypatch):
    # the next tick's numbers are drawn ahead (_split_run): pauses for trajectories and
    # operator writes must neither draw them again nor skip them
    writes = (
        Reprioritisation(tick=40, carrier=2, urgency=9),
        Reprioritisation(tick=41, carrier=3, urgency=0),
    )
    scenario = replace(_wide(150, 40, 120), reprioritisations=writes)
    whole = simulate(
        scenario, Urgency(alpha=0.7), seed=6, runs=1, backend="fast", threads=1, record=True
    )
    splits = _count_splits(monkeypatch)
    split = simulate(
        scenario, Urgency(alpha=0.7), seed=6, runs=1, backend="fast", threads=2, record=True
    )
    assert_same(whole, split)
    assert len(splits) >= 120  # one call a tick
    assert whole.trajectories is not None
    assert split.trajectories is not None
    np.testing.assert_array_equal(whole.trajectories.robot_pos, split.trajectories.robot_pos)


def test_a_warehouse_run_split_over_threads_gives_the_same_bytes(monkeypatch):
    part = {"map": "small-warehouse", "order_interval": 5.0, "initial_orders": 8}
    scenario = load_profile("lab").scenario({"robots": 30, "ticks": 3000, "warehouse": part})
    whole = simulate(scenario, Urgency(alpha=3.0), seed=2, runs=1, backend="fast", threads=1)
    splits = _count_splits(monkeypatch)
    split = simulate(scenario, Urgency(alpha=3.0), seed=2, runs=1, backend="fast", threads=2)
    assert_same(whole, split)
    assert splits
    assert (split.events.kind == "arrive").sum() > 0
    assert split.delivered.sum() > 0


_INDEX = ("robot_start", "robot_items", "crowd_start", "crowd_items", "x", "y")
"""The scratch arrays the robots' index writes (``_index.index_robots``)."""


@numba.njit(cache=False)  # not cached: machine code cached here would keep old _index code
def _index_robots_now(r: int, w: World, k: Constants, x: Scratch) -> None:
    index_robots(r, w, k, x)


@pytest.mark.first
def test_a_split_run_leaves_the_robots_index_of_where_they_stand(monkeypatch):
    # thread 1 builds the next tick's robots' index at the end of a tick (after docking),
    # and a paused run keeps it for its next call: it must be the index of the robots' places
    _count_splits(monkeypatch)
    stepped = fast_runner._Batch._split_run
    compared: list[int] = []

    def compare(self: fast_runner._Batch, r: int, *rest: object) -> None:
        stepped(self, r, *rest)  # type: ignore[arg-type]
        x = self.scratch
        fresh = x._replace(**{name: getattr(x, name).copy() for name in _INDEX})
        _index_robots_now(r, self.world, self.constants, fresh)
        for name in _INDEX:
            np.testing.assert_array_equal(getattr(x, name)[r], getattr(fresh, name)[r], name)
        compared.append(r)

    monkeypatch.setattr(fast_runner._Batch, "_split_run", compare)
    scenario = _wide(150, 40, 300, **{"camera.occlusion": "carriers+robots"})
    split = simulate(
        scenario, Urgency(alpha=0.7), seed=3, runs=1, backend="fast", threads=2, record=True
    )
    assert len(compared) >= 300  # one call a tick: every tick's index compared
    assert (split.events.kind == "select").sum() > 0  # robots chose carriers and went for them
