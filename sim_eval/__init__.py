"""ogcp physics validation in MuJoCo: measured resistance of planned grasps against Q1.

Each grasp is simulated with fingertip spheres at its contacts on a CoACD-decomposed object;
disturbance wrenches are ramped along many directions until the object moves, and the
measured resistance is compared with Q1 and with the analytic limit of the same actuation
model. The package consumes plan results (schema ``ogcp.plan/1``), grasps from any planner
(schema ``ogcp.grasps/1``, :func:`evaluate_grasps`) and the planner's value types; it never
runs a search and never imports matplotlib.

The names below load their modules on first use, so that reading a setting or a result
record (``ogcp.sim_eval.settings``, ``ogcp.sim_eval.result``) never pays for importing MuJoCo.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from ogcp.planner.infra.lazy import lazy_exports

if TYPE_CHECKING:
    from ogcp.planner.records.grasps import ExternalGrasps, load_grasps
    from ogcp.sim_eval.decomposition import Decomposition, DecompositionSettings
    from ogcp.sim_eval.evaluate import GraspEvaluator, evaluate_plan
    from ogcp.sim_eval.external import evaluate_grasps
    from ogcp.sim_eval.inputs.external_export import export_grasps
    from ogcp.sim_eval.result import SIM_SCHEMA, GraspSimResult, SimGraspRecord, SimRecord, SimResult
    from ogcp.sim_eval.settings import SimSettings

#: Public name -> the module that defines it.
_EXPORTS = {
    "SIM_SCHEMA": "ogcp.sim_eval.result",
    "Decomposition": "ogcp.sim_eval.decomposition",
    "DecompositionSettings": "ogcp.sim_eval.decomposition",
    "ExternalGrasps": "ogcp.planner.records.grasps",
    "GraspEvaluator": "ogcp.sim_eval.evaluate",
    "GraspSimResult": "ogcp.sim_eval.result",
    "SimGraspRecord": "ogcp.sim_eval.result",
    "SimRecord": "ogcp.sim_eval.result",
    "SimResult": "ogcp.sim_eval.result",
    "SimSettings": "ogcp.sim_eval.settings",
    "evaluate_grasps": "ogcp.sim_eval.external",
    "evaluate_plan": "ogcp.sim_eval.evaluate",
    "export_grasps": "ogcp.sim_eval.inputs.external_export",
    "load_grasps": "ogcp.planner.records.grasps",
}

__all__ = [
    "SIM_SCHEMA",
    "Decomposition",
    "DecompositionSettings",
    "ExternalGrasps",
    "GraspEvaluator",
    "GraspSimResult",
    "SimGraspRecord",
    "SimRecord",
    "SimResult",
    "SimSettings",
    "evaluate_grasps",
    "evaluate_plan",
    "export_grasps",
    "load_grasps",
]


__getattr__, __dir__ = lazy_exports(__name__, _EXPORTS)
