"""Forced oscillators coupled to hysteresis operators: q'' + 2ζq' + q = cos(Ωt) + C·M[q](t)."""
