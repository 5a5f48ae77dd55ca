"""Surface profiles z(x): the study's generated groups and the geometry of profiles (crop, tile,
close into a periodic cell). Pure functions: no file is read (surface/readers.py), no spec is
interpreted (surface/builder.py).

A Profile (surface/base.py) is a polyline in metres. Generated profiles (docs/methods.md §1) take
sizes in D50 units and return their exact corner vertices, so nothing is lost before the centroid
trace resamples them. Periodic convention: a periodic profile stores one closing vertex,
z[-1] == z[0], and its period is x[-1] − x[0]; z(x + period) = z(x).
"""

from __future__ import annotations

import math

import numpy as np

from interphase.errors import InputError
from interphase.surface.base import Profile

__all__ = ["Profile", "asymmetric_sawtooth", "close", "crop", "flat", "random_profile", "sawtooth", "selfaffine_profile",
           "tile"]


def flat(length: float, name: str = "flat") -> Profile:
    """A flat surface of `length` m at z = 0 (periodic: any period)."""
    return Profile(np.array([0.0, length]), np.zeros(2), periodic=True, name=name)


def sawtooth(rt: float, sw: float, sr: float = 0.0, *, d50: float, length: float | None = None,
             periods: int | None = None, name: str | None = None) -> Profile:
    """Groups 1–3: symmetric triangles of height `rt`, base `sw`, flat `sr` between them (D50 units).

    Valleys at z = 0; one period is rise (sw/2), fall (sw/2), flat (sr). The profile holds a whole
    number of periods covering at least `length` m (or exactly `periods`). Slope α = atan(2·rt/sw).
    """
    if rt <= 0 or sw <= 0 or sr < 0:
        raise InputError(f"need rt > 0, sw > 0, sr ≥ 0 (D50 units), got rt={rt}, sw={sw}, sr={sr}", where="sawtooth")
    lam = (sw + sr) * d50
    if periods is None:
        if length is None:
            raise InputError("give length or periods", where="sawtooth")
        periods = max(1, math.ceil(length / lam - 1e-9))
    spaced = sr > 1e-9 * sw      # a spacing below a nanometre-per-metre of the base is no spacing
    one_x = np.array([0.0, sw / 2, sw] + ([sw + sr] if spaced else [])) * d50
    one_z = np.array([0.0, rt, 0.0] + ([0.0] if spaced else [])) * d50
    k = np.arange(periods)[:, None] * lam
    x = np.concatenate([(one_x[:-1] + k).ravel(), [periods * lam]])
    z = np.concatenate([np.tile(one_z[:-1], periods), [0.0]])
    return Profile(x, z, periodic=True, name=name or f"sawtooth-rt{rt:g}-sw{sw:g}-sr{sr:g}")


def asymmetric_sawtooth(rt: float, rise: float, fall: float, sr: float = 0.0, *, d50: float,
                        length: float | None = None, periods: int | None = None, name: str | None = None) -> Profile:
    """Triangles of height `rt` rising over `rise` and falling over `fall`, flat `sr` between them (D50
    units): soil moving toward +x climbs the rising flank, at atan(rt/rise), and leaves over the falling
    one, at atan(rt/fall); sheared the other way the two swap (rise ↔ fall). rise = fall = sw/2 is
    `sawtooth`. Valleys at z = 0; a whole number of periods covering at least `length` m (or `periods`)."""
    if rt <= 0 or rise <= 0 or fall <= 0 or sr < 0:
        raise InputError(f"need rt, rise, fall > 0 and sr ≥ 0 (D50 units), got rt={rt}, rise={rise}, fall={fall}, "
                         f"sr={sr}", where="asymmetric sawtooth")
    lam = (rise + fall + sr) * d50
    if periods is None:
        if length is None:
            raise InputError("give length or periods", where="asymmetric sawtooth")
        periods = max(1, math.ceil(length / lam - 1e-9))
    spaced = sr > 1e-9 * (rise + fall)
    one_x = np.array([0.0, rise, rise + fall] + ([rise + fall + sr] if spaced else [])) * d50
    one_z = np.array([0.0, rt, 0.0] + ([0.0] if spaced else [])) * d50
    k = np.arange(periods)[:, None] * lam
    x = np.concatenate([(one_x[:-1] + k).ravel(), [periods * lam]])
    z = np.concatenate([np.tile(one_z[:-1], periods), [0.0]])
    return Profile(x, z, periodic=True, name=name or f"asym-rt{rt:g}-up{rise:g}-down{fall:g}-sr{sr:g}")


