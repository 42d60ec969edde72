"""Score rules of one's own: a Python function that ranks one robot's candidates.

A rule is ``score(urgency, distance, **context) -> scores``: numbers over the
candidates, larger better, the built-in tie rule after (nearer, then smaller
marker). It must score each candidate on its own values alone (elementwise),
because the simulator calls it once on a whole batch of ``(runs, robots,
carriers)`` arrays and the behaviour tree on one robot's ``(carriers,)``. The
context a rule may ask for by naming it as a keyword parameter (``CONTEXT``):

- ``marker``: the carriers' marker ids (integers);
- ``age``: seconds since each carrier's order time (its waiting time; what
  the warehouse management system knows, as the FIFO heuristic uses it).

A rule comes from a file (``FILE.py:FUNCTION``, ``load_rule``) or from a
package's entry point in the group ``swarmtag.policies``; its condition name
is the function's (or entry point's) name. Rules in use are registered in
this process so that condition names read back (``parse_policy``).
"""

from __future__ import annotations

import hashlib
import importlib.util
import inspect
import re
import sys
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from importlib.metadata import entry_points
from pathlib import Path
from types import ModuleType
from typing import Any, Final

import numpy as np
import numpy.typing as npt

from swarmtag._checks import check_instance, check_path_value, check_text
from swarmtag.errors import PolicyError
from swarmtag.policy._policies import Policy

__all__ = [
    "CONTEXT",
    "RULE_GROUP",
    "ScoreRule",
    "load_rule",
    "register_rule",
    "registered_rule",
    "rule_entry_points",
]

CONTEXT: Final = ("marker", "age")
"""The context keywords a rule may declare (module docstring)."""
RULE_GROUP: Final = "swarmtag.policies"
"""The entry-point group through which packages register score rules (``name = "module:fn"``)."""
_NAME: Final = re.compile(r"[A-Za-z][A-Za-z0-9_]*")
_REGISTERED: dict[str, tuple[str, ScoreRule]] = {}
"""Rules by condition name, each with its origin (a resolved file path, an entry point)."""


