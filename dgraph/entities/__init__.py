"""Entity families. Each subpackage is one family; importing it registers its types.

* :mod:`~dgraph.entities.operators` -- Constant, Add, Gain, Selector, Switch, Saturation
* :mod:`~dgraph.entities.references` -- Sinusoid
* :mod:`~dgraph.entities.discrete` -- Delay, Integrator (discrete-time state)
* :mod:`~dgraph.entities.devices` -- KinematicDevice
* :mod:`~dgraph.entities.recording` -- Recorder (numpy columns + Rerun)
"""
