"""Figures of the ensembles part of the paper (filled in as the analyses land)."""

FIGURES: list = []
