"""Scenario options shared by the commands that simulate: profile, file, flags, ``--set``.

Layers, later ones winning: the profile (``--profile``, default
``paper-sim``), a scenario TOML file (``--config``), the named flags, then
``--set KEY=VALUE`` overrides of any scenario key (dotted for tables:
``--set camera.memory=20``). Explicit settings always win over the profile.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Any, Final, TypeVar

import click

from swarmtag._toml import MAX_TOML_DEPTH, toml_value
from swarmtag.errors import ConfigError
from swarmtag.sim import Scenario
from swarmtag.sim.backends import BACKENDS
from swarmtag.sim.config.mapping import load_toml
from swarmtag.sim.config.profiles import DEFAULT_PROFILE, load_profile
from swarmtag.sim.config.sensors import OCCLUSION_MODELS, PERCEPTION_MODELS

__all__ = [
    "SCENARIO_FLAGS",
    "backend_option",
    "build_scenario",
    "note_compilation",
    "parse_set",
    "scenario_options",
]

_F = TypeVar("_F", bound=Callable[..., Any])

SCENARIO_FLAGS: Final = {
    "robots": "robots",
    "carriers": "carriers",
    "ticks": "ticks",
    "tick": "tick",
    "detection_radius": "detection_radius",
    "perception": "perception",
    "camera_range": "camera.range",
    "camera_memory": "camera.memory",
    "occlusion": "camera.occlusion",
    "radio_range": "radio.range",
    "urgency_model": "urgency.model",
}
"""Keyword of each named scenario flag -> the scenario key it sets."""


backend_option = click.option(
    "--backend",
    type=click.Choice(tuple(BACKENDS)),
    default=None,
    help="Simulation backend: the numpy reference kernel, or the compiled kernel (numba, the "
    "fast extra; the same results) [default: fast where numba is installed].",
)


def note_compilation(backend: str) -> None:
    """Say on stderr that the fast kernel is about to be compiled (once per machine)."""
    if backend != "fast":
        return
    from swarmtag.sim.fast import kernel_compiled  # noqa: PLC0415 - numba is an extra

    if not kernel_compiled():
        click.echo(
            "swarmtag: compiling the fast simulation kernel for this machine "
            "(once: about a minute or two; later runs load it)",
            err=True,
        )


def parse_set(text: str) -> tuple[str, Any]:
    """``KEY=VALUE`` with VALUE read as a TOML value (bare words as strings).

    >>> parse_set("camera.memory=20"), parse_set("camera.occlusion=carriers")
    (('camera.memory', 20), ('camera.occlusion', 'carriers'))
    """
    key, equals, raw = text.partition("=")
    key = key.strip()
    if not equals or not key:
        msg = f"--set: {text!r} is not KEY=VALUE (e.g. camera.memory=20)"
        raise ConfigError(msg)
    parts = key.count(".") + 1
    shown = key if len(key) <= 40 else f"{key[:40]}..."
    if parts > MAX_TOML_DEPTH:  # a deeper key would nest the merged scenario as deep
        msg = f"--set: key {shown!r} has {parts} dotted parts; at most {MAX_TOML_DEPTH}"
        raise ConfigError(msg)
    value: Any = toml_value(raw, source=f"--set {shown}", error=ConfigError)
    return key, value


def scenario_options(command: _F) -> _F:
    """Add the scenario options (profile, file, named flags, ``--set``) to a click command."""
    options = [
        click.option(
            "--profile",
            default=DEFAULT_PROFILE,
            show_default=True,
            metavar="NAME|FILE",
            help="Profile of free parameters (swarmtag profiles lists the shipped ones).",
        ),
        click.option(
            "--config",
            type=click.Path(exists=True, dir_okay=False, path_type=Path),
            help="Scenario TOML file, merged on top of the profile; the flags override it.",
        ),
        click.option("--robots", type=click.IntRange(min=1), help="Robots per run [default: 3]."),
        click.option(
            "--carriers", type=click.IntRange(min=1), help="Carriers per run [default: 7]."
        ),
        click.option(
            "--ticks", type=click.IntRange(min=1), help="Run length T in ticks [default: 3000]."
        ),
        click.option(
            "--tick",
            type=click.FloatRange(min=0, min_open=True),
            help="Seconds of robot time per tick [default: the profile's].",
        ),
        click.option(
            "--perception",
            type=click.Choice(PERCEPTION_MODELS),
            help="split: radio and camera apart (docs/simulator.md); disc: one detection radius.",
        ),
        click.option(
            "--detection-radius",
            type=click.FloatRange(min=0, min_open=True),
            help="Detection radius R in metres of the disc perception model.",
        ),
        click.option(
            "--camera-range",
            type=click.FloatRange(min=0, min_open=True),
            help="Camera range in metres (split perception).",
        ),
        click.option(
            "--camera-memory",
            type=click.FloatRange(min=0),
            help="Seconds a robot remembers where it saw a carrier (split perception).",
        ),
        click.option(
            "--occlusion",
            type=click.Choice(OCCLUSION_MODELS),
            help="What blocks the camera's line of sight (split perception).",
        ),
        click.option(
            "--radio-range",
            type=click.FloatRange(min=0, min_open=True),
            help="BLE range in metres (split perception).",
        ),
        click.option(
            "--urgency-model",
            type=click.Choice(["growing", "static"]),
            help="How urgencies arise [default: growing].",
        ),
        click.option(
            "--set",
            "settings",
            multiple=True,
            metavar="KEY=VALUE",
            help="Set any scenario key, repeatable: --set camera.memory=20 --set timing.dock=2.",
        ),
    ]
    for option in reversed(options):
        command = option(command)
    return command


def build_scenario(
    *,
    profile: str,
    config: Path | None,
    flags: dict[str, Any],
    settings: Sequence[str] = (),
) -> Scenario:
    """The scenario of the layers (profile, file, flags, ``--set``); errors name the layer."""
    chosen = load_profile(profile)
    file_values: dict[str, Any] = {}
    if config is not None:
        file_values = load_toml(config)
        try:
            chosen.scenario(file_values)
        except ConfigError as error:
            msg = f"{config}: {error}"
            raise ConfigError(msg) from None
    named = {
        SCENARIO_FLAGS[name]: value
        for name, value in flags.items()
        if value is not None and name in SCENARIO_FLAGS
    }
    overrides = dict(parse_set(text) for text in settings)
    return chosen.scenario(file_values, named, overrides)
