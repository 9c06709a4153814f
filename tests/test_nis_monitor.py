"""navcore.filters.nis_monitor: silent on a consistent filter's chi-square NIS, one warning when
most updates of a window are above their band; the warning through the filter shell."""
import numpy as np

from navcore.components import kf_components
from navcore.filters.nis_monitor import MIN_UPDATES, NisMonitor


def test_consistent_chi_square_nis_never_warns():
    rng = np.random.default_rng(7)
    for dof in (3, 6):
        monitor = NisMonitor(60.0)
        nis = rng.chisquare(dof, 20000)
        assert all(monitor.observe(float(k), x, dof) is None for k, x in enumerate(nis))


def test_nis_four_times_its_dof_warns_once_after_a_window():
    rng = np.random.default_rng(8)
    monitor = NisMonitor(30.0)
    messages = [(k, monitor.observe(float(k), 4.0 * x, 6))
                for k, x in enumerate(rng.chisquare(6, 200))]
    warned = [(k, m) for k, m in messages if m]
    assert len(warned) == 1
    k, text = warned[0]
    assert 30 <= k <= 35 and "\n" not in text and "chi-square band" in text


def test_a_single_huge_nis_and_a_thin_window_do_not_warn():
    monitor = NisMonitor(60.0)
    assert all(monitor.observe(float(k), 1e6 if k == 70 else 2.0, 3) is None
               for k in range(200))
    sparse = NisMonitor(60.0)       # fewer than MIN_UPDATES updates per window
    step = 60.0 / (MIN_UPDATES - 1)
    assert all(sparse.observe(k * step, 1e6, 3) is None for k in range(50))


def test_zero_window_switches_the_warning_off():
    monitor = NisMonitor(0.0)
    assert all(monitor.observe(float(k), 1e9, 3) is None for k in range(500))


def test_the_filter_shell_notifies_the_warning_once():
    """A Kf told its GNSS is 100 times better than it is: its NIS stays far above the band."""
    lat, h = 0.7, 100.0
    f = kf_components.Kf(init_lat=lat, init_h=h, r_pos_n=0.01, r_pos_e=0.01, r_pos_d=0.01,
                         measurement="position", nis_warning_s=20.0)
    f.start(0.0)
    rng = np.random.default_rng(3)
    notices = []
    for k in range(1, 6001):
        inputs = {p.name: 0.0 for p in f.inputs}
        inputs.update(imu_time=k * 0.01, imu_dt=0.01, imu_dvel_z=-9.80 * 0.01)
        if k % 100 == 0:           # a 1 Hz fix with 1 m of noise
            inputs.update(gnss_time=k * 0.01, gnss_lat=lat + rng.normal() / 6.4e6,
                          gnss_lon=0.0, gnss_h=h + rng.normal(), gnss_valid=True,
                          gnss_epoch=k // 100)
        else:
            inputs.update(gnss_epoch=(k // 100))
        f.advance((k - 1) * 0.01, 0.01, inputs)
        notices += f.take_notices()
    warned = [n for n in notices if "chi-square band" in n]
    assert len(warned) == 1 and warned[0].startswith("Kf: at t = "), notices
