import json

import numpy as np
import pytest

import bipolar
from bipolar import errors

from conftest import PAPER_SET, paper_face


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


def test_a_range_scan_is_read_as_seen_from_its_scanner(tmp_path):
    face = bipolar.read_mesh(paper_face("id4_neutral.obj"))
    # A head turned by 35 degrees: the scanner loses the far side around the far eye corner.
    scan, _ = bipolar.scan(face, pitch=1.0, yaw=35.0, artifacts="structured-light", seed=7)
    assert scan.grid_index is not None
    # The scan's own mesh is a range grid's: seen from +z by default.
    lm = bipolar.detect_landmarks(scan)
    assert set(lm["landmarks"]) == set(bipolar.LANDMARK_NAMES)
    same = bipolar.detect_landmarks(scan, toward_viewer=[0.0, 0.0, 2.0])
    assert same["landmarks"]["outer_eye_left"]["vertex"] == lm["landmarks"]["outer_eye_left"]["vertex"]
    # The same surface without a grid has no viewpoint: the missing surface is mismatch.
    plain = bipolar.Mesh(scan.vertices, scan.triangles)
    with pytest.raises(errors.LandmarksNotFoundError, match="templates"):
        bipolar.detect_landmarks(plain)
    with pytest.raises(errors.InputError, match="toward_viewer"):
        bipolar.detect_landmarks(plain, toward_viewer=[0.0, 0.0])
    with pytest.raises(errors.InputError, match="toward_viewer"):
        bipolar.detect_landmarks(plain, toward_viewer=[0.0, 0.0, 0.0])


def test_describe_names_the_corners_of_a_turned_scan():
    face = bipolar.read_mesh(paper_face("id4_neutral.obj"))
    scan, _ = bipolar.scan(face, pitch=1.0, yaw=35.0, artifacts="structured-light", seed=7)
    # Named references are detected as detect_landmarks does: the scan is seen from +z.
    d = bipolar.describe(scan, "outer-eye-right", "outer-eye-left", levels=10, max_level=10)
    assert len(d) > 0
    with pytest.raises(errors.LandmarksNotFoundError):
        bipolar.describe(bipolar.Mesh(scan.vertices, scan.triangles), "outer-eye-right", "outer-eye-left")


def test_landmarks_the_scanner_did_not_see_are_reported_unseen():
    face = bipolar.read_mesh(paper_face("id6_neutral.obj"))
    # Turned by 50 degrees: the far inner eye corner hides behind the nose.
    scan, _ = bipolar.scan(face, pitch=1.0, yaw=50.0, artifacts="structured-light", seed=3)
    lm = bipolar.detect_landmarks(scan)
    assert lm["unseen"], lm
    assert set(lm["landmarks"]) | set(lm["unseen"]) == set(bipolar.LANDMARK_NAMES)
    assert not set(lm["landmarks"]) & set(lm["unseen"])
    assert "nose_tip" in lm["landmarks"]
    for why in lm["unseen"].values():
        assert "did not see" in why or "surface" in why, why
    # Describing from an unseen landmark is an error naming it, not a point nearby.
    name = sorted(lm["unseen"])[0]
    with pytest.raises(errors.LandmarksNotFoundError, match=f"{name} is not found"):
        bipolar.describe(scan, name.replace("_", "-"), "nose-tip", levels=10)
    # A frontal face has nothing unseen.
    assert bipolar.detect_landmarks(face)["unseen"] == {}
