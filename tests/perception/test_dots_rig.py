"""The DOTS robot's own cameras (the ``dots`` rig): what its public code says, and what it reads."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

from swarmtag.cli import main
from swarmtag.perception import Nuisance, load_rig, run_range_study

pytest.importorskip("cv2")

RIG = load_rig("dots")


def test_the_rig_is_the_robots_camera_as_its_public_code_gives_it():
    lens = RIG.perimeter[0].intrinsics
    assert (lens.width, lens.height, lens.fx, lens.fy) == (640, 480, 330.0, 330.0)
    assert (lens.cx, lens.cy) == (319.5, 239.5)
    assert lens.distortion[0] == -0.1
    assert lens.horizontal_fov == pytest.approx(88.2, abs=0.1)  # not the 120 deg stated elsewhere
    yaws = sorted(round(math.radians(c.mount.yaw), 3) for c in RIG.perimeter)
    assert yaws == [-2.251, -0.297, 0.297, 2.251]
    assert RIG.carrier.marker_size == 0.04
    assert [c.name for c in RIG.cameras if c.upward] == ["cam4"]
    # under the carrier, a 7 x 7 map of 23.4 mm markers, ids 200-248 (test_marker_map.py)
    assert RIG.carrier.underside_map.ids == range(200, 249)
    assert RIG.carrier.underside_map.marker_size == 0.0234


def test_a_40_mm_side_marker_is_read_within_5_percent_at_0_8_m_and_not_reliably_at_2_5_m():
    study = run_range_study(
        RIG, distances=(0.8, 2.5), bearings=(0.0, 17.0), samples=12, seed=1, nuisance=Nuisance()
    )
    near, far = study.detected[0], study.detected[1]
    assert near.all()
    assert np.nanmax(np.abs(study.error[0])) < 0.05
    assert far.mean() < 0.5


def test_the_cli_renders_and_detects_with_the_dots_camera(capsys, tmp_path):
    image = tmp_path / "dots.png"
    argv = ["aruco", "render", "--camera", "dots", "--marker", "7", "--distance", "0.8"]
    with pytest.raises(SystemExit) as exited:
        main([*argv, "--bearing", "17", "--noise", "2", "--seed", "2", "--out", str(image)])
    out, err = capsys.readouterr()
    assert (exited.value.code or 0, err) == (0, ""), err
    assert "(camera cam0, 640x480; marker 7" in out
    with pytest.raises(SystemExit) as exited:
        main(["aruco", "detect", str(image), "--camera", "dots", "--json"])
    report = json.loads(capsys.readouterr().out)
    (carrier,) = report["carriers"]
    assert carrier["id"] == 7
    assert carrier["distance"] == pytest.approx(0.8, rel=0.05)
