"""Optimal control of louver angle, airflow regime and damper opening (Eq. 4–6).

Pure core: the objective, the horizon forecast, the optimiser on the real actuator grid,
the paper's relaxed SQP for comparison and the rule-based baseline. No I/O.
"""
