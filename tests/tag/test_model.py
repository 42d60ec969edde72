"""The tag model: apply or refuse writes, persist, survive power cycles (SPEC §2.2-§2.3)."""

from __future__ import annotations

import pytest
from hypothesis import strategies as st
from hypothesis.stateful import Bundle, RuleBasedStateMachine, initialize, invariant, rule

from swarmtag.errors import (
    ForgedWrite,
    IllegalTransition,
    ReplayedWrite,
    RoleNotAllowed,
    StateRecordError,
    WriteRejected,
    WrongTarget,
)
from swarmtag.tag import (
    Change,
    MemoryStore,
    Role,
    TagModel,
    TagState,
    TagStatus,
    Write,
    WriteSigner,
    derive_robot_key,
    derive_role_key,
    sign,
)
from tests.strategies import bytes_values, changes, statuses, urgencies

KEY = b"site-key-for-tests-0123456789abc"  # the site key: what a tag holds
ROBOT_KEY = derive_robot_key(KEY, 1)  # what robot 1 holds
SHARED_ROBOT_KEY = derive_role_key(KEY, Role.ROBOT)  # the legacy key of all robots
OPERATOR_KEY = derive_role_key(KEY, Role.OPERATOR)  # what an operator or the WMS holds
MARKER = 12
ROBOT_MOVES = {
    (TagStatus.AWAITING_PICKUP, TagStatus.PICKED_UP),
    (TagStatus.PICKED_UP, TagStatus.IDLE),
}


def _provision(status: TagStatus = TagStatus.AWAITING_PICKUP) -> tuple[TagModel, MemoryStore]:
    store = MemoryStore()
    state = TagState(urgency=5, status=status, destination=0, marker=MARKER)
    return TagModel.provision(state, site_key=KEY, store=store), store


def test_full_cycle_operator_robot_robot():
    tag, store = _provision(TagStatus.IDLE)
    operator = WriteSigner(writer=100, role=Role.OPERATOR, key=OPERATOR_KEY)
    robot = WriteSigner(writer=1, role=Role.ROBOT, key=ROBOT_KEY)
    assert tag.apply(operator.sign(MARKER, Change(status=TagStatus.AWAITING_PICKUP, urgency=8)))
    assert (
        tag.apply(robot.sign(MARKER, Change(status=TagStatus.PICKED_UP))).status
        is TagStatus.PICKED_UP
    )
    final = tag.apply(robot.sign(MARKER, Change(status=TagStatus.IDLE)))
    assert final == TagState(urgency=8, status=TagStatus.IDLE, destination=0, marker=MARKER)
    assert dict(tag.counters) == {1: 1, 100: 0}
    rebooted = TagModel.boot(site_key=KEY, store=store)
    assert (rebooted.state, dict(rebooted.counters)) == (final, {1: 1, 100: 0})


@pytest.mark.parametrize(
    ("message", "error"),
    [
        (sign(Write(writer=1, role=Role.ROBOT, counter=0, target=13, change=Change(status=TagStatus.PICKED_UP)), ROBOT_KEY), WrongTarget),
        (sign(Write(writer=1, role=Role.ROBOT, counter=0, target=MARKER, change=Change(urgency=0)), ROBOT_KEY), RoleNotAllowed),
        (sign(Write(writer=1, role=Role.ROBOT, counter=0, target=MARKER, change=Change(status=TagStatus.IDLE)), ROBOT_KEY), IllegalTransition),
        (sign(Write(writer=1, role=Role.OPERATOR, counter=0, target=MARKER, change=Change(urgency=0)), derive_role_key(b"not-the-site-key", Role.OPERATOR)), ForgedWrite),
        (sign(Write(writer=1, role=Role.OPERATOR, counter=0, target=MARKER, change=Change(urgency=0)), ROBOT_KEY), ForgedWrite),
    ],
)  # fmt: skip
def test_refusals_leave_everything_unchanged(message, error):
    tag, store = _provision()
    before = (tag.state, dict(tag.counters), store.load())
    with pytest.raises(error) as caught:
        tag.apply(message)
    assert caught.value.att_error >= 0x80
    assert (tag.state, dict(tag.counters), store.load()) == before


