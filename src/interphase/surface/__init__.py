"""Surface toolkit: profiles (generated and measured), centroid trace, surface normals (θa),
roughness (Rn, Rnc) and STL export. Imports nothing from engines, campaign, report or cli.

Layers, each importing only those below it (tests/test_surface_layers.py holds it):
  units, base       the units table and its one check; the plain types Profile and Scan
  filters, lines    pure filters of a Profile (centerline, resampling, Gaussian); a Scan's lines
  profiles          generated profiles and their geometry (crop, tile, close)
  trace, roughness, normals, areal, mesh, plot
                    the centroid trace, Rn/Rnc, θa of a line and of an areal scan, STL, figures
  patch             an areal scan's window closed on itself (the 3D cell's surface) and its θa
  readers           every file format (SurfaceTopography's instrument files, two-column text)
  spec              ProfileSpec: plain data, reads nothing
  builder           user input → spec (a file hashed) and spec → Profile: the one builder
"""
