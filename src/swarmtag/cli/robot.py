"""``swarmtag robot``: the robot's controller — its behaviour tree as text and as a picture."""

from __future__ import annotations

from pathlib import Path

import click

from swarmtag._outputs import OutputPlan
from swarmtag.errors import ConfigError

__all__ = ["robot"]


@click.group("robot")
def robot() -> None:
    """The robot's controller (the behaviour tree of docs/controller.md; the robot extra)."""


@robot.command("tree")
@click.option(
    "--out",
    "folder",
    type=click.Path(path_type=Path),
    help="Also write the tree as robot-tree.dot (and .png, .svg where Graphviz is installed).",
)
def tree_cmd(folder: Path | None) -> None:
    """Print the behaviour tree every robot runs, as text; draw it with --out."""
    try:
        from swarmtag.robot.tree import ascii_picture, create_tree, dot_picture  # noqa: PLC0415
    except ModuleNotFoundError as missing:
        msg = f"the behaviour tree needs {missing.name} (pip install 'swarmtag[robot]')"
        raise ConfigError(msg) from None
    from swarmtag.policy import Urgency  # noqa: PLC0415
    from swarmtag.robot import ControllerConfig  # noqa: PLC0415
    from swarmtag.sim import Scenario, make_params  # noqa: PLC0415

    config = ControllerConfig.from_params(make_params(Scenario.default(), Urgency(alpha=0.7)))
    tree = create_tree(config, "/swarmtag/cli/robot")
    plan = OutputPlan()
    if folder is not None:
        plan.folder("--out", folder)
    with plan.writing() as stage:
        click.echo(ascii_picture(tree), nl=False)
        if folder is not None:
            written = [folder / path.name for path in dot_picture(tree, stage.path(folder))]
            click.echo(_written_line(written), err=True)


def _written_line(written: list[Path]) -> str:
    """One line naming the files written, and why there is no PNG or SVG where there is none."""
    names = ", ".join(map(str, written))
    if any(path.suffix == ".png" for path in written):
        return f"wrote {names}"
    return f"wrote {names} only: PNG and SVG need Graphviz (its `dot` program on the PATH)"
