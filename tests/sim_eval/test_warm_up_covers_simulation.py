"""The planning warm-up also covers the kernels a simulated grasp's prediction calls."""

from __future__ import annotations

from ogcp.planner import GraspPlanner, builtin_mesh, sample_contacts
from ogcp.planner.methods import warm_up as warm
from ogcp.sim_eval.decomposition import DecompositionSettings
from ogcp.sim_eval.evaluate import GraspEvaluator
from ogcp.sim_eval.settings import SimSettings


def test_evaluating_a_grasp_after_the_warm_up_compiles_nothing() -> None:
    mesh = builtin_mesh("box")
    contacts = sample_contacts(mesh, n=30, seed=2)
    grasp = tuple(GraspPlanner().plan(contacts, 3).grasp)
    warm.warm_up()
    before = warm.compiled_signatures()
    evaluator = GraspEvaluator(SimSettings(directions=4), DecompositionSettings(method="convex_hull"))
    (result,) = evaluator.evaluate(mesh, contacts, [grasp]).grasps
    assert result.error is None
    assert warm.compiled_signatures() == before