def test_replay_and_stale_counter_refused():
    tag, _store = _provision()
    robot = WriteSigner(writer=1, role=Role.ROBOT, key=ROBOT_KEY, counter=41)
    lift = robot.sign(MARKER, Change(status=TagStatus.PICKED_UP))
    tag.apply(lift)
    with pytest.raises(ReplayedWrite, match="counter 42 from writer 1"):
        tag.apply(lift)
    # restarted without its counter:
    forgetful = WriteSigner(writer=1, role=Role.ROBOT, key=ROBOT_KEY)
    with pytest.raises(ReplayedWrite):
        tag.apply(forgetful.sign(MARKER, Change(status=TagStatus.IDLE)))
    assert tag.state.status is TagStatus.PICKED_UP


def test_counters_are_per_writer():
    tag, _store = _provision(TagStatus.IDLE)
    for writer in (5, 6):
        operator = WriteSigner(writer=writer, role=Role.OPERATOR, key=OPERATOR_KEY, counter=9)
        tag.apply(operator.sign(MARKER, Change(urgency=writer)))
    assert dict(tag.counters) == {5: 10, 6: 10}


def test_counter_survives_power_cycle_so_replay_stays_refused():
    tag, store = _provision()
    robot = WriteSigner(writer=3, role=Role.ROBOT, key=derive_robot_key(KEY, 3))
    lift = robot.sign(MARKER, Change(status=TagStatus.PICKED_UP))
    tag.apply(lift)
    operator = WriteSigner(writer=200, role=Role.OPERATOR, key=OPERATOR_KEY)
    tag.apply(operator.sign(MARKER, Change(status=TagStatus.AWAITING_PICKUP)))
    rebooted = TagModel.boot(site_key=KEY, store=store)
    with pytest.raises(ReplayedWrite):
        rebooted.apply(lift)  # would be a legal transition, but the counter is spent
    assert rebooted.state.status is TagStatus.AWAITING_PICKUP


class FailingStore(MemoryStore):
    """Flash that fails on the next save, like a brown-out mid-write."""

    fail = False

    def save(self, record: bytes) -> None:
        if self.fail:
            raise OSError("flash write failed")
        super().save(record)


def test_a_failed_persist_changes_nothing():
    store = FailingStore()
    start = TagState(urgency=5, status=TagStatus.AWAITING_PICKUP, destination=0, marker=MARKER)
    tag = TagModel.provision(start, site_key=KEY, store=store)
    store.fail = True
    robot = WriteSigner(writer=1, role=Role.ROBOT, key=ROBOT_KEY)
    with pytest.raises(OSError, match="flash"):
        tag.apply(robot.sign(MARKER, Change(status=TagStatus.PICKED_UP)))
    assert (tag.state, dict(tag.counters)) == (start, {})


def test_boot_from_empty_store_is_a_clear_error():
    with pytest.raises(StateRecordError, match="provision"):
        TagModel.boot(site_key=KEY, store=MemoryStore())


