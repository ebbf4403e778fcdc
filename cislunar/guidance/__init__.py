"""Guidance: first-order-hold discretisation, successive convexification, SSAT and MMD guidance."""
