"""The planning methods behind one interface: runners and the registry by name.

* :mod:`planner.methods.runners`: run a method's configuration on a contact set and return
  the result with its complete ``ogcp.plan/1`` record.
* :mod:`planner.methods.registry`: method name -> title, configuration class and runner.

The configurations themselves live one layer down, in :mod:`planner.config`, because the
engines (search, baselines, hands) read their defaults from them and the registry imports
the engines.
"""

from planner.methods.registry import METHODS, MethodSpec, method_spec
from planner.methods.runners import MethodRun, RunOptions

__all__ = ["METHODS", "MethodRun", "MethodSpec", "RunOptions", "method_spec"]
