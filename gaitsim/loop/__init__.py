"""The sim-to-real loop: residuals between a recording and its simulated twin, a library of effects the
twin may lack, their attribution, and the before/after report (``gaitsim loop DATASET --out DIR``)."""
