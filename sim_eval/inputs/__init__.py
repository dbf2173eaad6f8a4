"""Reading what is simulated: plan records (their mesh, contact set and fields, each checked) and their export as ``ogcp.grasps/1``.

:mod:`~ogcp.sim_eval.inputs.plan_input` rebuilds a plan's mesh and contact set and checks them against the record,
:mod:`~ogcp.sim_eval.inputs.plan_fields` checks the fields it reads, :mod:`~ogcp.sim_eval.inputs.plan_contacts`
finds the mesh file, and :mod:`~ogcp.sim_eval.inputs.external_export` writes a plan's grasps for other tools.
"""
