"""dsfd — on-line self-calibrating model-predictive control of double-skin façade panels."""

__version__ = "0.1.0"
