import json

import numpy as np
import pytest

import bipolar
from bipolar import errors

from conftest import PAPER_SET


def test_detects_the_five_landmarks_on_a_paper_set_face(face, face_path):
    lm = bipolar.detect_landmarks(face)
    assert set(lm["landmarks"]) == set(bipolar.LANDMARK_NAMES)
    assert 0.0 < lm["confidence"] <= 1.0
    m = lm["model_to_mesh"]
    np.testing.assert_allclose(m[:3, :3] @ m[:3, :3].T, np.eye(3), atol=1e-9)
    truth = bipolar.read_ict_landmarks(PAPER_SET / "landmarks.json")[face_path.stem]
    for name, l in lm["landmarks"].items():
        np.testing.assert_array_equal(l["position"], face.vertices[l["vertex"]])
        # The library's own evaluation places these within a few mm (docs/landmarks.md).
        assert np.linalg.norm(l["position"] - truth[name]) < 0.6, name


def test_a_face_in_millimetres_needs_no_scale(face):
    cm = bipolar.detect_landmarks(face)
    mm = bipolar.detect_landmarks(bipolar.Mesh(face.vertices * 10.0, face.triangles))
    for name in bipolar.LANDMARK_NAMES:
        d = np.linalg.norm(mm["landmarks"][name]["position"] / 10.0 - cm["landmarks"][name]["position"])
        assert d < 0.35, name


def test_a_sphere_is_not_a_face():
    with pytest.raises(errors.LandmarksNotFoundError, match="landmarks not found"):
        bipolar.detect_landmarks(bipolar.icosphere(4), scale=1.0)
    # Without a scale the units come from the size: a unit sphere is no face in any unit.
    with pytest.raises(errors.LandmarksNotFoundError, match="cannot detect units"):
        bipolar.detect_landmarks(bipolar.icosphere(4))
    with pytest.raises(errors.InputError, match="mesh_units_per_model_unit"):
        bipolar.detect_landmarks(bipolar.icosphere(2), scale=-1.0)
    with pytest.raises(errors.FileError):
        bipolar.detect_landmarks(bipolar.icosphere(2), model="/nonexistent.json")
