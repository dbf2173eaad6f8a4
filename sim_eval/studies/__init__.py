"""Studies of the simulation itself (run from a checkout, not shipped in the wheel).

They live in ``sim_eval`` because they measure MuJoCo directly, which the import contracts allow
only here; ``ogcp.benchmarks.studies`` holds the studies of ogcp's methods.
"""
