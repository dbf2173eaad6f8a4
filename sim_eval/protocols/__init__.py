"""The protocols a grasp meets in simulation, and what they are measured against.

:mod:`~ogcp.sim_eval.protocols.phases` (settling, ramps and holds), :mod:`~ogcp.sim_eval.protocols.gates`
(validity), :mod:`~ogcp.sim_eval.protocols.trial` (one fingertip grasp from start to record),
:mod:`~ogcp.sim_eval.protocols.dexgraspbench` (DexGraspBench's test), :mod:`~ogcp.sim_eval.protocols.directions`
(the disturbance directions), :mod:`~ogcp.sim_eval.protocols.predict` (the analytic resistance of fingertips)
and :mod:`~ogcp.sim_eval.protocols.metrics` (fidelity, correlations, ROC-AUC).
"""
