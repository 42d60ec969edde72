"""A calibration problem: targets, base profile, fixed settings and free parameters, checked.

Everything that could refuse is checked when the problem is built, before
any simulation: every free key is a real-valued scenario setting (checked by
building every set-up's scenario at both of its bounds), no set-up or
``--set`` fixes a free key, no ``--set`` is silently overridden by a set-up,
and the base profile logs in the baseline's time unit.

Layers, later ones winning: the base profile, ``--set`` (both written into
the fitted profile), the free parameters' values, then a set-up's scenario
(robots, carriers, ticks, urgency model: the experiment, not the profile).
"""

from __future__ import annotations

import hashlib
import json
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any, Final

from swarmtag._checks import MAX_SEED, check_int
from swarmtag.calibration.free import FreeParameter
from swarmtag.calibration.spec import MAX_RUNS, Setup, Targets
from swarmtag.errors import CalibrationError, ConfigError
from swarmtag.experiments.spec import model_digest
from swarmtag.sim import Scenario
from swarmtag.sim.config.mapping import flat_keys, merge_layers
from swarmtag.sim.config.profiles import Profile

__all__ = ["CACHE_FORMAT", "CalibrationProblem"]

CACHE_FORMAT: Final = "swarmtag-calibration-1"
"""Part of every cache key: a new format never reads old entries."""
_UNITS: Final = {"tick": "ticks", "s": "seconds"}


def _canonical(value: object) -> str:
    return json.dumps(value, sort_keys=True, separators=(",", ":"), allow_nan=False, default=str)


@dataclass(frozen=True)
class CalibrationProblem:
    """What to fit, to what, from where; ``values`` below are ``{free key: float}``.

    ``runs`` overrides every set-up's runs when given; ``model`` is the
    model's source digest (part of every cache key, so a changed model never
    reuses evaluations).
    """

    targets: Targets
    profile: Profile
    free: tuple[FreeParameter, ...]
    settings: Mapping[str, Any] = field(default_factory=dict)
    runs: int | None = None
    seed: int = 0
    model: str = field(default_factory=model_digest)

    def __post_init__(self) -> None:
        if not self.free:
            raise CalibrationError("no free parameters: give --free NAME=LO:HI")
        if self.runs is not None:
            check_int("--runs", self.runs, low=1, high=MAX_RUNS, error=CalibrationError)
        check_int("--seed", self.seed, low=0, high=MAX_SEED, error=CalibrationError)
        try:
            Profile(name=self.profile.name, values=self.base_values)
        except ConfigError as error:
            raise CalibrationError(f"--set: {error}") from None
        self._check_layers()
        self._check_free()
        self._check_time_unit()

    # --- layers --------------------------------------------------------------------------

    @property
    def base_values(self) -> dict[str, Any]:
        """The base profile's values with ``--set`` merged in (what the fitted profile keeps)."""
        return merge_layers(self.profile.values, self.settings)

    def profile_values(self, values: Mapping[str, float]) -> dict[str, Any]:
        """The fitted profile's values: the base values with the free values substituted."""
        return merge_layers(self.base_values, values)

    def simulated_runs(self, setup: Setup) -> int:
        """Runs simulated of ``setup`` at each evaluation (``--runs`` or the set-up's own)."""
        return setup.runs if self.runs is None else self.runs

    def scenario(self, setup: Setup, values: Mapping[str, float]) -> Scenario:
        """The scenario of ``setup`` at the free ``values``."""
        return Scenario.from_mapping(merge_layers(self.profile_values(values), setup.scenario))

    # --- checks --------------------------------------------------------------------------

    def _check_layers(self) -> None:
        fixed = set(flat_keys(self.settings))
        free = {parameter.key for parameter in self.free}
        for key in sorted(free & fixed):
            msg = f"--free {key}: --set {key}=... fixes it too; drop one of them"
            raise CalibrationError(msg)
        for setup in self.targets.setups:
            owned = set(flat_keys(setup.scenario))
            for key in sorted(free & owned):
                msg = f"--free {key}: set-up {setup.name!r} of {self.targets.source} sets it"
                raise CalibrationError(msg)
            for key in sorted(fixed & owned):
                msg = f"--set {key}: set-up {setup.name!r} of {self.targets.source} sets it "
                msg += "(its own value would win)"
                raise CalibrationError(msg)
            try:
                self.scenario(setup, {})
            except ConfigError as error:
                msg = f"{self.targets.source}: set-up {setup.name!r} on profile "
                msg += f"{self.profile.name!r}: {error}"
                raise CalibrationError(msg) from None

    def _check_free(self) -> None:
        resolved = flat_keys(self.scenario(self.targets.setups[0], {}).to_mapping())
        for parameter in self.free:
            where = f"--free {parameter.key}"
            if parameter.key not in resolved:
                msg = f"{where}: not a scenario key (docs/simulator.md lists them, e.g. "
                msg += "tick, camera.range, timing.dock)"
                raise CalibrationError(msg)
            current = resolved[parameter.key]
            if isinstance(current, bool) or not isinstance(current, float):
                integer = isinstance(current, int) and not isinstance(current, bool)
                kind = "an integer" if integer else "not a number"
                msg = f"{where}: the setting is {kind} ({current!r}); only real-valued "
                msg += "settings can be fitted"
                raise CalibrationError(msg)
            for label, bound in (("LO", parameter.low), ("HI", parameter.high)):
                for setup in self.targets.setups:
                    try:
                        self.scenario(setup, {parameter.key: bound})
                    except ConfigError as error:
                        msg = f"{where}: {label} = {bound:g} is refused in set-up "
                        msg += f"{setup.name!r} ({error})"
                        raise CalibrationError(msg) from None

    def _check_time_unit(self) -> None:
        wanted = self.targets.time_unit
        if wanted is None:
            return
        for setup in self.targets.setups:
            unit = self.scenario(setup, {}).time_unit
            if unit != wanted:
                msg = f"{self.targets.source} is in {_UNITS[wanted]} but profile "
                msg += f"{self.profile.name!r} logs in {_UNITS[unit]}: use a profile with "
                msg += f'time_unit = "{wanted}" or --set time_unit={wanted}'
                raise CalibrationError(msg)

    # --- cache keys ----------------------------------------------------------------------

    def point_key(self, values: Mapping[str, float]) -> str:
        """The cache key of an evaluation at ``values`` (hex SHA-256).

        Covers the cache format, the targets' digest, the base values (with
        ``--set``), the condition, the free values, the runs of every set-up,
        the seed and the model digest.
        """
        content = {
            "format": CACHE_FORMAT,
            "targets": self.targets.digest,
            "base": self.base_values,
            "condition": self.targets.condition,
            "values": {key: float(value) for key, value in values.items()},
            "runs": {setup.name: self.simulated_runs(setup) for setup in self.targets.setups},
            "seed": self.seed,
            "model": self.model,
        }
        return hashlib.sha256(_canonical(content).encode()).hexdigest()
