"""Sensing: observer sites, measurement models, covariance recursions and mutual information."""
