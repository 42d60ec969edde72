"""Bearing profiles of the camera's reach (``camera.bearing``), from the range study."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from swarmtag.errors import ConfigError
from swarmtag.sim.config.bearing import BEARING_PROFILES, bearing_profile, profile_from_study

STUDY = Path(__file__).parents[3] / "docs" / "perception" / "dots" / "range.json"


def test_the_dots_profile_is_the_dots_range_study_reduced():
    study = json.loads(STUDY.read_text())
    derived = profile_from_study(study["distances"], study["bearings"], study["detection_rate"])
    assert tuple((b, round(f, 3)) for b, f in derived) == BEARING_PROFILES["dots"]
    factors = dict(BEARING_PROFILES["dots"])
    # the blind wedge between the front and side cameras, short behind
    assert factors[73.0] < 0.05
    assert factors[180.0] < 0.3
    assert factors[0.0] == 1.0


def test_a_linear_ramp_has_its_centre_as_equivalent_range():
    # a ramp centred on 1.5 m, 1 m wide, straight ahead; the same ramp at half the range behind
    distances = np.arange(0.25, 3.01, 0.25)
    ahead = np.clip((2.0 - distances) / 1.0, 0.0, 1.0)
    behind = np.clip((1.0 - distances) / 0.5, 0.0, 1.0)
    profile = profile_from_study(distances, [0.0, 180.0], np.stack([ahead, behind], axis=1))
    assert np.ravel(profile).tolist() == pytest.approx([0.0, 1.0, 180.0, 0.5])


def test_studies_that_cannot_make_a_profile_are_refused():
    with pytest.raises(ConfigError, match="rise from 0 to 180"):
        profile_from_study([0.5, 1.0], [0.0, 90.0], [[1.0, 1.0], [0.5, 0.5]])
    with pytest.raises(ConfigError, match="shape"):
        profile_from_study([0.5, 1.0], [0.0, 180.0], [[1.0, 1.0]])
    with pytest.raises(ConfigError, match="nothing is detected"):
        profile_from_study([0.5, 1.0], [0.0, 180.0], [[0.0, 1.0], [0.0, 1.0]])


def test_kernel_forms_fall_from_one_to_minus_one():
    cosines, factors = bearing_profile("dots")
    assert cosines[0] == 1.0
    assert cosines[-1] == -1.0
    assert np.all(np.diff(cosines) < 0)
    assert factors.size == cosines.size
    assert bearing_profile("uniform")[0].size == 0
