"""Neural-network initial guesses for forward kinematics (Zhao et al. 2017, §1.1, Fig. 3).

:class:`BPNetwork` (numpy only) predicts; :func:`train_lm` (needs torch) trains it by
Levenberg-Marquardt as MATLAB's ``trainlm``; :func:`load_network` reads a saved network or the one
that ships with parakin (:mod:`parakin.nn.packaged`).
"""

from parakin.nn import bp
from parakin.nn.bp import *  # noqa: F403  (the names of bp.__all__, declared there once)
from parakin.nn.packaged import load_network, packaged_network_path

__all__ = [*bp.__all__, "load_network", "packaged_network_path"]
