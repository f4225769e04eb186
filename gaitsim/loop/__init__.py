"""The sim-to-real loop (``gaitsim loop DATASET --out DIR``): a recording's strides (strides), its stride-normalised
signature (signature), the digital twin fitted to it (twin, with its gait shape in gait_fit and sensor position
in mount_fit), the residuals between the two (residuals), a library of effects the twin may lack (effects), their
attribution (attribution), the held-out prediction across recordings (transfer), blind tests (blind), the report (report) and the command (command); every tuning
constant is in settings."""
