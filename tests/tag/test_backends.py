"""The tag-transport facade, the TagTable bookkeeping, and the fake and sim backends."""

from __future__ import annotations

import sys

import numpy as np
import pytest

from swarmtag.errors import ConfigError, RadioError
from swarmtag.tag import TagState, TagStatus, encode_manufacturer_data
from swarmtag.tag.backends import BACKENDS, Scanner, Sighting, TagTable, open_scanner
from swarmtag.tag.backends.fake import FakeScanner
from swarmtag.tag.backends.sim import SimScanner, SimTag, bench_tags, rssi_at

STATE = TagState(urgency=7, status=TagStatus.AWAITING_PICKUP, destination=3, marker=12)
OURS = {0xFFFF: bytes([7, 1, 3, 12])}


class Clock:
    """A clock the test moves by hand."""

    def __init__(self, now: float = 100.0) -> None:
        self.now = now

    def __call__(self) -> float:
        return self.now


def sighting(marker: int, seen_at: float, *, address: str = "AA") -> Sighting:
    state = TagState(urgency=1, status=TagStatus.IDLE, destination=0, marker=marker)
    return Sighting(marker, state, -60, seen_at, address)


# --- facade ---------------------------------------------------------------------------------


def test_backends_name_modules_and_classes():
    assert set(BACKENDS) == {"bleak", "sim", "fake"}
    for backend in ("sim", "fake"):
        assert isinstance(open_scanner(backend), Scanner)
        assert open_scanner(backend).name == backend


def test_unknown_backend_names_the_choices():
    with pytest.raises(
        ConfigError, match=r"'radio' is not a tag backend \(choose one of bleak, fake, sim\)"
    ):
        open_scanner("radio")


def test_unknown_option_is_a_config_error():
    with pytest.raises(ConfigError, match=r"backend 'fake':.*colour"):
        open_scanner("fake", colour="red")


def test_missing_bleak_names_the_ble_extra(monkeypatch):
    monkeypatch.setitem(sys.modules, "bleak", None)  # "import bleak" now fails
    monkeypatch.delitem(sys.modules, "swarmtag.tag.backends.bleak", raising=False)
    with pytest.raises(
        ConfigError, match=r"needs the bleak package.*pip install 'swarmtag\[ble\]'"
    ):
        open_scanner("bleak")


def test_backend_modules_are_imported_lazily():
    import subprocess

    code = "import swarmtag.tag.backends, sys; print('bleak' in sys.modules, 'swarmtag.tag.backends.sim' in sys.modules)"
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.split() == ["False", "False"]


# --- TagTable ---------------------------------------------------------------------------------


def test_table_keeps_the_latest_per_carrier():
    table = TagTable(max_age=5.0)
    assert table.update(sighting(12, 1.0, address="AA"))
    assert table.update(sighting(12, 2.0, address="BB"))
    assert not table.update(sighting(12, 1.5))  # a delayed advert does not undo a newer one
    assert table.update(sighting(7, 1.0))
    assert list(table.latest(now=2.0)) == [7, 12]
    assert table.latest(now=2.0)[12].address == "BB"


def test_table_ages_out_stale_sightings():
    table = TagTable(max_age=5.0)
    table.update(sighting(1, 0.0))
    table.update(sighting(2, 3.0))
    assert list(table.latest(now=5.0)) == [1, 2]  # exactly max_age old: still fresh
    assert list(table.latest(now=5.5)) == [2]
    assert table.prune(now=100.0) == 1
    assert len(table) == 0


@pytest.mark.parametrize("max_age", [0, -1, float("nan"), float("inf"), "5", True])
def test_table_refuses_bad_max_age(max_age):
    with pytest.raises(ConfigError, match="max_age"):
        TagTable(max_age=max_age)


# --- fake -------------------------------------------------------------------------------------


def test_fake_counts_and_ages_with_its_clock():
    clock = Clock()
    scanner = FakeScanner(clock=clock, max_age=2.0)
    with scanner:
        assert scanner.running
        assert scanner.feed("AA", OURS, rssi=-50) == Sighting(12, STATE, -50, 100.0, "AA")
        assert scanner.feed("PHONE", {0x004C: b"\x02\x15"}) is None
        assert scanner.feed("BROKEN", {0xFFFF: b"\x0a\x01\x03\x0c"}) is None
        assert scanner.feed("SHORT", {0xFFFF: b"\x01"}) is None  # 0xFFFF, another length
    assert not scanner.running
    assert (scanner.accepted, scanner.foreign, scanner.malformed) == (1, 2, 1)
    assert scanner.errors == {"UrgencyRangeError": 1}
    clock.now = 101.5
    assert list(scanner.states()) == [12]
    clock.now = 102.5
    assert scanner.states() == {}


def test_fake_reports_a_failure():
    scanner = FakeScanner()
    assert scanner.failure is None
    scanner.fail(RadioError("no adapter"))
    assert str(scanner.failure) == "no adapter"


def test_states_is_a_copy():
    scanner = FakeScanner(clock=Clock())
    scanner.feed("AA", OURS)
    scanner.states().clear()
    assert list(scanner.states()) == [12]


# --- sim --------------------------------------------------------------------------------------


def sim(clock: Clock, **options) -> SimScanner:
    tags = options.pop("tags", [SimTag("AA", STATE, distance=2.0, phase=0.1)])
    return SimScanner(tags=tags, clock=clock, **options)


