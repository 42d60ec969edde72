"""Every error swarmtag raises on purpose, in one tree.

Catch ``SwarmtagError`` to handle anything the library refuses; catch a leaf
to handle one cause. Each message says what was wrong and, where it helps,
what to do instead.

::

    SwarmtagError
    ├── FieldRangeError (ValueError)        a field value outside its allowed range
    ├── PayloadError (ValueError)           an advertisement payload is not a valid tag payload
    │   ├── PayloadLengthError              wrong number of bytes
    │   ├── ForeignCompanyError             company id is not 0xFFFF ("not ours")
    │   ├── UrgencyRangeError               urgency byte above 9
    │   └── UnknownStatusError              status byte not 0, 1 or 2
    ├── WriteRejected                       a tag refused an authenticated write
    │   ├── MalformedWrite                  bad length, version, reserved bits or padding
    │   ├── ForgedWrite                     the MAC does not verify under the named role's key
    │   ├── WrongTarget                     the write names another tag
    │   ├── ReplayedWrite                   counter not above the writer's highest seen
    │   ├── RoleNotAllowed                  that role may not change that field
    │   ├── IllegalTransition               that role may not make that status change
    │   ├── WriterTableFull                 the tag already tracks as many writers as it can
    │   └── ClaimRefused                    a claim on a tag awaiting no robot, or held by another
    ├── StateRecordError (ValueError)       a persisted tag record is corrupt or unknown
    ├── KeyFileError (ValueError)           a key file is missing, not private or malformed
    ├── CounterFileError (ValueError)       a writer's counter file is corrupt or unwritable
    ├── PolicyError (ValueError)            bad policy parameter, condition name or inputs
    ├── EventLogError (ValueError)          an event log breaks the schema (names file, row, column)
    ├── BagError (ValueError)               a ROS 2 bag or topic mapping refused (names what)
    ├── StatisticsError (ValueError)        statistics input refused (no runs, unknown baseline)
    ├── ConfigError (ValueError)            a scenario or backend value or key is not allowed
    ├── RadioError (RuntimeError)           the BLE radio cannot be used (adapter, BlueZ, rights)
    ├── SimulationError (RuntimeError)      a simulation broke one of its own contracts
    │   ├── InvariantError                  a world-state invariant failed (checking mode)
    │   └── DeterminismError                a run differed between two ways of computing it
    ├── ConformanceError                    a controller departed from the built-in one
    ├── StudyError (ValueError)             a study file or option is not allowed (names the key)
    ├── CalibrationError (ValueError)       a calibration baseline, free parameter or option refused
    ├── StoreError (RuntimeError)           the results store cannot be opened or is inconsistent
    ├── OutputError (ValueError)            an output path is refused (names the option and path)
    ├── ResourceError (ValueError)          the work asked for cannot fit (says estimate and limit)
    └── PerceptionError (ValueError)        a camera image, camera file or marker input is refused

``BackendFallback`` (a ``UserWarning``) says a run went to another backend
than the one asked for or the default (a rule the compiled kernel cannot run);
the command line prints it as one ``swarmtag: note:`` line.
"""

from __future__ import annotations

__all__ = [
    "BackendFallback",
    "BagError",
    "CalibrationError",
    "ClaimRefused",
    "ConfigError",
    "ConformanceError",
    "CounterFileError",
    "DeterminismError",
    "EventLogError",
    "FieldRangeError",
    "ForeignCompanyError",
    "ForgedWrite",
    "IllegalTransition",
    "InvariantError",
    "KeyFileError",
    "MalformedWrite",
    "OutputError",
    "PayloadError",
    "PayloadLengthError",
    "PerceptionError",
    "PolicyError",
    "RadioError",
    "ReplayedWrite",
    "ResourceError",
    "RoleNotAllowed",
    "SimulationError",
    "StateRecordError",
    "StatisticsError",
    "StoreError",
    "StudyError",
    "SwarmtagError",
    "UnknownStatusError",
    "UrgencyRangeError",
    "WriteRejected",
    "WriterTableFull",
    "WrongTarget",
]


class SwarmtagError(Exception):
    """Base of every error swarmtag raises on purpose."""


class FieldRangeError(SwarmtagError, ValueError):
    """A field value lies outside its allowed range; the message names the field."""


class PayloadError(SwarmtagError, ValueError):
    """Bytes that are not a valid swarmtag advertisement payload."""


class PayloadLengthError(PayloadError):
    """The payload has the wrong number of bytes."""