def random_profile(au: float, ar: float, rtmax: float, *, d50: float, length: float, seed: int,
                   name: str | None = None) -> Profile:
    """Group 4: a random walk of straight segments (sizes in D50 units), a pure function of its args.

    Project's law (the study leaves it open; docs/methods.md):
      - segment i has horizontal projection au·m_i and slope ar·k_i (so vertical projection
        ar·au·m_i·k_i), the multipliers m_i, k_i drawn independently from Uniform(0.5, 1.5) (mean 1:
        au and ar stay the mean projection and the mean slope);
      - sign rule: each segment goes up or down with probability ½;
      - bound rule: the running height stays in [0, rtmax]: a step that would leave the band is
        reflected (its sign flipped); if the reflected step leaves it too, the segment runs at its
        own slope to the farther bound and ends there (shorter than au·m_i). The slope is kept, so
        profiles whose steps all overshoot the band (Table 6.2's D and G) still differ by their Ar.
        The walk starts at rtmax/2.
      - the draws come three per segment in segment order (numpy PCG64 seeded by `seed`), so a
        longer profile extends a shorter one of the same seed: the profile an engine shears and
        the one the analysis measures are the same surface whatever length each asks for.
    """
    if au <= 0 or ar <= 0 or rtmax <= 0:
        raise InputError(f"need au, ar, rtmax > 0 (D50 units), got {au}, {ar}, {rtmax}", where="random profile")
    rng = np.random.default_rng(int(seed))
    target = length / d50
    xs, zs = [0.0], [rtmax / 2]
    # the bound rule is sequential (each step depends on the height so far); a few hundred segments
    while xs[-1] < target:
        for u_m, u_k, u_s in rng.random((256, 3)):
            h, slope = au * (0.5 + u_m), ar * (0.5 + u_k)
            dz = slope * h * (-1.0 if u_s < 0.5 else 1.0)
            z = zs[-1]
            if 0.0 <= z + dz <= rtmax:
                z_new = z + dz
            elif 0.0 <= z - dz <= rtmax:
                z_new = z - dz
            else:
                z_new = 0.0 if z > rtmax / 2 else rtmax
                h = abs(z_new - z) / slope
            xs.append(xs[-1] + h)
            zs.append(z_new)
            if xs[-1] >= target:
                break
    return Profile(np.array(xs) * d50, np.array(zs) * d50, periodic=False,
                   name=name or f"random-au{au:g}-ar{ar:g}-rtmax{rtmax:g}-seed{seed}")


def selfaffine_profile(hurst: float, rms_slope: float, long_cutoff: float, short_cutoff: float, length: float,
                       seed: int, *, d50: float, name: str | None = None) -> Profile:
    """A periodic self-affine line (sizes in D50 units, one period of `length`), synthesised by
    SurfaceTopography's Fourier filtering of random noise (fourier_synthesis): PSD C(q) ∝ q^(−1−2H)
    between the roll-off wavelength `long_cutoff` (flat below it) and `short_cutoff` (zero above
    it), scaled to the rms slope (dimensionless, so the same in any length unit); random phases and
    amplitudes from numpy's PCG64 seeded by `seed`. Grid: short_cutoff/8, so that the shortest
    wavelength has 8 points. A pure function of its args for a given SurfaceTopography version."""
    import contextlib
    import io
    import warnings

    if not (0 < hurst < 1 and rms_slope > 0 and 0 < short_cutoff < long_cutoff <= length):
        raise InputError(f"need 0 < hurst < 1, rms_slope > 0, 0 < short_cutoff < long_cutoff ≤ length (D50 units), "
                         f"got {hurst}, {rms_slope}, {short_cutoff}, {long_cutoff}, {length}", where="selfaffine profile")
    with warnings.catch_warnings(), contextlib.redirect_stdout(io.StringIO()):
        warnings.simplefilter("ignore")
        from SurfaceTopography.Generation import fourier_synthesis

        n = int(math.ceil(length / (short_cutoff / 8)))
        topo = fourier_synthesis((n,), (length,), hurst=hurst, rms_slope=rms_slope, short_cutoff=short_cutoff,
                                 long_cutoff=long_cutoff, rng=int(seed))
        z = np.asarray(topo.heights(), float)
    x = np.arange(n + 1) * (length / n)
    return Profile(x * d50, np.append(z, z[0]) * d50, periodic=True,
                   name=name or f"selfaffine-H{hurst:g}-s{rms_slope:g}-L{long_cutoff:g}-l{short_cutoff:g}-seed{seed}")


