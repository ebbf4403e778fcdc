"""Greaves & Scheeres (JAS 2021): optical NRHO tracking, the SRI OCBE, adaptive tuning, maneuver detection."""
