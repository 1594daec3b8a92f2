"""Frequency-space analysis: rho_lpq, order choice, lighting coefficients, SHRM prefiltering
and the angular-domain reference (DESIGN §4–6)."""
