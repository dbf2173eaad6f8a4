"""ogcp physics validation in MuJoCo: measured resistance of planned grasps against Q1.

Each grasp is simulated with fingertip spheres at its contacts on a CoACD-decomposed object;
disturbance wrenches are ramped along many directions until the object moves, and the
measured resistance is compared with Q1 and with the analytic limit of the same actuation
model. The package consumes plan results (schema ``ogcp.plan/1``) and the planner's value
types; it never runs a search and never imports matplotlib.
"""

from sim_eval.decomposition.decompose import Decomposition, DecompositionSettings
from sim_eval.evaluate import GraspEvaluator, evaluate_plan
from sim_eval.result import SIM_SCHEMA, GraspSimResult, SimGraspRecord, SimRecord, SimResult
from sim_eval.settings import SimSettings

__all__ = [
    "SIM_SCHEMA",
    "Decomposition",
    "DecompositionSettings",
    "GraspEvaluator",
    "GraspSimResult",
    "SimGraspRecord",
    "SimRecord",
    "SimResult",
    "SimSettings",
    "evaluate_plan",
]
