"""Estimators and their checks, batched over many problems at once.

:mod:`.map_gauss_newton` (batch MAP localization from ranges, Garcia et al. 2019 eqs. 10-22, with
Levenberg-Marquardt step control), :mod:`.kalman` and :mod:`.unscented` (KF, EKF and UKF as pure
predict/update steps on :class:`.gaussian.Gaussian` batches), :mod:`.tracking` (a filter run over a flock's
measurement sequence), :mod:`.bounds` (HDOP and the posterior Cramer-Rao bound), :mod:`.consistency` (NEES,
chi-square checks, confidence ellipses), :mod:`.range_logs` and :mod:`.noise` (beacons and range noise from
GPS + USBL logs), :mod:`.gnssa` (GNSS-Acoustic transponder positioning) and :mod:`.time_delay`
(cross-correlation and GCC-PHAT).
"""
