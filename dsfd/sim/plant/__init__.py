"""The stratified "truth" plant: the façade the controller is tested against in simulation.

A finer, physically richer model than the controller's lumped one (N stacked cavity
segments, slat-resolved optics, a pressure-network flow with the dampers' real losses,
sensors with noise and faults, actuators with motor steps and travel time), driven by
recorded real weather. :class:`~dsfd.sim.plant.plant.Plant` is the entry point;
:class:`~dsfd.sim.plant.config.PlantOptions` switches its fidelity and
:class:`~dsfd.sim.plant.config.TrueParameters` draws its unknown "true" parameters.
"""
