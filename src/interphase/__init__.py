"""interphase-dem: DEM interface-shear campaigns and the anisotropy-based failure criterion.

Units are SI inside the code (m, N, Pa, s, radians); profile generators take sizes in D50 units.
Angles follow docs/methods.md §0: θ counterclockwise from +x, ψ = θ − 90° (tilt from vertical, positive
toward −x, the shear-resisting side); public outputs name which reading they carry.
"""

__version__ = "0.1.0"
