"""DEM engines behind one contract (interphase.engines.base); imports no campaign code."""
