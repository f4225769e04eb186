"""Adapters between the project's recordings and solutions and other tools' conventions.

- :mod:`gaitsim.interop.gaitmap`: pandas DataFrames as mad-lab-fau/gaitmap uses them (deg/s, its foot sensor
  frame) and its trajectory results as solution files (needs pandas: ``pip install 'gaitsim[interop]'``).
- :mod:`gaitsim.interop.pyshoe`: MATLAB ``.mat`` files in utiasSTARS/pyshoe's layout (``imu`` N x 6, ``ts``,
  ``gt``), in and out (scipy only).
"""
