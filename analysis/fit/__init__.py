"""Fitting analytic models to measured BRDFs with nlopt."""
