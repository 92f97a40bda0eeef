"""The lumped double-skin façade model: pure numpy over arrays, SI units, no I/O.

solar geometry and sky models (:mod:`~dsfd.physics.solar`), optics of glass and louver,
long-wave exchange, airflow laws and the damper network, the exact zero-order-hold step
and the implicit thermal–airflow coupling, and the model itself
(:class:`~dsfd.physics.model.LumpedModel`). Documented in ``docs/model.md``.
"""
