"""Score rules of one's own, good and bad, as users write them (loaded by path in the tests)."""

from __future__ import annotations

import time

import numpy as np


def most_urgent(urgency, distance):
    """Urgency alone: the same scores as the built-in edf."""
    return urgency


def urgency_first(urgency, distance):
    """Most urgent first, the nearer among equals."""
    return urgency * 100.0 - np.minimum(distance, 99.0)


def oldest_first(urgency, distance, age):
    """FIFO: the carrier that has waited longest."""
    return age


def by_marker(urgency, distance, *, marker):
    """The smallest marker id first (context by keyword)."""
    return -marker.astype(np.float64)


def everything(urgency, distance, **context):
    """Takes every context keyword."""
    return urgency + context["age"] * 0.0 + context["marker"] * 0.0


def nan_scores(urgency, distance):
    return urgency * np.nan


def ranked(urgency, distance):
    """Not elementwise: ranks along the candidates."""
    return np.argsort(np.argsort(urgency, axis=-1), axis=-1).astype(np.float64)


def normalised(urgency, distance):
    """Not elementwise: divides by the sum over whatever it is given."""
    return urgency / (np.sum(urgency) + 1.0)


def clocked(urgency, distance):
    return urgency + time.monotonic() * 0.0


def raises(urgency, distance):
    msg = "no score today"
    raise ValueError(msg)


_calls = [0]


def drifting(urgency, distance):
    """Keeps state between calls."""
    _calls[0] += 1
    return urgency + _calls[0]


def one_argument(urgency):
    return urgency


def wants_more(urgency, distance, battery):
    return urgency


def edf(urgency, distance):
    """A built-in rule's name."""
    return urgency
