"""Profile picture: profile, centroid trace, and the polar distribution of trace normals (Fig. 6.6 style)."""

from __future__ import annotations

import math
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from interphase.surface.base import Profile  # noqa: E402
from interphase.surface.normals import keep_mask, segment_normals, theta_a  # noqa: E402
from interphase.surface.trace import centroid_trace  # noqa: E402


def plot_profile(profile: Profile, d50: float, path: str | Path, filt: int = 92, bins: int = 72) -> Path:
    """PNG with (left) profile and centroid trace in mm, (right) the length-weighted polar histogram of
    trace normals (θ ccw from +x, upper half plane), the kept side shaded, θa drawn as an arrow."""
    trace = centroid_trace(profile, d50)
    th, w = segment_normals(trace)
    res = theta_a(profile, d50, filt)
    fig = plt.figure(figsize=(11, 4))
    ax = fig.add_subplot(1, 2, 1)
    ax.plot(profile.x * 1e3, profile.z * 1e3, "k-", lw=1, label="profile")
    ax.plot(trace.x * 1e3, trace.z * 1e3, "C1-", lw=1, label=f"centroid trace (D50 = {d50 * 1e3:g} mm)")
    ax.set_aspect("equal", adjustable="datalim")
    ax.set_xlabel("x [mm] (soil moves +x)")
    ax.set_ylabel("z [mm]")
    ax.legend(loc="upper right", fontsize=8)
    ax.set_title(Path(profile.name).name if profile.name else "profile")
    pax = fig.add_subplot(1, 2, 2, projection="polar")
    edges = np.linspace(0, math.pi, bins + 1)
    hist, _ = np.histogram(th, bins=edges, weights=w)
    hist = hist / max(hist.sum(), 1e-300)
    keep = keep_mask(0.5 * (edges[:-1] + edges[1:]), filt)
    pax.bar(edges[:-1], hist, width=np.diff(edges), align="edge", color=np.where(keep, "C0", "0.75"),
            edgecolor="none")
    pax.set_thetamin(0)
    pax.set_thetamax(180)
    pax.set_yticklabels([])   # relative length shares: the shape matters, not the radial numbers
    if res.dilative:
        ang = math.radians(res.theta_a_ccw_deg)
        pax.annotate("", xy=(ang, hist.max()), xytext=(0, 0), arrowprops=dict(color="C3", width=1.5))
        title = f"θa = {res.theta_a_deg:.2f}° from vertical ({res.theta_a_ccw_deg:.2f}° ccw), filter {filt}"
    else:
        title = f"θa undefined: non-dilative (filter {filt})"
    pax.set_title(title, fontsize=9)
    fig.tight_layout()
    path = Path(path)
    fig.savefig(path, dpi=120)
    plt.close(fig)
    return path