def test_sim_advertises_every_interval_from_its_phase():
    clock = Clock(0.0)
    scanner = sim(clock, interval=0.25)
    scanner.start()
    assert scanner.advance(0.05) == 0
    assert scanner.advance(0.1) == 1  # the first advert at the phase
    assert scanner.advance(1.1) == 4  # 0.35, 0.6, 0.85, 1.1
    held = scanner.states()[12]
    assert (held.seen_at, held.rssi, held.address) == (pytest.approx(1.1), rssi_at(2.0), "AA")
    assert scanner.sent == scanner.accepted == 5


def test_sim_hears_nothing_before_start_or_after_stop():
    clock = Clock(0.0)
    scanner = sim(clock)
    assert scanner.advance(10.0) == 0
    scanner.start()
    scanner.stop()
    assert scanner.advance(20.0) == 0
    assert scanner.accepted == 0


def test_sim_out_of_range_is_not_heard():
    clock = Clock(0.0)
    scanner = sim(clock, radio_range=1.0)
    scanner.start()
    scanner.advance(2.0)
    assert scanner.states() == {}
    assert scanner.lost == scanner.sent > 0


def test_sim_delay_shifts_arrival():
    clock = Clock(0.0)
    scanner = sim(clock, delay=0.3)
    scanner.start()
    assert scanner.advance(0.35) == 0  # sent at 0.1 and 0.35, arriving at 0.4 and 0.65
    assert scanner.advance(0.4) == 1
    assert scanner.states()[12].seen_at == pytest.approx(0.4)


def test_sim_loss_is_seeded_and_independent_of_chunking():
    def run(steps):
        clock = Clock(0.0)
        scanner = sim(clock, loss=0.5, rng=np.random.default_rng(7), tags=bench_tags())
        scanner.start()
        for now in steps:
            scanner.advance(now)
        return scanner.lost, scanner.accepted, {m: s.seen_at for m, s in scanner.states().items()}

    once = run([20.0])
    assert once == run(np.linspace(0.01, 20.0, 137))
    assert 0 < once[0] < once[0] + once[1]  # some lost, some heard
    assert run([5.0, 20.0]) == once


def test_sim_is_deterministic_for_a_seed_and_differs_across_seeds():
    def lost(seed):
        clock = Clock(0.0)
        scanner = sim(clock, loss=0.3, rng=np.random.default_rng(seed), tags=bench_tags())
        scanner.start()
        scanner.advance(30.0)
        return scanner.lost

    assert lost(1) == lost(1)
    assert len({lost(seed) for seed in range(5)}) > 1


def test_sim_duplicate_filtering_reports_changes_only_and_states_age_out():
    clock = Clock(0.0)
    scanner = sim(clock, changes_only=True, max_age=1.0)
    scanner.start()
    assert scanner.advance(3.0) == 1  # 12 adverts, one report: the payload never changed
    assert scanner.filtered == 11
    clock.now = 3.0
    assert scanner.states() == {}  # heard at 0.1, older than max_age: aged out
    changed = TagState(urgency=9, status=TagStatus.AWAITING_PICKUP, destination=3, marker=12)
    scanner.set_state("AA", changed)
    assert scanner.advance(3.5) == 1
    assert scanner.states()[12].state == changed


def test_sim_updates_are_seen_through_repeats_and_drops():
    clock = Clock(0.0)
    scanner = sim(clock, loss=0.4, rng=np.random.default_rng(3))
    scanner.start()
    scanner.advance(2.0)
    picked = TagState(urgency=7, status=TagStatus.PICKED_UP, destination=3, marker=12)
    scanner.set_state("AA", picked)
    scanner.advance(6.0)
    clock.now = 6.0
    assert scanner.states()[12].state == picked
    assert scanner.lost > 0


def test_sim_poll_follows_the_clock():
    clock = Clock(0.0)
    scanner = sim(clock)
    scanner.start()
    clock.now = 0.5
    scanner.poll()
    assert list(scanner.states()) == [12]


def test_sim_draws_phases_from_its_generator():
    tags = [SimTag(f"T{i}", STATE) for i in range(4)]
    first = SimScanner(tags=tags, rng=np.random.default_rng(5))
    second = SimScanner(tags=tags, rng=np.random.default_rng(5))
    assert first._phase == second._phase
    assert all(0 <= phase < 250_000 for phase in first._phase.values())  # microseconds


@pytest.mark.parametrize(
    ("option", "value"),
    [
        ("interval", 0.05),
        ("interval", 1.5),
        ("loss", 1.5),
        ("delay", -1),
        ("radio_range", float("nan")),
        ("rng", 3),
    ],
)
def test_sim_refuses_bad_options(option, value):
    with pytest.raises(ConfigError, match=option):
        SimScanner(**{option: value})


def test_sim_set_state_of_an_unknown_tag():
    with pytest.raises(ConfigError, match="no simulated tag 'ZZ'"):
        SimScanner().set_state("ZZ", STATE)


def test_sim_payload_is_the_codec_one():
    clock = Clock(0.0)
    scanner = sim(clock)
    scanner.start()
    scanner.advance(0.1)
    assert encode_manufacturer_data(scanner.states()[12].state) == OURS
