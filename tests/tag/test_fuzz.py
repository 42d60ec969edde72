"""Fuzz the decoders with random bytes: typed errors only, never anything else.

The seed is printed (see the test's output with ``-s`` or on failure) and can
be pinned with ``SWARMTAG_FUZZ_SEED=<n>`` to replay a failing run exactly.
"""

from __future__ import annotations

import os
import secrets

import numpy as np

from swarmtag.errors import ForgedWrite, PayloadError, WriteRejected
from swarmtag.tag import (
    Change,
    MemoryStore,
    Role,
    ScanFilter,
    TagModel,
    TagState,
    TagStatus,
    WriteSigner,
    decode,
    decode_manufacturer_data,
    derive_role_key,
)

CASES = 100_000
KEY = bytes(range(32))


def _seed() -> int:
    pinned = os.environ.get("SWARMTAG_FUZZ_SEED")
    seed = int(pinned) if pinned else secrets.randbits(64)
    print(f"fuzz seed: {seed} (pin with SWARMTAG_FUZZ_SEED={seed})")
    return seed


def _random_payloads(rng: np.random.Generator, count: int) -> list[bytes]:
    """Random byte strings, biased to reach the deep paths: our company id, length 6."""
    lengths = rng.choice([0, 1, 2, 5, 6, 6, 6, 6, 7, 12, 31], size=count)
    raw = rng.integers(0, 256, size=(count, 31), dtype=np.uint8)
    ours = rng.random(count) < 0.5
    raw[ours, 0:2] = 0xFF
    small = rng.random(count) < 0.5  # plausible field values half of the time
    raw[small, 2] %= 12
    raw[small, 3] %= 4
    return [bytes(row[:length]) for row, length in zip(raw, lengths, strict=True)]


def test_decoder_fuzz(record_property):
    seed = _seed()
    record_property("fuzz_seed", seed)
    rng = np.random.default_rng(seed)
    payloads = _random_payloads(rng, CASES)
    outcomes = {"ok": 0}
    for payload in payloads:
        try:
            state = decode(payload)
        except PayloadError as error:
            outcomes[type(error).__name__] = outcomes.get(type(error).__name__, 0) + 1
        else:
            assert isinstance(state, TagState)
            outcomes["ok"] += 1
    assert sum(outcomes.values()) == CASES
    # The biased generator must actually reach every branch, or the fuzz proves little.
    assert set(outcomes) == {
        "ok",
        "PayloadLengthError",
        "ForeignCompanyError",
        "UrgencyRangeError",
        "UnknownStatusError",
    }, f"seed {seed}: {outcomes}"


def test_scanner_fuzz_never_raises():
    seed = _seed()
    rng = np.random.default_rng(seed)
    scan = ScanFilter()
    payloads = _random_payloads(rng, CASES // 4)
    companies = rng.choice([0xFFFF, 0x004C, 0x0006, 0x0000], size=len(payloads))
    for company, payload in zip(companies, payloads, strict=True):
        scan.feed({int(company): payload[2:]})
        scan.feed(payload)
    assert scan.accepted + scan.foreign + scan.malformed == 2 * len(payloads), f"seed {seed}"


def test_mapping_decoder_fuzz():
    seed = _seed()
    rng = np.random.default_rng(seed)
    for payload in _random_payloads(rng, CASES // 4):
        try:
            decode_manufacturer_data({0xFFFF: payload})
        except PayloadError:
            continue


def test_write_fuzz_random_bytes_and_bit_flips():
    """Random 20-byte writes and single-bit corruptions of real ones are all refused, typed."""
    seed = _seed()
    rng = np.random.default_rng(seed)
    start = TagState(urgency=3, status=TagStatus.AWAITING_PICKUP, destination=0, marker=12)
    tag = TagModel.provision(start, site_key=KEY, store=MemoryStore())
    lengths = rng.choice([0, 19, 20, 20, 20, 21], size=CASES // 10)
    for length in lengths:
        message = rng.integers(0, 256, size=int(length), dtype=np.uint8).tobytes()
        try:
            tag.apply(message)
        except WriteRejected:
            continue
        raise AssertionError(f"seed {seed}: random bytes accepted: {message.hex()}")
    operator = WriteSigner(writer=9, role=Role.OPERATOR, key=derive_role_key(KEY, Role.OPERATOR))
    for _ in range(2_000):
        message = bytearray(operator.sign(12, Change(urgency=int(rng.integers(0, 10)))))
        bit = int(rng.integers(0, 160))
        message[bit // 8] ^= 1 << (bit % 8)
        try:
            tag.apply(bytes(message))
        except ForgedWrite:
            continue
        raise AssertionError(f"seed {seed}: a corrupted write was accepted: {message.hex()}")
    assert tag.state == start
    assert dict(tag.counters) == {}
