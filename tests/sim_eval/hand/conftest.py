"""A plan made with the SDH, planned once for the hand tests that evaluate or draw it."""

from __future__ import annotations

import json
from typing import Any

import pytest

from ogcp.benchmarks.cli import main


@pytest.fixture(scope="package")
def sdh_plan(tmp_path_factory: pytest.TempPathFactory) -> dict[str, Any]:
    """The ``ogcp.plan/1`` record of a 3-contact SDH plan on the box (80 contacts); copy it to change it."""
    folder = tmp_path_factory.mktemp("plan")
    path = folder / "plan.json"
    with pytest.MonkeyPatch.context() as patch:
        patch.setenv("OGCP_CACHE", str(folder / "cache"))
        assert main(["plan", "box", "-n", "80", "-m", "3", "--hand", "sdh", "-o", str(path)]) == 0
    return json.loads(path.read_text())
