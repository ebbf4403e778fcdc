"""Nychka & Bhattacharya: LPV CR3BP, H2 / H-infinity sensing-precision LMIs, observer simulations."""
