"""Face matching from Python (enroll, Template, Gallery.identify, verify, bipolar.dask), on
virtual range scans of the paper-set faces."""

import pickle

import numpy as np
import pytest

import bipolar
from bipolar import errors

from conftest import ROOT, paper_face

FIXTURE = ROOT / "fixtures" / "facematch" / "small.bpt"
GALLERY_FACES = ["id1_neutral", "id2_neutral", "id3_neutral"]


def same(a, b):
    """Equal, NaN included: float reprs round-trip exactly."""
    assert repr(a) == repr(b)


@pytest.fixture(scope="module")
def scans():
    # paper_face skips (or fails, with BIPOLAR_REQUIRE_SHARED) when a face is absent.
    names = GALLERY_FACES + ["id1_happiness"]
    paths = {n: paper_face(f"{n}.obj") for n in names}
    return {n: bipolar.scan(p)[0] for n, p in paths.items()}


@pytest.fixture(scope="module")
def scan_files(scans, tmp_path_factory):
    d = tmp_path_factory.mktemp("scans")
    paths = []
    for n in GALLERY_FACES:
        p = d / f"{n}.ply"
        bipolar.write_mesh(p, scans[n])
        paths.append(p)
    return paths


@pytest.fixture(scope="module")
def gallery(scan_files):
    # Files, identities from the file names, enrolled in parallel.
    return bipolar.enroll(scan_files, identity_from=r"(id\d+)_")


@pytest.fixture(scope="module")
def probe(scans):
    # An in-memory scan of another expression of id1, with the reference-point search.
    return bipolar.Template.from_scan(scans["id1_happiness"], "id1", probe=True)


@pytest.fixture(scope="module")
def ball():
    s = bipolar.icosphere(4)
    return bipolar.Mesh(s.vertices * 80.0, s.triangles)  # face-sized, mm


def test_the_format_fixture_reads_back_bit_identically(tmp_path):
    data = FIXTURE.read_bytes()
    t = bipolar.Template.read(FIXTURE)
    assert t.to_bytes() == data
    assert (t.identity, t.source, t.pair) == ("id07", "id07-e0.bnt", "left-nose")
    assert t.notes == ["no scanner direction given: +z taken"]
    assert t.searched and t.view_yaws == [15.0, -15.0]
    assert bipolar.Template.from_bytes(data).to_bytes() == data
    assert pickle.loads(pickle.dumps(t)).to_bytes() == data
    t.write(tmp_path / "copy.bpt")
    assert (tmp_path / "copy.bpt").read_bytes() == data


def test_malformed_template_bytes_are_a_format_error():
    data = FIXTURE.read_bytes()
    with pytest.raises(errors.FileFormatError, match="truncated"):
        bipolar.Template.from_bytes(data[:-3])
    with pytest.raises(errors.FileFormatError, match="not a template"):
        bipolar.Template.from_bytes(b"hello", "x.bpt")
    with pytest.raises(errors.FileError):
        bipolar.Template.read(ROOT / "no-such-file.bpt")


def test_a_template_of_other_settings_is_refused_naming_both():
    t = bipolar.Template.read(FIXTURE)  # made with "method=exact levels=10" only
    with pytest.raises(errors.TemplateSettingsError) as e:
        bipolar.Gallery([t])
    msg = str(e.value)
    assert "template: method=exact levels=10\n" in msg
    assert "expected: method=exact levels=10 cutoff=" in msg
    assert isinstance(e.value, errors.InputError)


def test_a_gallery_folder_with_other_settings_or_none_is_refused(tmp_path):
    with pytest.raises(errors.InputError, match="no templates"):
        bipolar.Gallery.open(tmp_path)
    with pytest.raises(errors.InputError, match="at least one template"):
        bipolar.Gallery([])
    (tmp_path / "a.bpt").write_bytes(FIXTURE.read_bytes())
    with pytest.raises(errors.TemplateSettingsError, match="a.bpt"):
        bipolar.Gallery.open(tmp_path)


def test_a_sphere_has_no_face(ball):
    with pytest.raises(errors.LandmarksNotFoundError, match="no face found"):
        bipolar.enroll([ball], ["ball"])
    with pytest.raises(errors.LandmarksNotFoundError, match="^ball: no face found"):
        bipolar.Template.from_scan(ball, "ball", probe=True)
    with pytest.warns(RuntimeWarning, match="not enrolled: ball: no face found"):
        with pytest.raises(errors.InputError, match="no scan could be enrolled"):
            bipolar.enroll([ball], ["ball"], skip_failed=True)


def test_bad_enrolment_arguments_are_input_errors(ball, tmp_path):
    with pytest.raises(errors.InputError, match="identities"):
        bipolar.enroll([ball])
    with pytest.raises(errors.InputError, match="2 identities for 1 scans"):
        bipolar.enroll([ball], ["a", "b"])
    with pytest.raises(errors.InputError, match="no match in x.ply"):
        bipolar.enroll([tmp_path / "x.ply"], identity_from=r"id(\d+)")
    with pytest.raises(errors.InputTypeError):
        bipolar.enroll([42], ["a"])
    with pytest.raises(errors.FileError, match="x.ply"):
        bipolar.enroll([tmp_path / "x.ply"])


