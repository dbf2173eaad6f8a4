"""Contact models in suites: sweeps like mu, hard cells keep their ids, soft cells plan and simulate soft."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from ogcp.benchmarks.plots.data import load_run
from ogcp.benchmarks.plots.facets import facet_names, faceted
from ogcp.benchmarks.suite.parse import parse_suite
from ogcp.benchmarks.suite.runner import SuiteRunner
from ogcp.benchmarks.suite.store import RESULTS
from ogcp.planner.infra import OgcpError

SUITE = """schema_version = 1
objects = ["box"]
contacts = 16
m = 2
tip_radius = 0
{extra}

[[methods]]
method = "astar"
label = "A*"
"""


def _cells(extra: str):
    return parse_suite(SUITE.format(extra=extra)).cells


def test_hard_cells_keep_their_ids_and_params():
    plain, hard = _cells(""), _cells('contact_model = "hard"')
    assert [c.id for c in plain] == [c.id for c in hard]
    assert "torsional_friction" not in plain[0].params() and "contact_model" not in plain[0].params()


def test_models_and_coefficients_sweep_like_mu():
    cells = _cells('contact_model = ["hard", "soft"]\ntorsional_friction = [0.01, 0.02]')
    assert [c.torsional_friction for c in cells] == [0.0, 0.01, 0.02] and len({c.id for c in cells}) == 3
    assert cells[1].params()["contact_model"] == "soft" and cells[1].params()["torsional_friction"] == 0.01
    assert [c.torsional_friction for c in _cells("torsional_friction = 0.005")] == [0.005]
    assert [c.torsional_friction for c in _cells('contact_model = "soft"')] == [0.02]
    assert [c.torsional_friction for c in _cells('contact_model = ["soft", "hard"]')] == [0.02, 0.0]


@pytest.mark.parametrize(
    "extra,message",
    [
        ('contact_model = "hard"\ntorsional_friction = 0.01', "needs the soft contact model"),
        ('contact_model = "soft"\ntorsional_friction = 0', r"torsional_friction: soft fingers need"),
        ('contact_model = "gel"', "contact_model"),
        ("torsional_friction = [0.01, 0.01]", "repeated values"),
    ],
)
def test_bad_models_name_the_key(extra, message):
    with pytest.raises(OgcpError, match=message):
        _cells(extra)


def test_a_model_sweep_runs_plots_and_selects(tmp_path: Path):
    suite = parse_suite(SUITE.format(extra='contact_model = ["hard", "soft"]'))
    out = tmp_path / "out"
    assert SuiteRunner(suite, out, only=("contact_model=soft",)).run().ran == 1
    assert SuiteRunner(suite, out, resume=True).run().ran == 1
    records = [json.loads(line) for line in (out / RESULTS).read_text().splitlines()]
    by_model = {r["params"].get("contact_model", "hard"): r for r in records}
    assert by_model["hard"]["plan"]["q1"] == 0.0 < by_model["soft"]["plan"]["q1"]  # m = 2: only soft closes
    assert by_model["soft"]["plan"]["contact_set"]["torsional_friction"] == 0.02
    run = load_run(out)
    assert faceted(run)
    assert sorted(facet_names(run).values()) == ["box, mu = 0.5, hard", "box, mu = 0.5, soft 0.02 m"]
