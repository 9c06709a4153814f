"""The textbook linear Kalman filter that the unscented and IMM tests use as their reference
(on a linear-Gaussian model the UKF and an IMM bank of UKFs must reproduce it)."""
import numpy as np


class LinearKalmanFilter:
    """x, P with predict(F, Q) and a Joseph-form update(z, H, R) -> (v, S, NIS)."""

    def __init__(self, x0, P0):
        self.x = np.array(x0, dtype=float)
        self.P = np.array(P0, dtype=float)

    def predict(self, F, Q):
        self.x = F @ self.x
        self.P = F @ self.P @ F.T + Q

    def update(self, z, H, R):
        v = z - H @ self.x
        S = H @ self.P @ H.T + R
        K = self.P @ H.T @ np.linalg.inv(S)
        self.x = self.x + K @ v
        I_KH = np.eye(len(self.x)) - K @ H
        self.P = I_KH @ self.P @ I_KH.T + K @ R @ K.T       # Joseph form
        return v, S, float(v @ np.linalg.solve(S, v))