def test_enrolment_names_identities_and_sources(gallery):
    assert len(gallery) == 3
    assert gallery.identities == ["id1", "id2", "id3"]
    t = gallery.templates
    assert [x.source for x in t] == [f"{n}.ply" for n in GALLERY_FACES]
    # A mesh file has no scanner direction: +z is taken and said.
    assert all(any("scanner direction" in n for n in x.notes) for x in t)
    assert not any(x.searched for x in t)
    assert all(len(x.view_yaws) == 8 for x in t)


def test_identify_ranks_the_probes_identity_first(gallery, probe):
    assert probe.searched and probe.notes == []
    ranking = gallery.identify(probe)
    assert [r["identity"] for r in ranking][0] == "id1"
    assert sorted(r["identity"] for r in ranking) == ["id1", "id2", "id3"]
    scores = [r["score"] for r in ranking]
    assert all(np.isfinite(scores)) and scores == sorted(scores)
    best = ranking[0]
    assert best["template"] == "id1_neutral.ply"
    c = best["comparison"]
    assert c["scored_by"] in ("corners", "right-nose", "left-nose")
    assert min(p["distance"] for p in c["pairs"]) == best["score"]
    assert c["view"]["kind"] in ("own", "matched")
    assert c["fallbacks"] == [] and best["notes"] == []
    assert all(p["moved"] > 0 for p in c["pairs"])
    same(gallery.identify(probe, top=1), ranking[:1])


def test_a_scan_probe_ranks_as_its_template(gallery, probe, scans):
    same(gallery.identify(scans["id1_happiness"]), gallery.identify(probe))


def test_a_gallery_template_as_probe_gets_a_note(gallery):
    r = gallery.identify(gallery.templates[1])
    assert r[0]["identity"] == "id2" and r[0]["score"] < 1e-12
    assert "the probe is a template without the reference-point search" in r[0]["notes"]


def test_verify_as_the_cli(gallery, probe, scans):
    ranking = {r["identity"]: r for r in gallery.identify(probe)}
    v = bipolar.verify(probe, gallery.templates[0])
    assert v["score"] == ranking["id1"]["score"]
    assert v["threshold"] == bipolar.VERIFY_THRESHOLD
    assert v["same"] == (v["score"] <= v["threshold"])
    same(v["comparison"], ranking["id1"]["comparison"])
    v2 = bipolar.verify(probe, gallery.templates[2])
    assert v2["score"] > v["score"] and not v2["same"]
    # The second side a scan: enrolled without the search.
    v3 = bipolar.verify(probe, scans["id1_neutral"])
    assert np.isfinite(v3["score"]) and v3["score"] < v2["score"]


def test_templates_and_galleries_round_trip_through_files(gallery, probe, tmp_path):
    folder = tmp_path / "folder"
    folder.mkdir()
    for t in gallery.templates + [probe]:
        b = t.to_bytes()
        assert bipolar.Template.from_bytes(b).to_bytes() == b
        p = (tmp_path if t is probe else folder) / f"{t.source}.bpt"
        t.write(p)
        assert bipolar.Template.read(p).to_bytes() == b
    gallery.write(tmp_path / "g.bpg")
    assert (tmp_path / "g.bpg").read_bytes() == gallery.to_bytes()
    for opened in (bipolar.Gallery.open(tmp_path / "g.bpg"), bipolar.Gallery.open(folder)):
        assert opened.to_bytes() == gallery.to_bytes()
    assert pickle.loads(pickle.dumps(gallery)).to_bytes() == gallery.to_bytes()
    # A probe given as a .bpt path is read and used as is.
    same(gallery.identify(tmp_path / f"{probe.source}.bpt"), gallery.identify(probe))


# Dask: the same rankings from shards of templates on a LocalCluster of two worker processes.


@pytest.mark.parametrize("shard_size", [1, 2, None])
def test_dask_identify_templates_equals_one_process(client, gallery, probe, shard_size):
    from bipolar import dask as bdask

    probes = [probe, gallery.templates[2]]
    want = [gallery.identify(p, top=2) for p in probes]
    got = bdask.identify_templates(
        probes, gallery, client=client, shard_size=shard_size, top=2
    )
    assert len(got) == 2 and got[0][0]["identity"] == "id1"
    same(got, want)


def test_dask_identify_templates_takes_a_gallery_file_and_scan_probes(
    client, gallery, probe, ball, tmp_path
):
    from bipolar import dask as bdask

    gallery.write(tmp_path / "g.bpg")
    got = bdask.identify_templates([probe], tmp_path / "g.bpg", client=client)
    same(got, [gallery.identify(probe)])
    # A scan probe is made into a template on a worker; its error comes back as raised there.
    with pytest.raises(errors.LandmarksNotFoundError, match="no face found"):
        bdask.identify_templates([ball], gallery, client=client)
