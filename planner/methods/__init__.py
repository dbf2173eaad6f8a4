"""The planning methods behind one interface: configurations, runners and the registry by name.

* :mod:`planner.methods.options`: :class:`~planner.methods.options.Option`, the declaration of
  one parameter (default, type, range, help), and the validated configuration base class.
* :mod:`planner.methods.configs`: one frozen configuration dataclass per method; every
  default is written there once.
* :mod:`planner.methods.runners`: run a configuration on a contact set and return the
  result with its complete ``ogcp.plan/1`` record.
* :mod:`planner.methods.registry`: method name -> title, configuration class and runner.

This package imports nothing at its own import: the engines import
:mod:`planner.methods.configs` for their defaults, and the registry imports the engines.
"""
