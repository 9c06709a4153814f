"""The Rauch-Tung-Striebel smoother (navcore.filters.rts_smoother, navfmu run --smooth).

The backward pass against filterpy's independent ``rts_smoother`` on a linear model (the
closed-loop form with the corrections against the textbook form on the states; with a
velocity pseudo-measurement after some fixes, at their epoch, as a land aid's), and the
smoother over a simulated MEMS INS/GNSS run with a 10 s GNSS outage: the smoothed position
error inside the outage far below the forward filter's, the last epoch unchanged; the
recording through a rollback for late fixes; a filter the smoother does not support refused
in one error line.
"""
from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from filterpy.kalman import rts_smoother

from navcore.components.smoothing import SmoothingSession
from navcore.filters.land_aids import linear_update
from navcore.filters.rts_smoother import backward
from orchestrator.cli.commands import main
from orchestrator.results import metrics as nav_metrics
from orchestrator.running import scenarios, smoothing

ROOT = Path(__file__).resolve().parents[1]


def _linear_run(seed, n=60, gap=(20, 35), aid_sigma=None):
    """A forward Kalman filter on a 1-D constant-velocity model with a varying step and no
    position measurement inside ``gap``: (F, Q, x_prior, P_prior, x_post, P_post).  With
    ``aid_sigma``, a velocity pseudo-measurement every third epoch besides, after the
    position at the same epoch (a land aid beside a fix: two updates merged into one)."""
    rng = np.random.default_rng(seed)
    dts = rng.uniform(0.5, 1.5, n)
    F = np.array([[[1.0, dt], [0.0, 1.0]] for dt in dts])
    Q = np.array([0.05 * np.array([[dt ** 3 / 3, dt ** 2 / 2], [dt ** 2 / 2, dt]]) for dt in dts])
    H, R = np.array([[1.0, 0.0]]), np.array([[0.5]])
    truth = np.array([0.0, 1.0])
    x, P = np.array([0.3, 0.5]), np.diag([1.0, 1.0])
    xs_pr, Ps_pr, xs_po, Ps_po = [x], [P], [x], [P]
    for k in range(1, n):
        truth = F[k] @ truth + rng.multivariate_normal(np.zeros(2), Q[k])
        x, P = F[k] @ x, F[k] @ P @ F[k].T + Q[k]
        xs_pr.append(x)
        Ps_pr.append(P)
        if not gap[0] <= k < gap[1]:
            z = H @ truth + rng.normal(0.0, np.sqrt(R[0, 0]), 1)
            S = H @ P @ H.T + R
            K = P @ H.T @ np.linalg.inv(S)
            x = x + K @ (z - H @ x)
            P = (np.eye(2) - K @ H) @ P
        if aid_sigma is not None and k % 3 == 0:
            x, P = linear_update(x, P, truth[1:] + rng.normal(0.0, aid_sigma, 1),
                                 np.array([[0.0, 1.0]]), np.array([[aid_sigma ** 2]]))
        xs_po.append(x)
        Ps_po.append(P)
    return F, Q, *(np.array(a) for a in (xs_pr, Ps_pr, xs_po, Ps_po))


@pytest.mark.parametrize("seed, aid_sigma", [(1, None), (2, None), (3, 0.2)])
def test_backward_pass_matches_filterpy_rts_smoother(seed, aid_sigma):
    F, Q, x_pr, P_pr, x_po, P_po = _linear_run(seed, aid_sigma=aid_sigma)
    # filterpy's Fs[k], Qs[k] take epoch k to k+1 (the last pair unused)
    ref_x, ref_P, _, _ = rts_smoother(x_po.copy(), P_po.copy(), np.roll(F, -1, axis=0),
                                      np.roll(Q, -1, axis=0))
    # closed loop: the nominal is the posterior, the correction applied at an epoch is
    # prior - posterior (error = computed - true, removed by subtraction)
    ds, diag, Ps0 = backward(F[1:], P_pr[1:], P_po[:-1], x_pr[1:] - x_po[1:], np.zeros(2),
                             P_po[-1])
    smoothed = x_po[:-1] - ds
    np.testing.assert_allclose(smoothed, ref_x[:-1], rtol=0, atol=1e-10)
    np.testing.assert_allclose(diag, np.diagonal(ref_P[:-1], axis1=1, axis2=2), rtol=1e-9)
    np.testing.assert_allclose(Ps0, ref_P[0], rtol=1e-9)
    # the smoother changed the states (a test that could not fail otherwise)
    assert np.max(np.abs(ds[20:35, 0])) > 0.1