def crop(profile: Profile, x0: float, x1: float) -> Profile:
    """The part of a profile over [x0, x1] [m], end points interpolated (an open profile)."""
    inside = (profile.x > x0) & (profile.x < x1)
    x = np.concatenate([[x0], profile.x[inside], [x1]])
    z = np.interp(x, profile.x, profile.z)
    return Profile(x, z, periodic=False, name=profile.name)


def tile(profile: Profile, length: float) -> Profile:
    """Repeat a profile until it covers `length` m from x = 0.

    Periodic profiles repeat seamlessly. A measured (open) profile is repeated as it is, each copy
    joined to the next by one straight segment of one sample step: the direction of every face (and
    so θa) is kept, which mirroring copies would not do; the seam adds one short segment per copy.
    """
    x = profile.x - profile.x[0]
    z = profile.z
    if x[-1] >= length:
        return Profile(x, z, profile.periodic, profile.name)
    if profile.periodic:
        period, body_x, body_z = x[-1], x[:-1], z[:-1]
    else:
        step = float(np.median(np.diff(x)))
        period, body_x, body_z = x[-1] + step, x, z
    copies = math.ceil(length / period - 1e-12) + (0 if profile.periodic else 1)
    xs = (body_x[None, :] + period * np.arange(copies)[:, None]).ravel()
    zs = np.tile(body_z, copies)
    if profile.periodic:
        xs, zs = np.append(xs, copies * period), np.append(zs, body_z[0])
    return Profile(xs, zs, profile.periodic, profile.name)


def close(profile: Profile, length: float, min_face: float = 0.0) -> Profile:
    """An open profile made periodic over about `length` m [m]: cut between two crossings of its
    mean height (length-weighted), the first crossing and the one nearest `length` after it (at
    least length/2, at most 2·length after it), both ends at that height, x from 0. Nothing is
    stretched or levelled, so every face keeps its direction (and θa is that of the kept part); the
    joint adds one kink, as any vertex does. The mean height, not the first point's, so that an
    edge step or an outlier at the start of a measured line cannot leave it unclosable. A vertex
    nearer than `min_face` [m] to a cut is left out, so that no face at a cut is a sliver (a cut
    0.15 µm from a sample of a measured line made a face LIGGGHTS refuses to mesh). Raises
    InputError when the profile does not cross its mean height again in that range."""
    x, z = profile.x - profile.x[0], profile.z
    level = float(np.sum(0.5 * (z[1:] + z[:-1]) * np.diff(x)) / x[-1])
    s = z - level
    i = np.flatnonzero(s[:-1] * s[1:] < 0)                       # strict crossings inside a segment
    at = np.sort(np.concatenate([x[i] - s[i] * (x[i + 1] - x[i]) / (s[i + 1] - s[i]), x[s == 0]]))
    start = float(at[0]) if at.size else math.nan
    cand = at[(at >= start + 0.5 * length) & (at <= start + 2 * length)]
    if cand.size == 0:
        raise InputError(f"the profile does not cross its mean height twice about {length * 1e3:.4g} mm apart "
                         f"({x[-1] * 1e3:.4g} mm searched), so it cannot close into a periodic cell",
                         where=profile.name or "profile", fix="use device = 'walled' for this surface")
    end = float(cand[np.argmin(np.abs(cand - start - length))])
    inside = (x > start * (1 + 1e-12) + 1e-15) & (x < end * (1 - 1e-12))
    xi, zi = x[inside], z[inside]
    keep = (np.hypot(xi - start, zi - level) >= min_face) & (np.hypot(end - xi, zi - level) >= min_face)
    xs = np.concatenate([[start], xi[keep], [end]]) - start
    zs = np.concatenate([[level], zi[keep], [level]])
    return Profile(xs, zs, periodic=True, name=profile.name)
