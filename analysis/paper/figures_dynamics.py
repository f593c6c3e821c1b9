"""Figures of the dynamics part of the paper (filled in as the analyses land)."""

FIGURES: list = []