@dataclass(frozen=True, slots=True, eq=False)
class ScoreRule(Policy):
    """A user's score function as a policy; its condition name is ``label``.

    ``function(urgency, distance, **context)`` gets float64 arrays of one
    shape (and the context keywords it declares, ``CONTEXT``) and returns
    finite scores of that shape. Python code: the reference backend and the
    behaviour tree run it; the compiled backend cannot (``compiled`` is False).
    """

    label: str
    function: Callable[..., Any] = field(repr=False)
    source: str
    """Where it came from: ``rules.py:by_urgency`` or ``entry point pkg.mod:fn``."""
    wants: tuple[str, ...] = ()
    """The context keywords the function declares (checked by ``ScoreRule.make``)."""

    @classmethod
    def make(cls, label: str, function: object, source: str) -> ScoreRule:
        """A rule checked for its name and signature (``PolicyError``, one line, otherwise)."""
        if not _NAME.fullmatch(label):
            msg = (
                f"{source}: {label!r} cannot name a condition (letters, digits, _; a letter first)"
            )
            raise PolicyError(msg)
        from swarmtag.policy._catalogue import rule_info  # noqa: PLC0415 - the catalogue imports us

        if rule_info(label) is not None:
            msg = f"{source}: {label!r} is a built-in rule's name; rename the function"
            raise PolicyError(msg)
        if not callable(function):
            msg = f"{source}: {function!r} is not a function"
            raise PolicyError(msg)
        return cls(label=label, function=function, source=source, wants=_wants(function, source))

    @property
    def name(self) -> str:
        """The condition name: the function's name."""
        return self.label

    @property
    def context_names(self) -> tuple[str, ...]:
        """The context keywords the function declares."""
        return self.wants

    @property
    def compiled(self) -> bool:
        """False: Python code, which the compiled kernel cannot call."""
        return False

    @property
    def kernel_form(self) -> tuple[int, float]:
        """None exists: raises ``PolicyError`` (check ``compiled`` first)."""
        msg = f"rule {self.label!r} ({self.source}) is Python code and has no compiled form"
        raise PolicyError(msg)

    def _formula(
        self, urgency: npt.NDArray[np.float64], distance: npt.NDArray[np.float64]
    ) -> npt.NDArray[np.float64]:
        return self.scores(urgency, distance, {})

    def scores(
        self,
        urgency: npt.NDArray[np.float64],
        distance: npt.NDArray[np.float64],
        context: Mapping[str, npt.ArrayLike],
    ) -> npt.NDArray[np.float64]:
        """The function's scores, checked: one finite float per candidate."""
        result = self.raw_scores(urgency, distance, context)
        problem = self.non_finite(result)
        if problem is not None:
            raise PolicyError(problem)
        return result

    def non_finite(self, result: npt.NDArray[np.float64]) -> str | None:
        """Why ``result`` cannot be scores (a NaN or infinite one), or None."""
        if not result.size or np.isfinite(result).all():
            return None
        bad = float(result[~np.isfinite(result)][0])
        return f"rule {self.label!r} ({self.source}) returned a score of {bad}; scores are finite"

    def raw_scores(
        self,
        urgency: npt.NDArray[np.float64],
        distance: npt.NDArray[np.float64],
        context: Mapping[str, npt.ArrayLike],
    ) -> npt.NDArray[np.float64]:
        """The function's scores, one float per candidate, finite or not (``check_rule``)."""
        given = {}
        for key in self.wants:
            if key not in context:
                msg = f"rule {self.label!r} ({self.source}) asks for {key!r}, not given here"
                raise PolicyError(msg)
            given[key] = np.broadcast_to(np.asarray(context[key]), urgency.shape)
        try:
            with np.errstate(all="ignore"):  # a division by zero shows as a non-finite score
                out = self.function(urgency, distance, **given)
                result = np.array(out, dtype=np.float64)
        except Exception as exc:  # noqa: BLE001 - a user's code: any failure is theirs, told in one line
            msg = f"rule {self.label!r} ({self.source}) raised {type(exc).__name__}: {exc}"
            raise PolicyError(msg) from None
        if result.shape != urgency.shape:
            try:
                result = np.array(np.broadcast_to(result, urgency.shape))
            except ValueError:
                msg = (
                    f"rule {self.label!r} ({self.source}) returned shape {result.shape} "
                    f"for {urgency.shape} candidates; return one score per candidate"
                )
                raise PolicyError(msg) from None
        return result


def _wants(function: Callable[..., Any], source: str) -> tuple[str, ...]:
    """The context keywords ``function`` declares; ``PolicyError`` if it cannot take a call."""
    try:
        signature = inspect.signature(function)
    except (TypeError, ValueError):
        return ()  # a builtin or compiled callable: called with urgency and distance alone
    parameters = signature.parameters.values()
    wants: tuple[str, ...] = CONTEXT
    if not any(p.kind is p.VAR_KEYWORD for p in parameters):
        wants = tuple(p.name for p in parameters if p.name in CONTEXT)
    try:
        signature.bind(1.0, 1.0, **dict.fromkeys(wants, 0))
    except TypeError as exc:
        msg = (
            f"{source}: a rule takes (urgency, distance, **context) with context from "
            f"{', '.join(CONTEXT)}; this one takes {signature} ({exc})"
        )
        raise PolicyError(msg) from None
    return wants


def register_rule(rule: ScoreRule, *, origin: str | None = None) -> ScoreRule:
    """Make ``rule``'s condition name read back in this process (``parse_policy``).

    ``origin`` says where it comes from (default: its ``source``): the same
    origin registers again (an edited file replaces its rule), another
    origin under a name already registered is refused.
    """
    check_instance("rule", rule, ScoreRule, error=PolicyError)
    if origin is not None:
        check_text("origin", origin, error=PolicyError)
    origin = rule.source if origin is None else origin
    held = _REGISTERED.get(rule.label)
    if held is not None and held[0] != origin:
        msg = f"{rule.source}: condition {rule.label!r} is already the rule from {held[1].source}"
        raise PolicyError(msg)
    if held is None or held[1].function is not rule.function:
        _REGISTERED[rule.label] = (origin, rule)
    return _REGISTERED[rule.label][1]


