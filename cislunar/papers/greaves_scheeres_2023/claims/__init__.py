"""Declared claims of Greaves & Scheeres (AMOS 2023), one module per chapter: :mod:`.ssat_guidance` (notebook 07)
and :mod:`.informed_station_keeping` (notebook 08)."""
