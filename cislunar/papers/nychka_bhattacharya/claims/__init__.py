"""Declared claims of Nychka & Bhattacharya (one module per notebook), fixed before comparing."""
