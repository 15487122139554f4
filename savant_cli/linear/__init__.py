"""Frequency-domain stability analysis at trajectory time points (``study=linear``)."""
