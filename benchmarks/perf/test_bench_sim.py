"""Simulation throughput: direction-trials per second, rollout over threads vs a serial mj_step loop.

Both benchmarks run the same 16 ramped trials from the same settled pinch grasp, so their
medians compare directly (``python -m ogcp.benchmarks.studies.sim_study`` prints the ratio on a real grasp).
"""

from __future__ import annotations

import numpy as np
import pytest
import trimesh

from ogcp.sim_eval.protocols.directions import direction_set
from ogcp.sim_eval.protocols.phases import ramp_trials, serial_trials, settle
from ogcp.sim_eval.scene.body import object_inertia
from ogcp.sim_eval.scene.grasp_scene import build_scene
from ogcp.sim_eval.settings import SimSettings


@pytest.fixture(scope="module")
def trials():
    box = trimesh.creation.box([0.1, 0.08, 0.06])
    settings = SimSettings()
    com, inertia = object_inertia(box, settings.body_mass)
    positions = np.array([[0.05, 0.0, 0.0], [-0.05, 0.0, 0.0], [0.0, 0.0, 0.03]])
    normals = np.array([[-1.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, -1.0]])
    scene = build_scene([(box.vertices, box.faces)], com, inertia, positions, normals, settings, 0.5, 0.008)
    settled = settle(scene, settings)
    directions = direction_set(4, 0).vectors[:16]
    rates = np.full(len(directions), 5.0 / settings.ramp_time)
    return scene, settled, directions, rates, settings


def test_rollout_trials(benchmark, trials):
    scene, settled, directions, rates, settings = trials
    result = benchmark.pedantic(
        ramp_trials, args=(scene, settled, directions, rates, 6.0, 0.1, settings), rounds=1, iterations=1
    )
    assert len(result.failure_load) == len(directions)


def test_serial_trials(benchmark, trials):
    scene, settled, directions, rates, settings = trials
    result = benchmark.pedantic(
        serial_trials, args=(scene, settled, directions, rates, 6.0, 0.1, settings), rounds=1, iterations=1
    )
    assert len(result.failure_load) == len(directions)
