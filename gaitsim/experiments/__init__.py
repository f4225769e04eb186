"""Experiments: the seed paper's study end to end (``gaitsim reproduce``) and Monte Carlo runs (``gaitsim run``)."""
