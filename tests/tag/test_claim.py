"""Claims (write format version 2): golden vectors, the tag's rule, old tags' refusal."""

from __future__ import annotations

import pytest

from swarmtag.errors import (
    ClaimRefused,
    FieldRangeError,
    ForgedWrite,
    MalformedWrite,
    ReplayedWrite,
    RoleNotAllowed,
    WrongTarget,
)
from swarmtag.tag import (
    Change,
    MemoryStore,
    Role,
    TagModel,
    TagState,
    TagStatus,
    WriteSigner,
    derive_robot_key,
    derive_role_key,
)
from swarmtag.tag.claim import (
    Claim,
    decode_claim_data,
    encode_claim_data,
    sign_claim,
    verify_claim,
)
from swarmtag.tag.write import authenticated, mac

SITE = bytes(range(16))
GOLDEN = [  # robot 7's claims on tag 12 for 30 s, signed with robot 7's own key (HKDF by hand)
    "02010700000000000c1e00008d2a7370a36399b5",
    "02010700010000000c1e00007c360f1b3e712b34",
]
LEGACY_GOLDEN = [  # the same claims under the legacy shared robot key
    "02010700000000000c1e0000c3f5508afd58f434",
    "02010700010000000c1e00000d2b3b96fb5106c1",
]


def robot(writer: int = 7) -> WriteSigner:
    return WriteSigner(writer=writer, role=Role.ROBOT, key=derive_robot_key(SITE, writer))


def tag(status: TagStatus = TagStatus.AWAITING_PICKUP) -> TagModel:
    state = TagState(urgency=5, status=status, destination=0, marker=12)
    return TagModel.provision(state, site_key=SITE, store=MemoryStore())


def test_golden_vectors():
    signer = robot()
    assert [sign_claim(signer, 12, 30).hex() for _ in GOLDEN] == GOLDEN
    shared = WriteSigner(writer=7, role=Role.ROBOT, key=derive_role_key(SITE, Role.ROBOT))
    assert [sign_claim(shared, 12, 30).hex() for _ in LEGACY_GOLDEN] == LEGACY_GOLDEN
    for message in map(bytes.fromhex, LEGACY_GOLDEN):
        with pytest.raises(ForgedWrite):
            verify_claim(message, SITE)
        assert verify_claim(message, SITE, shared_robot_key=True).writer == 7
    assert encode_claim_data(Claim(holder=7, until=112.0), now=100.0).hex() == "0107000c"
    assert decode_claim_data(bytes.fromhex("0107000c"), now=100.0) == Claim(7, 112.0)


def test_a_claim_is_granted_held_renewed_and_ended_by_the_lift():
    model, first, second = tag(), robot(7), robot(8)
    assert model.claim(sign_claim(first, 12, 30), now=100.0) == Claim(7, 130.0)
    with pytest.raises(ClaimRefused, match="robot 7 holds this tag for 20 s more"):
        model.claim(sign_claim(second, 12, 30), now=110.0)
    assert model.claim(sign_claim(first, 12, 5), now=110.0) == Claim(7, 115.0)  # renewed
    assert model.claim_at(114.5) == Claim(7, 115.0)
    assert model.claim_at(115.0) is None  # ended
    assert model.claim(sign_claim(second, 12, 10), now=116.0) == Claim(8, 126.0)
    model.apply(second.sign(12, Change(status=TagStatus.PICKED_UP)))
    assert model.claim_at(117.0) is None  # the lift ends the wait it reserved
    with pytest.raises(ClaimRefused, match="PICKED_UP, not AWAITING_PICKUP"):
        model.claim(sign_claim(first, 12, 30), now=118.0)


def test_claims_use_the_writers_one_counter_and_persist_it():
    model, signer = tag(), robot()
    signer.sign(12, Change(status=TagStatus.PICKED_UP))  # counter 0, never sent
    message = sign_claim(signer, 12, 30)  # counter 1
    model.claim(message, now=0.0)
    assert model.counters == {7: 1}
    assert TagModel.boot(site_key=SITE, store=model._store).counters == {7: 1}
    with pytest.raises(ReplayedWrite):
        model.claim(message, now=1.0)


@pytest.mark.parametrize(
    ("change", "error", "words"),
    [
        (lambda m: m[:19], MalformedWrite, "a write is 20 bytes"),
        (lambda m: m[:19] + bytes((m[19] ^ 1,)), ForgedWrite, "does not verify"),
        (lambda m: _resigned(m, 9, 0), MalformedWrite, "hold is 1-255 seconds, got 0"),
        (lambda m: _resigned(m, 10, 1), MalformedWrite, "bytes 10 and 11 are zero"),
        (lambda m: _resigned(m, 1, 0x11), MalformedWrite, "sets bits other than the role"),
        (lambda m: _resigned(m, 8, 13), WrongTarget, "for tag 13"),
    ],
)
def test_bad_claims_are_refused_and_change_nothing(change, error, words):
    model = tag()
    with pytest.raises(error, match=words):
        model.claim(change(sign_claim(robot(), 12, 30)), now=0.0)
    assert model.counters == {}
    assert model.claim_at(0.0) is None


def _resigned(message: bytes, index: int, value: int) -> bytes:
    signed = bytearray(message[:12])
    signed[index] = value
    writer = int.from_bytes(signed[2:4], "little")
    return bytes(signed) + mac(derive_robot_key(SITE, writer), bytes(signed))


def test_an_operator_may_not_claim():
    signed = bytes.fromhex("020207000000000c1e0000".replace("000c", "00000c"))
    operator_key = derive_role_key(SITE, Role.OPERATOR)
    message = signed + mac(operator_key, signed)
    assert authenticated(message, SITE)[1] is Role.OPERATOR
    with pytest.raises(RoleNotAllowed, match="operator's role may not claim"):
        verify_claim(message, SITE)
    operator = WriteSigner(writer=1, role=Role.OPERATOR, key=operator_key)
    with pytest.raises(FieldRangeError, match="claims are a robot's"):
        sign_claim(operator, 12, 30)


def test_a_tag_without_the_extension_refuses_a_claim_as_malformed():
    # version 1's parser: what a tag that knows no claims runs
    with pytest.raises(MalformedWrite, match="write format version 2 is not supported"):
        tag().apply(sign_claim(robot(), 12, 30))


def test_claim_data_that_is_not_one_is_refused():
    for text in ("0107000c00", "0207000c", "01070000"):
        with pytest.raises(MalformedWrite, match="is not 01 \\+ holder"):
            decode_claim_data(bytes.fromhex(text), now=0.0)
    with pytest.raises(FieldRangeError, match="it has ended"):
        encode_claim_data(Claim(7, 10.0), now=10.0)
