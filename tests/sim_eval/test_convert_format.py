"""The Dex-Net converter: parallel-jaw configurations closed on the mesh become ``ogcp.grasps/1``.

Cheap: the built-in box, convex-hull decomposition, one thread, no sphere directions.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from ogcp.benchmarks.studies.convert_dexnet import close_jaws, convert, main
from ogcp.planner.infra import OgcpError
from ogcp.planner.objects import resolve_object
from ogcp.planner.records.grasps import load_grasps
from ogcp.sim_eval import evaluate_grasps

SETTINGS = {"directions": 0, "threads": 1}
HULL = {"method": "convex_hull"}
# The built-in box at 0.2 m diagonal: half extents [m].
HALF = np.array([0.07756315, 0.05170877, 0.03619614])


def _configuration(centre: list[float], axis: list[float], width: float, min_width: float = 0.0) -> list[float]:
    """A Dex-Net ``ParallelJawPtGrasp3D`` configuration: centre, axis, width, angle, jaw width, min width."""
    return [*centre, *axis, width, 0.3, 0.005, min_width]


# Across x (off-centre in y and z), across z, and one whose jaws start inside the box (missed).
ROWS = [
    _configuration([0.0, 0.01, 0.005], [1.0, 0.0, 0.0], 0.2),
    _configuration([0.0, 0.0, 0.0], [0.0, 0.0, 1.0], 0.1, 0.01),
    _configuration([0.0, 0.0, 0.0], [0.0, 1.0, 0.0], 0.05),
]


def test_closing_the_jaws_across_the_box_gives_both_faces_with_inward_normals() -> None:
    mesh, _ = resolve_object("box")
    contacts = close_jaws(mesh, np.array(ROWS[0]))
    assert contacts is not None
    positions, normals = contacts
    np.testing.assert_allclose(positions, [[-HALF[0], 0.01, 0.005], [HALF[0], 0.01, 0.005]], atol=1e-7)
    np.testing.assert_allclose(normals, [[1.0, 0.0, 0.0], [-1.0, 0.0, 0.0]], atol=1e-12)
    # The minimum width stops the jaws short of a face that lies beyond their travel.
    assert close_jaws(mesh, np.array(_configuration([0, 0, 0], [0, 0, 1], 0.1, 0.09))) is None
    with pytest.raises(OgcpError, match="not a unit vector"):
        close_jaws(mesh, np.array(_configuration([0, 0, 0], [0, 0, 2], 0.1)))


@pytest.mark.parametrize("suffix", [".npy", ".txt"])
def test_a_file_converts_loads_and_evaluates_with_q1_zero(tmp_path: Path, suffix: str) -> None:
    source = tmp_path / f"dexnet{suffix}"
    # Nine-entry rows (no min width) are read as Dex-Net reads them; the text form is savetxt's.
    rows = np.array([row[:9] for row in ROWS[:2]])
    if suffix == ".npy":
        np.save(source, rows)
    else:
        np.savetxt(source, rows, header="center(3) axis(3) width angle jaw_width")
    out = tmp_path / "grasps.json"
    grasps = convert(source, out, "box", 0.5, method="dexnet")
    loaded = load_grasps(out)
    assert loaded.to_dict() == grasps.to_dict()
    assert [g.label for g in loaded.grasps] == ["grasp-0", "grasp-1"]
    np.testing.assert_allclose(loaded.grasps[1].positions, [[0, 0, -HALF[2]], [0, 0, HALF[2]]], atol=1e-7)
    np.testing.assert_allclose(loaded.grasps[1].normals, [[0, 0, 1], [0, 0, -1]], atol=1e-12)
    result = evaluate_grasps(None, loaded, SETTINGS, HULL)
    external = result.object["external"]
    # Two hard-finger contacts are never in force closure: ogcp's Q1 of a pinch is 0.
    assert [g["q1"] for g in external["grasps"]] == [0.0, 0.0]
    assert external["n_projected"] == 0
    assert len(result.grasps) == 2


def test_missed_grasps_are_refused_or_skipped_and_units_scale(tmp_path: Path) -> None:
    source = tmp_path / "dexnet.npy"
    np.save(source, np.array(ROWS))
    with pytest.raises(OgcpError, match=r"1 grasp\(s\) whose jaws meet no surface \(first: row 2\)"):
        convert(source, tmp_path / "out.json", "box", 0.5)
    assert not (tmp_path / "out.json").exists()
    grasps = convert(source, tmp_path / "out.json", "box", 0.5, skip_missed=True)
    assert [g.label for g in grasps.grasps] == ["grasp-0", "grasp-1"]
    # Millimetres: the same grasp, centre and widths scaled, the axis not.
    mm = np.array(ROWS[:1])
    mm[:, [0, 1, 2, 6, 8, 9]] *= 1000.0
    np.save(source, mm)
    scaled = convert(source, tmp_path / "mm.json", "box", 0.5, units="mm")
    np.testing.assert_allclose(scaled.grasps[0].positions, grasps.grasps[0].positions, atol=1e-9)


def test_bad_files_are_one_line_errors_and_the_cli_writes(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    bad = tmp_path / "bad.npy"
    np.save(bad, np.zeros((2, 6)))
    with pytest.raises(OgcpError, match=r"shape \(G, 10\) or \(G, 9\), got \(2, 6\)"):
        convert(bad, tmp_path / "x.json", "box", 0.5)
    source = tmp_path / "dexnet.npy"
    np.save(source, np.array(ROWS[:1]))
    out = tmp_path / "cli.json"
    assert main([str(source), "-o", str(out), "--mesh", "box", "--mu", "0.4"]) == 0
    assert "1 grasp(s) on box, mu 0.4" in capsys.readouterr().out
    assert load_grasps(out).method == "dexnet"
    assert main([str(bad), "-o", str(out), "--mesh", "box", "--mu", "0.4"]) == 2
    assert "convert_dexnet: error:" in capsys.readouterr().err


def test_parallel_jaw_grasps_as_soft_fingers_can_close(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    # A parallel jaw is two contacts: only soft fingers (torsional friction) can put it in force closure.
    source = tmp_path / "dexnet.npy"
    np.save(source, np.array(ROWS[:2]))
    out = tmp_path / "soft.json"
    args = [str(source), "-o", str(out), "--mesh", "box", "--mu", "0.5", "--contact-model", "soft"]
    assert main(args) == 0
    soft = load_grasps(out)
    assert soft.torsional_friction == 0.02
    result = evaluate_grasps(None, soft, SETTINGS, HULL)
    assert all(g["q1"] > 0 for g in result.object["external"]["grasps"])
    assert result.settings["contact_model"]["simulated"] == "soft"
    capsys.readouterr()
    assert main([*args[:-1], "gel", "-o", str(tmp_path / "x.json")]) == 2
    assert "contact_model 'gel'; valid choices: hard, soft" in capsys.readouterr().err
    assert not (tmp_path / "x.json").exists()