class ForeignCompanyError(PayloadError):
    """The company identifier is not 0xFFFF: the advertisement is not ours."""


class UrgencyRangeError(PayloadError):
    """The urgency byte is above 9."""


class UnknownStatusError(PayloadError):
    """The status byte is not a known ``TagStatus``."""


class WriteRejected(SwarmtagError):
    """A tag refused a write and left its state exactly as it was.

    ``att_error`` is the ATT error code a hardware tag answers with.
    """

    att_error: int = 0x80

    def __init__(self, reason: str) -> None:
        super().__init__(reason)
        self.reason = reason


class MalformedWrite(WriteRejected):
    """The write is not a well-formed swarmtag write (length, version, reserved bits, padding)."""

    att_error = 0x0D  # ATT "Invalid Attribute Value Length" / malformed value


class ForgedWrite(WriteRejected):
    """The MAC does not verify under the key of the role the flags name (or name no role)."""

    att_error = 0x80


class ReplayedWrite(WriteRejected):
    """The counter is not above the highest counter seen from that writer."""

    att_error = 0x81


class WrongTarget(WriteRejected):
    """The write is addressed to another tag (another marker id)."""

    att_error = 0x82


class RoleNotAllowed(WriteRejected):
    """The writer's role may not change that field."""

    att_error = 0x83


class IllegalTransition(WriteRejected):
    """The writer's role may not make that status transition."""

    att_error = 0x84


class WriterTableFull(WriteRejected):
    """The tag already tracks its maximum number of writer ids and refuses a new one."""

    att_error = 0x85


class ClaimRefused(WriteRejected):
    """A claim the tag cannot grant: it awaits no robot, or another robot holds it."""

    att_error = 0x86


class StateRecordError(SwarmtagError, ValueError):
    """A persisted tag state record is corrupt, truncated or of an unknown version."""


class KeyFileError(SwarmtagError, ValueError):
    """A site or role key file cannot be used: missing, readable by others, or another kind.

    The message names the file and what to do; it never contains the key or
    any other byte of the file, so it is safe to log.
    """


class CounterFileError(SwarmtagError, ValueError):
    """A writer's counter file cannot be used: not a counter file, corrupt, or not writable.

    The message names the file and what to do.
    """


class PolicyError(SwarmtagError, ValueError):
    """A selection policy got a bad parameter, condition name or input arrays."""


class EventLogError(SwarmtagError, ValueError):
    """An event log breaks the schema; the message names the file, row and column."""


class BagError(SwarmtagError, ValueError):
    """A ROS 2 bag or its topic mapping cannot give an event log, or a recording cannot be written.

    The message names the bag and the topic, field, trial or mapping key at fault.
    """


class StatisticsError(SwarmtagError, ValueError):
    """Metrics or statistics got input they cannot use (no runs, unknown baseline, bad option)."""


class ConfigError(SwarmtagError, ValueError):
    """A scenario or a tag backend has a bad value or an unknown key; the message names it."""


class RadioError(SwarmtagError, RuntimeError):
    """The BLE radio cannot be used: no adapter, no BlueZ, no permission, or failures past retry.

    The message says what is missing and how to get it.
    """


class SimulationError(SwarmtagError, RuntimeError):
    """The simulator broke one of its own contracts (a bug, never bad user input)."""


class InvariantError(SimulationError):
    """A world-state invariant failed in checking mode; the message names run, tick and rule."""


class DeterminismError(SimulationError):
    """A run gave different results alone, in a batch or in another process."""


class ConformanceError(SwarmtagError):
    """A controller departed from the built-in controller; the message names the first place."""


class StudyError(SwarmtagError, ValueError):
    """A study file or study option is not allowed; the message names the file and the key."""


class CalibrationError(SwarmtagError, ValueError):
    """A calibration baseline, free parameter or option is refused; the message names it."""


class StoreError(SwarmtagError, RuntimeError):
    """The results store cannot be opened, or holds rows that contradict its own keys."""


class OutputError(SwarmtagError, ValueError):
    """An output path is refused before any work: no folder, a folder, unwritable, or twice."""


class ResourceError(SwarmtagError, ValueError):
    """The work asked for cannot fit this machine; the message gives the estimate and the limit."""


class PerceptionError(SwarmtagError, ValueError):
    """A camera image, camera file or marker input cannot be used; the message names it."""


class BackendFallback(UserWarning):
    """A run goes to the reference backend because the chosen one cannot run its rule."""
