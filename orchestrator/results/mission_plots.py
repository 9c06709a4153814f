"""The PNG plot of a guided vehicle's mission: the route, the true and estimated paths per run
with the GNSS outage drawn thick, and the cross-track error over time (``mission.png``)."""
from __future__ import annotations

import numpy as np
from navcore.vehicles.route_guidance import LocalPlane, parse_route

from . import mission_metrics
from .plot_style import plt, save_png, titled


#: margin around the route and the true paths, as a fraction of their larger extent
FRAME_MARGIN = 0.08


def frame_around(ax, paths):
    """Equal-aspect limits [km] of ``ax`` around ``paths`` (``(north, east)`` arrays [m]: the
    route and the true paths) with :data:`FRAME_MARGIN`, a square frame centred on them: an
    estimated path that drifts far off (a GNSS outage) is cut at the frame instead of
    shrinking the route to a dot."""
    north = np.concatenate([np.asarray(n, float).ravel() for n, _ in paths]) / 1e3
    east = np.concatenate([np.asarray(e, float).ravel() for _, e in paths]) / 1e3
    ok = np.isfinite(north) & np.isfinite(east)
    if not ok.any():
        return
    north, east = north[ok], east[ok]
    centre = ((north.min() + north.max()) / 2, (east.min() + east.max()) / 2)
    half = max(np.ptp(north), np.ptp(east), 1e-3) * (0.5 + FRAME_MARGIN)
    ax.set_xlim(centre[1] - half, centre[1] + half)
    ax.set_ylim(centre[0] - half, centre[0] + half)
    ax.set_aspect("equal", adjustable="box")


def plot_mission(entries, vehicle, path, title=""):
    """A guided vehicle's flight per run: the route (the vehicle's ``route`` parameter, when
    the run recorded it, on the plane of its ``origin_lat``/``origin_lon``), the true path
    and the filter's estimated path of each entry, the GNSS outage (no valid fix) drawn
    thick, and the cross-track error over time with the outage shaded.  ``entries``: (label,
    results, filter component) per run."""
    first = entries[0][1]
    params = ((first.metadata or {}).get("parameters") or {}).get(vehicle) or {}
    lat0 = params.get("origin_lat", first.column(vehicle, "truth_lat")[0])
    lon0 = params.get("origin_lon", first.column(vehicle, "truth_lon")[0])
    route = parse_route(params["route"]) if "route" in params else None
    plane = LocalPlane(lat0, lon0, route[0][2] if route else first.column(vehicle, "truth_h")[0])
    fig, (ax, ax_t) = plt.subplots(1, 2, figsize=(14, 6.5))
    framed = [] if not route else [([w[0] for w in route], [w[1] for w in route])]
    if route:
        ax.plot([w[1] / 1e3 for w in route], [w[0] / 1e3 for w in route], "k--", lw=1,
                label="route")
    for i, (label, results, f) in enumerate(entries):
        color = f"C{i}"
        north, east = plane.to_plane(results.column(vehicle, "truth_lat"),
                                     results.column(vehicle, "truth_lon"))
        outage = mission_metrics.outage_rows(results)
        framed.append((north, east))
        ax.plot(east / 1e3, north / 1e3, color=color, lw=0.9, label=f"{label}: true path")
        ax.plot(np.where(outage, east, np.nan) / 1e3, np.where(outage, north, np.nan) / 1e3,
                color=color, lw=3.0, alpha=0.5)
        n_est, e_est = plane.to_plane(results.column(f, "nav_lat"), results.column(f, "nav_lon"))
        ax.plot(e_est / 1e3, n_est / 1e3, color=color, lw=0.6, ls=":",
                label=f"{label}: estimated path")
        ax_t.plot(results.time, results.column(vehicle, "cross_track"), color=color, lw=0.8,
                  label=label)
    t, outage = first.time, mission_metrics.outage_rows(first)
    if outage.any():
        ax_t.axvspan(t[outage][0], t[outage][-1], color="0.85", label="GNSS outage")
    ax.set_xlabel("east [km]")
    ax.set_ylabel("north [km]")
    frame_around(ax, framed)
    ax.legend(fontsize=7)
    ax.grid(True, alpha=0.3)
    ax.set_title("route, true and estimated paths (thick: GNSS outage; an estimate beyond "
                 "the frame is cut off)", fontsize=9)
    ax_t.set_xlabel("time [s]")
    ax_t.set_ylabel("cross-track error of the true path [m]")
    ax_t.legend(fontsize=7)
    ax_t.grid(True, alpha=0.3)
    fig.suptitle(titled("mission", title))
    fig.tight_layout()
    return save_png(fig, path)
