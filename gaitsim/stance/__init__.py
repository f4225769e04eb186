"""Real feet in stance: measure how a foot IMU's angular rate and velocity co-vary through stance, fit the
simulator's rolling-foot stance model to it, and compare the length underestimate of ZUPT-aided navigation
against the zero-velocity threshold on measured recordings and on their simulated twins (``gaitsim stance``).

Modules: :mod:`.events` (detected stances and gait events from the IMU), :mod:`.sweep` (threshold sweep:
detected windows, in-window site velocity, stance-to-stance length underestimate, bootstrap over strides),
:mod:`.profiles` (stance-phase profiles), :mod:`.twin` (the simulated twin at a recording's gait and rate),
:mod:`.fit` (fit of the stance model), :mod:`.command` (the command and its report).
"""
