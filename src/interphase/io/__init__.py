"""Readers of each engine's files into ContactTable / History (see interphase.tables).
Usable with no runner; imports nothing from engines, campaign, report or cli."""
