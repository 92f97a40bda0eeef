"""Simulation at the edge: the truth plant (:mod:`dsfd.sim.plant`), replay of real weather
at a panel's site, open-loop and closed-loop runs, the paper's excitation protocol, and the
simulated plant that ``dsfd run --plant sim`` drives."""
