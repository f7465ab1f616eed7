"""Rigid-body dynamics of the cycle: the mass model of the links (``bodies``), inverse dynamics by virtual work
(``inverse``), motors and gears with the shortest cycle time (``motors``) and the time-optimal motion (``optimal``).
The model and its idealisations: docs/cycles.md."""
