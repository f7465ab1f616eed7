"""Pick-and-place cycles: task-space trajectories, actuator curves and forces, LCI and link clearance along them.

Modules: ``config`` (the ``cycle:`` config section), ``trajectory`` (paths and motion laws), ``clearance``
(capsule distances), ``analysis`` (the cycle of one design: ``analyse``; catalogue metrics: ``metrics``).
"""
