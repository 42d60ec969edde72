"""Work bounded before it starts: the memory limit and its one refusal rule."""

from __future__ import annotations

import pytest

from swarmtag._resources import check_memory, format_bytes, memory_limit
from swarmtag.errors import ResourceError, StudyError


def test_the_limit_is_the_environment_variable_when_set(monkeypatch):
    monkeypatch.setenv("SWARMTAG_MEMORY_LIMIT", "2GiB")
    assert memory_limit() == 2 * 2**30
    monkeypatch.setenv("SWARMTAG_MEMORY_LIMIT", "1500")
    assert memory_limit() == 1500


def test_the_limit_without_the_variable_is_what_the_machine_has(monkeypatch):
    monkeypatch.delenv("SWARMTAG_MEMORY_LIMIT", raising=False)
    assert 2**20 < memory_limit() < 2**50


def test_a_bad_limit_is_one_clear_error(monkeypatch):
    monkeypatch.setenv("SWARMTAG_MEMORY_LIMIT", "lots")
    with pytest.raises(ResourceError, match="SWARMTAG_MEMORY_LIMIT: 'lots' is not a size"):
        memory_limit()


def test_an_estimate_over_the_limit_is_refused_with_both_numbers(monkeypatch):
    monkeypatch.setenv("SWARMTAG_MEMORY_LIMIT", "1MiB")
    check_memory("--runs 1", 2**20)  # exactly the limit fits
    with pytest.raises(StudyError) as error:
        check_memory("--runs 9", 3 * 2**20, error=StudyError)
    assert str(error.value).startswith("--runs 9 needs about 3.0 MiB of memory; 1.0 MiB is")


def test_format_bytes_picks_the_largest_unit():
    assert format_bytes(3 * 2**40) == "3.0 TiB"
    assert format_bytes(1536) == "1.5 KiB"
    assert format_bytes(0) == "0 B"
