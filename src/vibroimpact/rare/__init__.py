"""Rare events of the oscillator on the exact simulator (numerics only: no files, no workflow).

- :mod:`~vibroimpact.rare.forcing`: the random force as a filter with a state to clone;
- :mod:`~vibroimpact.rare.paths`: paths stopped at any sample, copied and continued exactly;
- :mod:`~vibroimpact.rare.coordinates`: reaction coordinates (the predicted envelope for a
  smooth force) and start sets;
- :mod:`~vibroimpact.rare.ams`: adaptive multilevel splitting (unbiased form) and the mean
  first-passage time by renewal;
- :mod:`~vibroimpact.rare.reference`: Rice's and Vanmarcke's rates from the actual spectrum;
- :mod:`~vibroimpact.rare.motions`: the residence of a periodic impact motion (the oscillator
  with its wall and harmonic force; A and B read once per forcing period).
"""
from vibroimpact.rare.ams import FirstPassage, SplittingRun, ams, first_passage
from vibroimpact.rare.coordinates import Displacement, Energy, EnergyBelow, Predicted
from vibroimpact.rare.forcing import ForceFilter, ForceState
from vibroimpact.rare.motions import (MotionDynamics, PeriodicMotion, PredictedDeviation,
                                      Residence, StrobeDistance, brute_force_residence,
                                      residence_time)
from vibroimpact.rare.paths import Dynamics, Path, PathState
from vibroimpact.rare.reference import (bandwidth, response_moments, rice_rate,
                                        vanmarcke_rate)

__all__ = ["FirstPassage", "SplittingRun", "ams", "first_passage", "Displacement", "Energy",
           "EnergyBelow", "Predicted", "ForceFilter", "ForceState", "Dynamics", "Path",
           "PathState", "bandwidth", "response_moments", "rice_rate", "vanmarcke_rate",
           "MotionDynamics", "PeriodicMotion", "PredictedDeviation", "Residence",
           "StrobeDistance", "brute_force_residence", "residence_time"]