class TagLifecycle(RuleBasedStateMachine):
    """Random sequences of honest, forged, replayed and illegal writes, with power cycles.

    A plain reference model (a dict and a status) says what must happen;
    invariants: the tag equals the model, the persisted record equals memory,
    a refused write changes nothing, and no write is ever accepted twice.
    """

    accepted = Bundle("accepted")

    @initialize(urgency=urgencies, status=statuses, destination=bytes_values)
    def provision(self, urgency, status, destination):
        self.store = MemoryStore()
        self.expected = TagState(
            urgency=urgency, status=status, destination=destination, marker=MARKER
        )
        self.tag = TagModel.provision(self.expected, site_key=KEY, store=self.store)
        self.counters: dict[int, int] = {}
        self.lifter: int | None = None  # set by a robot's lift, kept while PICKED_UP
        self.robots = [
            WriteSigner(writer=w, role=Role.ROBOT, key=derive_robot_key(KEY, w)) for w in (1, 2)
        ]
        self.operator = WriteSigner(writer=100, role=Role.OPERATOR, key=OPERATOR_KEY)
        self.seen: set[bytes] = set()

    def _refused(self, message: bytes, error: type[WriteRejected]) -> None:
        before = (self.tag.state, dict(self.tag.counters), self.store.load())
        with pytest.raises(error):
            self.tag.apply(message)
        assert (self.tag.state, dict(self.tag.counters), self.store.load()) == before

    def _accepted(self, message: bytes, writer: int, counter: int, new: TagState) -> bytes:
        assert message not in self.seen, "the same write was accepted twice"
        assert self.tag.apply(message) == new
        self.seen.add(message)
        self.expected = new
        self.counters[writer] = counter
        return message

    @rule(target=accepted, change=changes)
    def operator_write(self, change):
        message = self.operator.sign(MARKER, change)
        new = TagState(
            urgency=self.expected.urgency if change.urgency is None else change.urgency,
            status=self.expected.status if change.status is None else change.status,
            destination=self.expected.destination
            if change.destination is None
            else change.destination,
            marker=MARKER,
        )
        if new.status is not TagStatus.PICKED_UP or self.expected.status is not new.status:
            self.lifter = None  # an operator's move overrides (and forgets) any lifter
        return self._accepted(message, 100, self.operator.counter, new)

    @rule(robot=st.sampled_from([0, 1]), status=statuses)
    def robot_status_write(self, robot, status):
        signer = self.robots[robot]
        message = signer.sign(MARKER, Change(status=status))
        release = self.expected.status is TagStatus.PICKED_UP
        bound = release and self.lifter not in (None, signer.writer)
        if (self.expected.status, status) in ROBOT_MOVES and not bound:
            new = TagState(
                urgency=self.expected.urgency,
                status=status,
                destination=self.expected.destination,
                marker=MARKER,
            )
            self._accepted(message, signer.writer, signer.counter, new)
            self.lifter = None if release else signer.writer
        else:
            self._refused(message, IllegalTransition)

    @rule(robot=st.sampled_from([0, 1]), status=statuses)
    def robot_signs_as_the_other_robot(self, robot, status):
        """Robot 1's key with robot 2's writer id (and the other way round) is forged."""
        thief = WriteSigner(
            writer=self.robots[1 - robot].writer,
            role=Role.ROBOT,
            key=self.robots[robot].key,
            counter=10**6,
        )
        self._refused(thief.sign(MARKER, Change(status=status)), ForgedWrite)

    @rule(robot=st.sampled_from([0, 1]), urgency=urgencies)
    def robot_changes_urgency(self, robot, urgency):
        self._refused(self.robots[robot].sign(MARKER, Change(urgency=urgency)), RoleNotAllowed)

    @rule(message=accepted)
    def replay(self, message):
        self._refused(message, ReplayedWrite)

    @rule(message=accepted, position=st.integers(0, 19), mask=st.integers(1, 255))
    def tamper(self, message, position, mask):
        forged = bytearray(message)
        forged[position] ^= mask
        self._refused(bytes(forged), ForgedWrite)

    @rule(change=changes)
    def wrong_key(self, change):
        intruder = WriteSigner(
            writer=100, role=Role.OPERATOR, key=b"guessed-operator-key-0123456789a", counter=10**6
        )
        self._refused(intruder.sign(MARKER, change), ForgedWrite)

    @rule(writer=st.sampled_from([1, 2, 100]), change=changes)
    def robot_key_signs_as_operator(self, writer, change):
        for key in (ROBOT_KEY, SHARED_ROBOT_KEY):
            impostor = WriteSigner(writer=writer, role=Role.OPERATOR, key=key, counter=10**6)
            self._refused(impostor.sign(MARKER, change), ForgedWrite)

    @rule(writer=st.sampled_from([1, 2]), status=statuses)
    def shared_robot_key_on_a_new_tag(self, writer, status):
        legacy = WriteSigner(writer=writer, role=Role.ROBOT, key=SHARED_ROBOT_KEY, counter=10**6)
        self._refused(legacy.sign(MARKER, Change(status=status)), ForgedWrite)

    @rule(change=changes, other=bytes_values.filter(lambda m: m != MARKER))
    def other_tag(self, change, other):
        self._refused(self.operator.sign(other, change), WrongTarget)

    @rule()
    def power_cycle(self):
        self.tag = TagModel.boot(site_key=KEY, store=self.store)

    @invariant()
    def tag_matches_model(self):
        assert self.tag.state == self.expected
        assert dict(self.tag.counters) == self.counters
        assert self.tag.lifter == self.lifter

    @invariant()
    def persisted_matches_memory(self):
        persisted = TagModel.boot(site_key=KEY, store=self.store)
        assert persisted.state == self.tag.state
        assert persisted.counters == self.tag.counters
        assert (persisted.lifter, persisted.shared_robot_key) == (self.tag.lifter, False)


TestTagLifecycle = TagLifecycle.TestCase