def registered_rule(name: str) -> ScoreRule | None:
    """The rule registered (or offered by an entry point) under condition ``name``, or None."""
    check_text("name", name, error=PolicyError)
    held = _REGISTERED.get(name)
    if held is not None:
        return held[1]
    for entry in entry_points(group=RULE_GROUP):
        if entry.name == name:
            try:
                function = entry.load()
            except Exception as exc:  # noqa: BLE001 - a package's code: told in one line
                msg = f"rule {name!r}: its entry point {entry.value!r} failed to load ({exc})"
                raise PolicyError(msg) from None
            rule = ScoreRule.make(name, function, f"entry point {entry.value}")
            return register_rule(rule, origin=f"entry point {entry.value}")
    return None


def rule_entry_points() -> tuple[tuple[str, str], ...]:
    """``(name, target)`` of every rule the installed packages register, sorted by name."""
    found = {entry.name: entry.value for entry in entry_points(group=RULE_GROUP)}
    return tuple(sorted(found.items()))


def load_rule(spec: str, *, base: Path | None = None) -> ScoreRule:
    """The rule ``FILE.py:FUNCTION`` (``FILE`` relative to ``base``), loaded and registered.

    Every way a file can be wrong (missing, a syntax error, an import that
    raises, no such function, a signature a rule cannot have) is one
    ``PolicyError`` line naming the file.
    """
    check_text("rule file", spec, error=PolicyError)
    if base is not None:
        base = Path(check_path_value("base", base, error=PolicyError))
    path_text, sep, function_name = spec.rpartition(":")
    if not sep or not path_text or not function_name:
        msg = f"rule file: {spec!r} is not FILE.py:FUNCTION"
        raise PolicyError(msg)
    path = Path(path_text)
    if base is not None and not path.is_absolute():
        path = base / path
    module, origin = _load_module(path, path_text)
    function = getattr(module, function_name, None)
    if function is None:
        defined = sorted(
            name
            for name, value in vars(module).items()
            if inspect.isfunction(value) and not name.startswith("_")
        )
        listed = ", ".join(defined) or "none"
        msg = f"{path_text}: no function {function_name!r} (it defines: {listed})"
        raise PolicyError(msg)
    rule = ScoreRule.make(function_name, function, f"{path_text}:{function_name}")
    return register_rule(rule, origin=origin)


def _load_module(path: Path, shown: str) -> tuple[ModuleType, str]:
    """The Python file ``path`` imported as a module of its own, and its resolved path.

    The module is cached by path and content: loading an unchanged file
    again gives the same functions; an edited one is imported afresh.
    Errors are named by ``shown``.
    """
    if path.suffix != ".py":
        msg = f"{shown}: a rule file is a Python file ending in .py"
        raise PolicyError(msg)
    try:
        content = path.read_bytes()
    except FileNotFoundError:
        msg = f"{shown}: no such file"
        raise PolicyError(msg) from None
    except OSError as exc:
        msg = f"{shown}: cannot be read ({exc.strerror or exc})"
        raise PolicyError(msg) from None
    resolved = str(path.resolve())
    key = hashlib.sha256(resolved.encode() + b"\0" + content).hexdigest()[:16]
    name = f"swarmtag_rules_{key}"
    loaded = sys.modules.get(name)
    if loaded is not None:
        return loaded, resolved
    spec = importlib.util.spec_from_file_location(name, resolved)
    if spec is None or spec.loader is None:
        msg = f"{shown}: cannot be imported as a Python file"
        raise PolicyError(msg)
    module = importlib.util.module_from_spec(spec)
    try:
        spec.loader.exec_module(module)
    except SyntaxError as exc:
        msg = f"{shown}: line {exc.lineno}: {exc.msg}"
        raise PolicyError(msg) from None
    except Exception as exc:  # noqa: BLE001 - a user's file: any failure is told in one line
        msg = f"{shown}: importing it raised {type(exc).__name__}: {exc}"
        raise PolicyError(msg) from None
    sys.modules[name] = module
    return module, resolved
