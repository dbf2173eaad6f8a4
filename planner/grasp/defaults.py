"""Defaults of the contact sampling, in a module that imports nothing.

They are read where loading numpy, trimesh and the Q1 kernels would be wasted: the command
line's ``--help`` and the simulation's settings. :mod:`planner.grasp.contact_set` and
:mod:`planner.grasp.reach` take them from here, so each value is written once.
"""

#: Friction coefficient mu of a contact set when none is given.
DEFAULT_MU = 0.5
#: Friction-cone edges k of a contact set when none is given.
DEFAULT_CONE_EDGES = 8
#: Contacts sampled from a mesh when no count is given.
DEFAULT_CONTACTS = 100
#: Default fingertip radius as a fraction of the object's bounding-box diagonal: the one
#: default of both the contact sampling and the simulation, so that a plan made with the
#: defaults only holds contacts the simulated fingertip can touch.
DEFAULT_TIP_RADIUS_RATIO = 0.04
