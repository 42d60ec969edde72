"""Hypothesis strategies shared across the test suite."""

from __future__ import annotations

from hypothesis import strategies as st

from swarmtag.tag import Change, TagState, TagStatus

statuses = st.sampled_from(TagStatus)
urgencies = st.integers(0, 9)
bytes_values = st.integers(0, 255)

tag_states = st.builds(
    TagState,
    urgency=urgencies,
    status=statuses,
    destination=bytes_values,
    marker=bytes_values,
)

changes = st.builds(
    Change,
    urgency=st.none() | urgencies,
    status=st.none() | statuses,
    destination=st.none() | bytes_values,
).filter(lambda change: not change.empty)
