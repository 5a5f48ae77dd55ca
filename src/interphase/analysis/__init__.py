"""Analysis of ContactTable/History: anisotropy, stress, strength, correlations, criterion.
Pure numpy/pandas; imports nothing from engines, campaign, report or cli."""
