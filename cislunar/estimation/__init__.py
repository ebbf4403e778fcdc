"""Estimation: SRIF, the OCBE (single and batched), adaptive OCBE, NEES consistency, LPV models and observers."""