#: a simulated MEMS run with a 20 s outage at 100-120 s, GNSS errors white (no correlated
#: or bias part) and the IMU errors the filter models (no scale factor or misalignment)
SIMULATED = {"gnss.outages": "100,120", **{f"gnss.{q}_{a}": 0.0 for q in (
    "pos_gm_sigma", "pos_bias_sigma", "vel_gm_sigma") for a in "ned"},
    **{f"trajectory.{q}": 0.0 for q in ("gyro_scale_factor_ppm", "gyro_misalignment_urad",
                                        "g_sensitivity_dphpg", "accel_scale_factor_ppm",
                                        "accel_misalignment_urad")}}


def _outage_errors(run):
    e = nav_metrics.navigation_errors(run.results, scenarios.FILTER_COMPONENT)
    inside = e["valid"] & (e["time"] > 100.0) & (e["time"] <= 120.0)
    return np.sqrt(np.mean(e["pos_n"][inside] ** 2 + e["pos_e"][inside] ** 2)), e


def test_smoothed_error_in_an_outage_is_far_below_the_forward_filter():
    """One recording run (its rows are the forward filter's) and its smoothed solution laid
    on them, as :func:`orchestrator.running.smoothing.smoothed_run` does."""
    model = scenarios.load_scenario(ROOT / "models" / "mems_outages")
    session = SmoothingSession("Kf")
    forward = scenarios.simulate_scenario(
        model, filter="Kf", stop_time=130.0, parameters=SIMULATED, log=None, backend="direct",
        components={"Kf": session.component_class})
    solution = session.solution()
    smoothed = scenarios.measured_run("Kf-smoothed", model,
                                      smoothing.smoothed_results(forward.results, solution))
    rms_forward, e_f = _outage_errors(forward)
    rms_smoothed, e_s = _outage_errors(smoothed)
    # measured: 1.32 m forward, 0.28 m smoothed (the fixes' white 0.5 m noise averaged)
    assert rms_forward > 1.0
    assert rms_smoothed < 0.3 * rms_forward, (rms_smoothed, rms_forward)
    # at the last epoch the smoothed solution is the filtered one
    assert e_s["pos_n"][-1] == pytest.approx(e_f["pos_n"][-1], abs=1e-9)
    # the recording: 6500 epochs of 20 floats and 131 updates of 262 (the tables grown by
    # doubling from 1024 rows)
    assert solution["recording_bytes"] == 8 * (8192 * 20 + 1024 * 262)


def test_a_filter_the_smoother_does_not_support_is_refused(capsys, tmp_path):
    with pytest.raises(SystemExit) as exc:
        main(["run", str(ROOT / "models" / "mems_outages"), "--filter", "Ukf", "--smooth",
              "--backend", "direct", "--stop", "1", "--no-plots", "--out", str(tmp_path / "o")])
    out, err = capsys.readouterr()
    assert exc.value.code != 0
    assert "Traceback" not in err + out
    first = err.strip().splitlines()[0]
    assert first.startswith("navfmu: error:") and "Ukf" in first and "Kf" in first
    assert not (tmp_path / "o").exists()


def test_the_recording_follows_a_rollback_for_late_fixes():
    """Fixes delivered 0.3 s after their time make the filter roll back and integrate again
    (navcore.filters.latency): the recording keeps one epoch per IMU interval, in time
    order, and one update per fix at the epoch of its time."""
    from walk_inputs import LAT, walk_fix

    session = SmoothingSession("Kf")
    f = session.component_class(init_lat=LAT, init_h=100.0, init_vn=1.08, init_ve=1.44)
    f.start(0.0)
    dt, g = 0.1, 9.80665
    for k in range(100):
        late = walk_fix(k - 3, dt) if k >= 3 else {**walk_fix(k, dt), "gnss_valid": False,
                                                    "gnss_epoch": 0}
        f.advance(k * dt, dt, {"imu_time": (k + 1) * dt, "imu_dt": dt, "imu_dtheta_x": 0.0,
                               "imu_dtheta_y": 0.0, "imu_dtheta_z": 0.0, "imu_dvel_x": 0.0,
                               "imu_dvel_y": 0.0, "imu_dvel_z": -g * dt, **late})
    assert f.late_fixes                                   # the filter did roll back
    rec = f.recording
    t = rec.epochs.rows[:, 0]
    np.testing.assert_allclose(t, np.arange(101) * dt, atol=1e-9)
    epochs = rec.updates.rows[:, 0].astype(int)
    assert epochs[0] == 0 and np.all(np.diff(epochs) > 0)
    np.testing.assert_allclose(t[epochs[1:]], np.arange(1, len(epochs)), atol=1e-9)
    assert len(epochs) - 1 == 9                           # fixes at 1..9 s delivered by 9.9 s
    out = session.solution()
    assert len(out["time"]) == 101 and np.all(np.isfinite(out["lat"]))
