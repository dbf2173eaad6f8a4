"""The simulated scene and its bodies: the object's mass properties and collision surface, and the fingertip grasp model.

:mod:`~ogcp.sim_eval.scene.body` (mass properties of the watertight mesh), :mod:`~ogcp.sim_eval.scene.collision`
(distances to the convex parts, where tips start) and :mod:`~ogcp.sim_eval.scene.grasp_scene` (the MuJoCo model
of an object held by fingertip servos, and the options every scene shares).
"""
