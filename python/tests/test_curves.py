"""The section-6 curve representations from Python: facial curves, iso-curvature curves and
the elastic curve distance."""

import numpy as np
import pytest

import bipolar
from bipolar import errors

from conftest import rotation


def ellipsoid(axes, r=None, t=(0.0, 0.0, 0.0), reverse=False):
    """Icosphere (level 4) scaled by ``axes``, rotated by ``r``, translated by ``t``; vertices
    listed in reverse order when ``reverse``. Returns the mesh and its top (+z) vertex."""
    s = bipolar.icosphere(4)
    v = s.vertices * np.asarray(axes)
    top = int(np.argmax(v[:, 2]))
    if r is not None:
        v = v @ r.T
    v = v + np.asarray(t)
    tri = s.triangles.astype(np.int64)
    if reverse:
        n = len(v)
        v = v[::-1].copy()
        tri = n - 1 - tri
        top = n - 1 - top
    return bipolar.Mesh(v, tri), top


def test_facial_curves_are_invariant_and_discriminate():
    a, ta = ellipsoid((3.0, 2.0, 1.5))
    b, tb = ellipsoid((3.0, 2.0, 1.5), rotation(4), (1.0, -2.0, 5.0), reverse=True)
    c, tc = ellipsoid((2.2, 2.0, 1.5))
    fa = bipolar.facial_curves(a, ta, radius=1.8, levels=6)
    fb = bipolar.facial_curves(b, tb, radius=1.8, levels=6)
    fc = bipolar.facial_curves(c, tc, radius=1.8, levels=6)
    assert len(fa) == 6 and fa.n_levels == 6 and abs(fa.step - 0.3) < 1e-12
    curve = fa.curves[2]
    assert curve["level"] == 3 and curve["closed"] and curve["points"].shape[1] == 3
    same = bipolar.facial_curves_distance(fa, fb)
    other = bipolar.facial_curves_distance(fa, fc)
    assert same < 0.1 * other
    assert bipolar.facial_curves_distance(fa, fc, aggregate="sum") >= other
    with pytest.raises(errors.InputError, match="curve aggregate"):
        bipolar.facial_curves_distance(fa, fc, aggregate="max")


def test_iso_curvature_curves_are_invariant_and_discriminate():
    a, _ = ellipsoid((3.0, 2.0, 1.5))
    b, _ = ellipsoid((3.0, 2.0, 1.5), rotation(7), (4.0, 0.0, -1.0), reverse=True)
    c, _ = ellipsoid((2.2, 2.0, 1.5))
    kw = dict(k1_levels=[0.6, 0.9], k2_levels=[0.3, 0.45])
    ia, ib, ic = (bipolar.iso_curvature_curves(m, **kw) for m in (a, b, c))
    assert ia.levels_k1 == [0.6, 0.9] and len(ia) == len(ib) > 0
    assert {c["field"] for c in ia.curves} == {"k1", "k2"}
    assert ia.k1.shape == (len(a.vertices),) and np.all(ia.k1 >= ia.k2)
    assert bipolar.iso_curvature_distance(ia, ib) < 1e-6
    assert bipolar.iso_curvature_distance(ia, ic) > 1e-3
    with pytest.raises(errors.NoDescriptorPointsError):
        bipolar.iso_curvature_curves(a, k1_levels=[10.0], k2_levels=[10.0])


def test_elastic_distance_of_curves():
    t = np.linspace(0, 1, 300, endpoint=False)
    loop = np.stack([np.cos(2 * np.pi * t) * (1 + 0.3 * np.cos(6 * np.pi * t)),
                     np.sin(2 * np.pi * t) * (1 + 0.3 * np.cos(6 * np.pi * t)),
                     0.4 * np.sin(4 * np.pi * t)], axis=1)
    moved = np.roll(loop, 77, axis=0) @ rotation(2).T + 3.0
    d = bipolar.elastic_distance(loop, moved, a_closed=True, b_closed=True)
    assert d < 0.05
    ellipse = np.stack([1.5 * np.cos(2 * np.pi * t), 0.6 * np.sin(2 * np.pi * t), 0 * t], axis=1)
    assert bipolar.elastic_distance(loop, ellipse, a_closed=True, b_closed=True) > 0.1
    with pytest.raises(errors.InputError, match="second curve has 2 points"):
        bipolar.elastic_distance(loop, ellipse[:2], a_closed=True, b_closed=True)
