"""``swarmtag aruco render|detect``: a synthetic camera image of a carrier; markers in a photo.

Both read a camera file (``--camera FILE``, or a shipped rig's name; default
``dots-like``; docs/perception.md gives the layout) and use one of its cameras
(``--view``). OpenCV is the ``vision`` extra: without it both refuse in one line.
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import click
import numpy as np

from swarmtag._checks import check_number
from swarmtag._inputs import is_regular_file
from swarmtag._outputs import OutputPlan
from swarmtag.errors import PerceptionError

__all__ = ["aruco"]

_CAMERA_HELP = "Camera file (TOML, docs/perception.md) or a shipped rig's name."


def _number(option: str, value: float, low: float, high: float) -> float:
    """A finite option value in [low, high] (click's float type lets NaN and infinities in)."""
    return check_number(option, value, low=low, high=high, error=PerceptionError)


def _rig(camera: str, plan: OutputPlan | None = None) -> Any:  # noqa: ANN401 - a Rig
    from swarmtag.perception import load_rig  # noqa: PLC0415 - numpy-only, but not at start-up

    if plan is not None and (camera.endswith(".toml") or is_regular_file(camera)):
        plan.input("--camera", Path(camera))
    return load_rig(camera)


def _camera_option(command: Any) -> Any:  # noqa: ANN401 - a click command
    command = click.option(
        "--view",
        metavar="NAME",
        help="Which of the file's cameras (render: the one facing the carrier; detect: the first).",
    )(command)
    return click.option(
        "--camera",
        "camera",
        default="dots-like",
        show_default=True,
        metavar="FILE|NAME",
        help=_CAMERA_HELP,
    )(command)


@click.group("aruco")
def aruco() -> None:
    """The cameras' ArUco markers (ARUCO_MIP_36h12, 50 mm): synthetic images and detection."""


@aruco.command("render")
@click.option(
    "--marker",
    required=True,
    type=click.IntRange(0, 249),
    help="The carrier's marker id 0-249 (the dictionary's ids; not one of an underside map's).",
)
@click.option(
    "--distance",
    required=True,
    type=float,
    metavar="M",
    help="Robot centre to carrier centre (m, 0-20).",
)
@click.option(
    "--bearing",
    required=True,
    type=float,
    metavar="DEG",
    help="Direction of the carrier (deg, counter-clockwise from forward, -180-180).",
)
@click.option(
    "--turn",
    default=0.0,
    show_default=True,
    type=float,
    metavar="DEG",
    help="The carrier turned this far off square to the robot (deg, -180-180).",
)
@_camera_option
@click.option(
    "--blur", default=0.0, show_default=True, type=float, help="Gaussian blur sigma (px)."
)
@click.option(
    "--noise",
    default=0.0,
    show_default=True,
    type=float,
    help="Sensor noise sigma (grey levels of 255).",
)
@click.option("--exposure", default=1.0, show_default=True, type=float, help="Exposure gain.")
@click.option(
    "--occlusion",
    default=0.0,
    show_default=True,
    type=float,
    help="Share (0-1) of each marker's width hidden behind a dark bar.",
)
@click.option(
    "--seed",
    default=0,
    show_default=True,
    type=click.IntRange(0, 2**63 - 1),
    help="Seed of the noise and occlusion draws.",
)
@click.option(
    "--out",
    required=True,
    type=click.Path(path_type=Path),
    metavar="PNG",
    help="The .png file to write (its folder must exist).",
)
def render_cmd(
    *,
    marker: int,
    distance: float,
    bearing: float,
    turn: float,
    camera: str,
    view: str | None,
    blur: float,
    noise: float,
    exposure: float,
    occlusion: float,
    seed: int,
    out: Path,
) -> None:
    """Write the 8-bit grey image a camera takes of a carrier placed at DISTANCE and BEARING."""
    from swarmtag.perception import Conditions, Placement, render  # noqa: PLC0415
    from swarmtag.perception._opencv import opencv  # noqa: PLC0415

    distance = _number("--distance", distance, 0.0, 20.0)
    bearing = _number("--bearing", bearing, -180.0, 180.0)
    turn = _number("--turn", turn, -180.0, 180.0)
    conditions = Conditions(blur=blur, noise=noise, exposure=exposure, occlusion=occlusion)
    plan = OutputPlan()
    rig = _rig(camera, plan)
    chosen = rig.camera(view) if view is not None else rig.facing(bearing)
    cv2 = opencv()
    target = plan.file("--out", out, suffixes=(".png",))
    rng = np.random.default_rng(np.random.SeedSequence(seed))
    image = render(
        chosen, rig.carrier, [Placement.at(marker, distance, bearing, turn)], conditions, rng=rng
    )
    ok, encoded = cv2.imencode(".png", image)
    if not ok:  # pragma: no cover - OpenCV encodes any 8-bit grey array
        msg = f"--out: OpenCV could not encode the image as PNG ({out})"
        raise PerceptionError(msg)
    with plan.writing() as stage:
        stage.path(target).write_bytes(encoded.tobytes())
    lens = chosen.intrinsics
    click.echo(
        f"wrote camera image: {out} (camera {chosen.name}, {lens.width}x{lens.height}; "
        f"marker {marker} at {distance:g} m, bearing {bearing:g} deg)"
    )


def _round(values: Any, digits: int = 4) -> Any:  # noqa: ANN401 - nested lists of floats
    return np.round(np.asarray(values, dtype=np.float64), digits).tolist()


@aruco.command("detect")
@click.argument("image", type=click.Path(path_type=Path))
@_camera_option
@click.option(
    "--heading",
    type=float,
    metavar="DEG",
    help="The robot's heading in the world (deg): faces taken on the world's axes.",
)
@click.option("--json", "as_json", is_flag=True, help="Print everything as one JSON object.")
def detect_cmd(
    image: Path, camera: str, view: str | None, heading: float | None, *, as_json: bool
) -> None:
    """Find the markers in IMAGE, a photo from one camera of the camera file.

    Prints each carrier's id, distance, bearing and predock point; from the upward
    camera, the centring offset (from every marker of the carriers' underside map in
    view, where the camera file gives one: map markers name no carrier).
    """
    from swarmtag.perception import centring_offset, detect_markers, fuse  # noqa: PLC0415
    from swarmtag.perception._opencv import opencv  # noqa: PLC0415
    from swarmtag.perception.images import check_camera, read_image  # noqa: PLC0415

    if heading is not None:
        heading = _number("--heading", heading, -360.0, 360.0)
    rig = _rig(camera)
    chosen = rig.camera(view) if view is not None else rig.cameras[0]
    check_camera(chosen, camera)
    opencv()  # one line if the extra is missing, before the image is looked at
    found = detect_markers(read_image(image, chosen), chosen, rig.carrier)
    carriers = fuse(found, rig.carrier, heading=heading)
    centring = centring_offset(found) if chosen.upward else None
    markers = []
    for d in found:
        entry: dict[str, Any] = {
            "id": d.marker,
            "corners": _round(d.corners, 2),
            "distance": round(d.distance, 4),
            "bearing": round(d.bearing, 2),
            "position": _round(d.position),
            "normal": _round(d.normal),
            "camera_distance": round(d.camera_distance, 4),
            "side_pixels": round(d.side_pixels, 2),
            "reprojection_error": round(d.reprojection_error, 3),
        }
        if d.map_offset is not None:  # only on a map: old camera files print what they did
            entry["map_offset"] = _round(d.map_offset)
        markers.append(entry)
    report = {
        "image": str(image),
        "camera": chosen.name,
        "markers": markers,
        "carriers": [],
        "centring": None,
    }
    for estimate in carriers:
        predock = estimate.predock(rig.carrier)
        entry = {
            "id": estimate.marker,
            "distance": round(estimate.distance, 4),
            "bearing": round(estimate.bearing, 2),
            "position": _round(estimate.position),
            "yaw": round(estimate.yaw, 2),
            "markers": estimate.markers,
            "predock": {"point": _round(predock.point), "heading": round(predock.heading, 2)},
        }
        if heading is not None:
            entry["predock"]["face"] = predock.face(heading).name.lower()
        report["carriers"].append(entry)
    if centring is not None:
        report["centring"] = {
            "id": centring.marker,
            "offset": _round(centring.offset),
            "error": round(centring.error, 4),
            "yaw": round(centring.yaw, 2),
            "centred": centring.centred(),
        }
        if any(d.in_map for d in found):
            report["centring"]["map_markers"] = centring.markers
    if as_json:
        click.echo(json.dumps(report))
        return
    _print_report(report, chosen.name)


def _print_report(report: dict[str, Any], camera: str) -> None:
    markers, carriers = report["markers"], report["carriers"]
    click.echo(f"camera {camera}: {len(markers)} marker(s), {len(carriers)} carrier(s)")
    if carriers:
        click.echo(f"{'id':>4}  {'distance':>9}  {'bearing':>8}  {'markers':>7}  predock (x, y) m")
    for entry in carriers:
        x, y = entry["predock"]["point"]
        click.echo(
            f"{entry['id']:>4}  {entry['distance']:>7.3f} m  {entry['bearing']:>6.1f}°  "
            f"{entry['markers']:>7}  ({x:.3f}, {y:.3f}), heading {entry['predock']['heading']:.1f}°"
        )
    centring = report["centring"]
    if centring is not None:
        dx, dy = centring["offset"]
        state = "centred" if centring["centred"] else "not centred"
        what = centring["id"]
        if "map_markers" in centring:
            what = f"the underside map {what} ({centring['map_markers']} markers)"
        click.echo(
            f"centring on {what}: move ({dx * 100:+.1f}, {dy * 100:+.1f}) cm, "
            f"turn {centring['yaw']:.1f}°: {state}"
        )
    if not markers:
        click.echo("no marker found")
