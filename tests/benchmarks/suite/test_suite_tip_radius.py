"""A suite's ``tip_radius``: the fingertip its contacts are kept for, in cell ids, params and contact sets."""

from __future__ import annotations

import pytest

from ogcp.benchmarks.suite.cells import contact_set
from ogcp.benchmarks.suite.parse import load_suite, parse_suite
from ogcp.planner import builtin_mesh
from ogcp.planner.grasp.reach import default_tip_radius
from ogcp.planner.infra import OgcpError

BASE = """schema_version = 1
objects = ["box", "amphora"]
contacts = 30
{extra}
[[methods]]
method = "astar"
label = "A*"
position_weight = 1.0
kmeans_iterations = 10
"""
#: The ids of BASE's two cells before contacts knew the fingertip (plain sampling), when the
#: searches' Γ^fc defaulted to position weight 1 and 10 k-means iterations.
PLAIN_IDS = ["1956639be7f7aa3c", "b779e027cc36bec3"]


def _suite(extra: str = ""):
    return parse_suite(BASE.format(extra=extra))


def test_plain_sampling_cells_keep_their_ids_and_params():
    cells = _suite("tip_radius = 0").cells
    assert [c.id for c in cells] == PLAIN_IDS
    assert all(c.tip_radius == 0 and "tip_radius" not in c.canonical() for c in cells)
    assert all("tip_radius" not in c.params() for c in cells)


def test_reach_aware_cells_get_new_ids():
    default, given, plain = _suite().cells, _suite("tip_radius = 0.004").cells, _suite("tip_radius = 0").cells
    assert [c.tip_radius for c in default] == [None, None]
    assert default[0].canonical()["tip_radius"] == "default" and default[0].params()["tip_radius"] == "default"
    assert given[0].canonical()["tip_radius"] == 0.004 and given[0].params()["tip_radius"] == 0.004
    ids = [c.id for cells in (default, given, plain) for c in cells]
    assert len(set(ids)) == 6 and not set(ids[:4]) & set(PLAIN_IDS)


def test_tip_radius_is_swept_like_mu_and_set_per_group():
    cells = _suite("tip_radius = [0, 0.004, 0.006]").cells
    assert sorted((c.object.spec, c.tip_radius) for c in cells) == [
        (obj, tip) for obj in ("amphora", "box") for tip in (0.0, 0.004, 0.006)
    ]
    grouped = parse_suite(
        "schema_version = 1\ncontacts = 30\ntip_radius = 0\n"
        "[[group]]\nname = 'plain'\nobjects = ['box']\n[[group.methods]]\nmethod = 'astar'\n"
        "[[group]]\nname = 'tip'\nobjects = ['box']\ntip_radius = 0.005\n[[group.methods]]\nmethod = 'astar'\n"
    )
    assert sorted((c.groups, c.tip_radius) for c in grouped.cells) == [(("plain",), 0.0), (("tip",), 0.005)]


def test_the_simulation_tip_is_the_default_of_an_absent_key():
    table = "[simulation]\ntip_radius = 0.006"
    absent = parse_suite(BASE.format(extra="") + table).cells
    plain = parse_suite(BASE.format(extra="tip_radius = 0") + table).cells
    assert [c.tip_radius for c in absent] == [0.006, 0.006] and [c.tip_radius for c in plain] == [0.0, 0.0]


@pytest.mark.parametrize(
    "extra, message",
    [
        ("tip_radius = -0.01", "tip_radius: expected a number >= 0"),
        ("tip_radius = 'big'", "tip_radius: expected a number >= 0"),
        ("tip_radius = []", "tip_radius: empty list"),
        ("tip_radius = [0.01, 0.01]", "repeated values"),
    ],
)
def test_bad_tip_radii_name_the_key_and_the_valid_values(extra, message):
    with pytest.raises(OgcpError, match=message):
        _suite(extra)


def test_cells_sample_for_their_tip_and_cache_per_tip():
    cells = {c.tip_radius: c for c in _suite("tip_radius = [0, 0.004]").cells if c.object.spec == "amphora"}
    (default,) = [c for c in _suite().cells if c.object.spec == "amphora"]
    plain, given = contact_set(cells[0.0]), contact_set(cells[0.004])
    assert "tip_radius" not in plain.source and given.source["tip_radius"] == 0.004
    # Same object, n and seed: a cache keyed without the tip would hand back the plain set here.
    assert contact_set(default).source["tip_radius"] == default_tip_radius(builtin_mesh("amphora"))


def test_the_paper_suite_keeps_plain_sampling_and_the_others_the_default_tip():
    assert {c.tip_radius for c in load_suite("paper").cells} == {0.0}
    assert {c.tip_radius for name in ("quick", "sdh") for c in load_suite(name).cells} == {None}
