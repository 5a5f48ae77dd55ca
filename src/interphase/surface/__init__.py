"""Surface toolkit: profiles (generated and measured), centroid trace, surface normals (θa),
roughness (Rn, Rnc) and STL export. Imports nothing from engines, campaign, report or cli."""
