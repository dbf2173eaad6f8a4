"""ogcp physics validation in MuJoCo (measured resistance of planned grasps against Q1).

This package consumes plan results (schema ``ogcp.plan/1``); its modules arrive with the
simulation work. It imports only the planner's value types, never its search.
"""
