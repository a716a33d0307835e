"""Estimators (the layout helper owns this package; polynomial estimators live here)."""
