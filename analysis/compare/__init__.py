"""Comparators: Cabral et al. 1999 RSIBR, Kautz & McCool 2000, Green et al. 2007 Gaussian lobes."""
