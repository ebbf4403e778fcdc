"""Greaves & Scheeres (AMOS 2023): SSAT, MMD guidance and informed station keeping on a QPO of the 9:2 NRHO."""
