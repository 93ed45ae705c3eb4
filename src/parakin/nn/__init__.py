"""Neural-network initial guesses for forward kinematics (Zhao et al. 2017, §1.1, Fig. 3).

:class:`BPNetwork` (numpy only) predicts; :func:`train_lm` (needs torch) trains it by
Levenberg-Marquardt as MATLAB's ``trainlm``.
"""

from parakin.nn.bp import BPNetwork, residual_jacobian, residuals, torch_forward, train_lm

__all__ = ["BPNetwork", "train_lm", "torch_forward", "residuals", "residual_jacobian"]
